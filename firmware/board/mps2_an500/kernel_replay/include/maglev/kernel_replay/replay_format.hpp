// The kernel replay vector format, shared by the host recorder
// (tests/target/bitexact, x86-64) and the replay image
// (maglev-qemu-kernel-replay, Cortex-M7): both sides encode/decode with THESE
// functions, field by field, little-endian, so struct padding and ABI never
// enter the bytes that are compared.
//
// Input file  (recorder -> image):  InputHeader, the stage profile
//                                    (profile_bytes), then tick_count InputRecords.
// Output file (recorder and image): tick_count OutputRecords, nothing else.
// Two output files are bit-identical iff the two kernels produced the same
// bits on every tick (commands' results, DAC codes, status floats, poses).
//
// Heap-free, exception-free: compiled into the firmware image.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/controller/controller.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::kernel_replay {

inline constexpr char kMagic[8] = {'M', 'G', 'L', 'V', 'R', 'P', 'L', '1'};
// v2: the header's last word is the size of the stage profile that follows
// it (0: the kernel's default configuration).
inline constexpr std::uint32_t kFormatVersion = 3;  // 3: total_effort_A (= effort_A) gone

// --- byte-level little-endian helpers (both targets are little-endian; the
// memcpy keeps it alignment- and aliasing-safe) ------------------------------
template <typename T>
inline void put(std::uint8_t*& p, T value) {
  std::memcpy(p, &value, sizeof(T));
  p += sizeof(T);
}
template <typename T>
inline T get(const std::uint8_t*& p) {
  T value;
  std::memcpy(&value, p, sizeof(T));
  p += sizeof(T);
  return value;
}

// --- header ------------------------------------------------------------------
inline constexpr std::size_t kHeaderBytes = 32;
struct InputHeader {
  std::uint32_t version = kFormatVersion;
  std::uint32_t tick_count = 0;
  std::uint32_t input_record_bytes = 0;
  std::uint32_t output_record_bytes = 0;
  std::uint32_t command_count = 0;
  // Bytes of the stage_profile::StageProfile after the header (its in-memory
  // image: plain data, natural alignment, identical on x86-64 and AAPCS; the
  // size check catches a layout that differs). 0: default_kernel_config().
  std::uint32_t profile_bytes = 0;
};

// --- input record: one servo tick's inputs --------------------------------------
// When MotionCommand or SensorSample grows a field, extend encode_input /
// decode_input (and bump kFormatVersion); the recorder drives its own kernel
// with the decoded record, so an uncarried field can never make the two sides
// see different inputs -- it is only left untested.
// SensorSample (44) + overrun, has_command, type, axis, harmonics, 3 pad (8)
// + the 11 doubles of MotionCommand (88).
inline constexpr std::size_t kSensorSampleBytes =
    4 * io::kInterferometerAxes + 2 * (io::kDisplacementSensors + io::kHallChannels + io::kCoils) + 2;
inline constexpr std::size_t kInputRecordBytes = kSensorSampleBytes + 8 + 11 * 8;

struct InputRecord {
  io::SensorSample sample{};
  bool tick_overrun = false;
  bool has_command = false;
  kernel::MotionCommand command{};
};

// --- output record: what one tick of Controller<float> produced ---------------
// kNoCommand in command_result: no command was issued this tick.
inline constexpr std::uint8_t kNoCommand = 0xFF;
inline constexpr int kStatusFloats = 1 + 3 * kernel::kAxisCount + io::kCoils;  // scale_k, 3x6 efforts, 8 currents
inline constexpr std::size_t kOutputRecordBytes =
    4 + 4 + 2 * io::kCoils + 4 + 4 * static_cast<std::size_t>(kStatusFloats) + 8 * 2 * kernel::kAxisCount;

struct OutputRecord {
  std::uint32_t tick = 0;
  std::uint8_t command_result = kNoCommand;
  io::ActuatorCommand actuator{};
  const kernel::ControllerStatus* status = nullptr;
};

// Field table of an output record, for the host's mismatch report.
enum class FieldKind : std::uint8_t { kU32, kU8, kBool, kI16, kF32, kI64 };
struct FieldInfo {
  const char* name;
  FieldKind kind;
  int count;
};
inline constexpr FieldInfo kOutputFields[] = {
    {"tick", FieldKind::kU32, 1},
    {"command_result", FieldKind::kU8, 1},
    {"amplifier_enable", FieldKind::kBool, 1},
    {"sequencer_state", FieldKind::kU8, 1},
    {"closed_axes", FieldKind::kU8, 1},
    {"dac_code", FieldKind::kI16, io::kCoils},
    {"fault", FieldKind::kU8, 1},
    {"saturated", FieldKind::kBool, 1},
    {"pose_valid", FieldKind::kU8, 1},
    {"pad", FieldKind::kU8, 1},
    {"scale_k", FieldKind::kF32, 1},
    {"effort_A", FieldKind::kF32, kernel::kAxisCount},
    {"loop_effort_A", FieldKind::kF32, kernel::kAxisCount},
    {"applied_effort_A", FieldKind::kF32, kernel::kAxisCount},
    {"coil_current_A", FieldKind::kF32, io::kCoils},
    {"pose_pm_or_prad", FieldKind::kI64, kernel::kAxisCount},
    {"reference_pm_or_prad", FieldKind::kI64, kernel::kAxisCount},
};
constexpr std::size_t field_bytes(FieldKind kind) {
  switch (kind) {
    case FieldKind::kU8:
    case FieldKind::kBool: return 1;
    case FieldKind::kI16: return 2;
    case FieldKind::kU32:
    case FieldKind::kF32: return 4;
    case FieldKind::kI64: return 8;
  }
  return 0;
}
constexpr std::size_t output_fields_bytes() {
  std::size_t total = 0;
  for (const FieldInfo& f : kOutputFields) {
    total += field_bytes(f.kind) * static_cast<std::size_t>(f.count);
  }
  return total;
}
static_assert(output_fields_bytes() == kOutputRecordBytes, "field table and encoder disagree");

