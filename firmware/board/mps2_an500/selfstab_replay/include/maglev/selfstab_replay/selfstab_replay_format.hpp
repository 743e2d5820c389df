// The vectors and outputs of the selfstab kernel's bit-exact replay (paper
// 001): written by the host recorder (tests/target/bitexact,
// selfstab-vector-recorder), read by the M7 image
// (maglev-qemu-selfstab-replay.elf), which writes the outputs in the same
// encoding the recorder used for the host's own run. Little-endian fields,
// copied byte by byte: the same bytes on x86-64 and the Cortex-M7.
//
// vectors: Header | StageProfile bytes | tick_count x InputRecord
// outputs: tick_count x OutputRecord
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/selfstab_stage/selfstab_stage.hpp"

namespace maglev::selfstab_replay {

inline constexpr std::uint32_t kMagic = 0x50525353u;  // "SSRP"
inline constexpr std::uint32_t kVersion = 1;
inline constexpr std::size_t kHeaderBytes = 16;
inline constexpr std::size_t kInputRecordBytes = 20;
inline constexpr std::size_t kTelemetryFloats = 6 * 7 + 9;
inline constexpr std::size_t kOutputRecordBytes = 8 + 2 * selfstab::kCoils + 2 + 4 * kTelemetryFloats;

// A command applied before the tick (the bench's timeline).
enum class Command : std::uint8_t {
  kNone = 0,
  kLiftOff = 1,
  kMoveTo = 2,
  kHold = 3,
  kLand = 4,
  kFilterOn = 5,
  kFilterOff = 6,
};

struct Header {
  std::uint32_t magic, version, tick_count, profile_bytes;
};

struct InputRecord {
  selfstab::SelfstabSensorSample sample;
  Command command;
  std::int8_t axis;
  float value;
};

namespace detail {
template <typename T>
inline void put(std::uint8_t*& p, T v) {
  std::memcpy(p, &v, sizeof v);
  p += sizeof v;
}
template <typename T>
inline T get(const std::uint8_t*& p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  p += sizeof v;
  return v;
}
}  // namespace detail

inline void encode_header(const Header& h, std::uint8_t out[kHeaderBytes]) {
  std::uint8_t* p = out;
  detail::put(p, h.magic);
  detail::put(p, h.version);
  detail::put(p, h.tick_count);
  detail::put(p, h.profile_bytes);
}
inline bool decode_header(const std::uint8_t in[kHeaderBytes], Header* h) {
  const std::uint8_t* p = in;
  h->magic = detail::get<std::uint32_t>(p);
  h->version = detail::get<std::uint32_t>(p);
  h->tick_count = detail::get<std::uint32_t>(p);
  h->profile_bytes = detail::get<std::uint32_t>(p);
  return h->magic == kMagic && h->version == kVersion;
}

inline void encode_input(const InputRecord& r, std::uint8_t out[kInputRecordBytes]) {
  std::uint8_t* p = out;
  for (int c = 0; c < selfstab::kPsdChannels; ++c) detail::put(p, r.sample.psd_code[c]);
  detail::put(p, r.sample.status);
  detail::put(p, static_cast<std::uint8_t>(r.command));
  detail::put(p, r.axis);
  detail::put(p, std::uint8_t{0});
  detail::put(p, r.value);
}
inline void decode_input(const std::uint8_t in[kInputRecordBytes], InputRecord* r) {
  const std::uint8_t* p = in;
  for (int c = 0; c < selfstab::kPsdChannels; ++c) r->sample.psd_code[c] = detail::get<std::int16_t>(p);
  r->sample.status = detail::get<std::uint8_t>(p);
  r->sample.reserved = 0;
  r->command = static_cast<Command>(detail::get<std::uint8_t>(p));
  r->axis = detail::get<std::int8_t>(p);
  (void)detail::get<std::uint8_t>(p);
  r->value = detail::get<float>(p);
}

// Applies the record's command; returns its result (kOk for none).
inline selfstab::SelfstabResult apply_command(selfstab::SelfstabKernel& k, const InputRecord& r) {
  switch (r.command) {
    case Command::kLiftOff: return k.lift_off();
    case Command::kMoveTo: return k.move_to(r.axis, r.value);
    case Command::kHold: return k.hold();
    case Command::kLand: return k.land();
    case Command::kFilterOn: return k.set_feedback_filter(true);
    case Command::kFilterOff: return k.set_feedback_filter(false);
    case Command::kNone: break;
  }
  return selfstab::SelfstabResult::kOk;
}

// One tick's outputs: the command result, the DAC codes and every float of
// the telemetry (pose, feedback, reference, effort, scales, currents).
inline void encode_output(std::uint32_t tick, selfstab::SelfstabResult result, const selfstab::SelfstabCoilCommand& c,
                          const selfstab::SelfstabTelemetry& t, std::uint8_t out[kOutputRecordBytes]) {
  std::uint8_t* p = out;
  detail::put(p, tick);
  detail::put(p, static_cast<std::uint8_t>(result));
  detail::put(p, static_cast<std::uint8_t>(t.mode));
  detail::put(p, c.enable);
  detail::put(p, std::uint8_t{0});
  for (int j = 0; j < selfstab::kCoils; ++j) detail::put(p, c.dac_code[j]);
  detail::put(p, std::uint16_t{0});
  const float* groups[] = {t.pose, t.feedback, t.reference, t.effort_A, t.kp_scale, t.kd_scale};
  for (const float* g : groups)
    for (int a = 0; a < selfstab::kAxes; ++a) detail::put(p, g[a]);
  for (int j = 0; j < selfstab::kCoils; ++j) detail::put(p, t.current_A[j]);
}

}  // namespace maglev::selfstab_replay