// --- encoders / decoders ---------------------------------------------------------
inline void encode_header(const InputHeader& h, std::uint8_t* out) {
  std::memcpy(out, kMagic, sizeof(kMagic));
  std::uint8_t* p = out + sizeof(kMagic);
  put<std::uint32_t>(p, h.version);
  put<std::uint32_t>(p, h.tick_count);
  put<std::uint32_t>(p, h.input_record_bytes);
  put<std::uint32_t>(p, h.output_record_bytes);
  put<std::uint32_t>(p, h.command_count);
  put<std::uint32_t>(p, h.profile_bytes);
}

// False if the magic, version or record sizes do not match this build.
inline bool decode_header(const std::uint8_t* in, InputHeader* h) {
  if (std::memcmp(in, kMagic, sizeof(kMagic)) != 0) {
    return false;
  }
  const std::uint8_t* p = in + sizeof(kMagic);
  h->version = get<std::uint32_t>(p);
  h->tick_count = get<std::uint32_t>(p);
  h->input_record_bytes = get<std::uint32_t>(p);
  h->output_record_bytes = get<std::uint32_t>(p);
  h->command_count = get<std::uint32_t>(p);
  h->profile_bytes = get<std::uint32_t>(p);
  return h->version == kFormatVersion && h->input_record_bytes == kInputRecordBytes &&
         h->output_record_bytes == kOutputRecordBytes;
}

inline void encode_input(const InputRecord& r, std::uint8_t* out) {
  std::uint8_t* p = out;
  for (std::uint32_t v : r.sample.interferometer_counts) put<std::uint32_t>(p, v);
  for (std::int16_t v : r.sample.displacement_adc) put<std::int16_t>(p, v);
  for (std::int16_t v : r.sample.hall_adc) put<std::int16_t>(p, v);
  for (std::int16_t v : r.sample.coil_current_adc) put<std::int16_t>(p, v);
  put<std::uint16_t>(p, r.sample.status_flags);
  put<std::uint8_t>(p, r.tick_overrun ? 1U : 0U);
  put<std::uint8_t>(p, r.has_command ? 1U : 0U);
  put<std::uint8_t>(p, static_cast<std::uint8_t>(r.command.type));
  put<std::uint8_t>(p, static_cast<std::uint8_t>(r.command.axis));
  put<std::uint8_t>(p, r.command.harmonics);
  for (int i = 0; i < 3; ++i) put<std::uint8_t>(p, 0U);
  const kernel::MotionCommand& c = r.command;
  for (double v : {c.target, c.velocity, c.acceleration, c.jerk, c.amplitude, c.frequency_Hz, c.diameter_m,
                   c.period_s, c.turns, c.duration_s, 0.0}) {
    put<double>(p, v);
  }
}

inline void decode_input(const std::uint8_t* in, InputRecord* r) {
  const std::uint8_t* p = in;
  for (std::uint32_t& v : r->sample.interferometer_counts) v = get<std::uint32_t>(p);
  for (std::int16_t& v : r->sample.displacement_adc) v = get<std::int16_t>(p);
  for (std::int16_t& v : r->sample.hall_adc) v = get<std::int16_t>(p);
  for (std::int16_t& v : r->sample.coil_current_adc) v = get<std::int16_t>(p);
  r->sample.status_flags = get<std::uint16_t>(p);
  r->tick_overrun = get<std::uint8_t>(p) != 0U;
  r->has_command = get<std::uint8_t>(p) != 0U;
  kernel::MotionCommand& c = r->command;
  c.type = static_cast<kernel::MotionType>(get<std::uint8_t>(p));
  c.axis = static_cast<kernel::Axis>(get<std::uint8_t>(p));
  c.harmonics = get<std::uint8_t>(p);
  p += 3;
  for (double* v : {&c.target, &c.velocity, &c.acceleration, &c.jerk, &c.amplitude, &c.frequency_Hz,
                    &c.diameter_m, &c.period_s, &c.turns, &c.duration_s}) {
    *v = get<double>(p);
  }
}

inline void encode_output(const OutputRecord& r, std::uint8_t* out) {
  const kernel::ControllerStatus& s = *r.status;
  std::uint8_t* p = out;
  put<std::uint32_t>(p, r.tick);
  put<std::uint8_t>(p, r.command_result);
  put<std::uint8_t>(p, r.actuator.amplifier_enable ? 1U : 0U);
  put<std::uint8_t>(p, static_cast<std::uint8_t>(s.state));
  put<std::uint8_t>(p, s.closed_axes);
  for (std::int16_t v : r.actuator.dac_code) put<std::int16_t>(p, v);
  put<std::uint8_t>(p, static_cast<std::uint8_t>(s.fault));
  put<std::uint8_t>(p, s.saturated ? 1U : 0U);
  put<std::uint8_t>(p, s.pose_valid);
  put<std::uint8_t>(p, 0U);
  put<float>(p, s.scale_k);
  for (float v : s.effort_A) put<float>(p, v);
  for (float v : s.loop_effort_A) put<float>(p, v);
  for (float v : s.applied_effort_A) put<float>(p, v);
  for (float v : s.coil_current_A) put<float>(p, v);
  for (const kernel::Pose64* pose : {&s.pose, &s.reference}) {
    for (std::int64_t v : pose->pico) put<std::int64_t>(p, v);  // kernel Axis order
  }
}

}  // namespace maglev::kernel_replay
