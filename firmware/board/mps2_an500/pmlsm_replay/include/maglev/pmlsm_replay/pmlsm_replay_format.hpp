// Vectors and outputs of paper 002's bit-exact replay (PmlsmController on
// the host bench vs on QEMU's Cortex-M7). Shared by the host recorder
// (hil/bench, `maglev-hil record-pmlsm`) and the M7 image
// (maglev-qemu-pmlsm-replay). Plain structs copied byte for byte: both ends
// are little-endian and every member is at most 4-byte aligned, so the
// layouts agree; the sizes are pinned here so a difference fails to compile.
//
//   vectors: Header | PmlsmKernelConfig | tick_count x InputRecord
//   outputs: tick_count x OutputRecord
#pragma once

#include <cstdint>
#include <cstring>

#include "maglev/pmlsm_stage/pmlsm_controller.hpp"

namespace maglev::pmlsm_replay {

inline constexpr char kMagic[8] = {'P', 'M', 'L', 'S', 'M', 'R', 'P', '1'};

struct Header {
  char magic[8];
  std::uint32_t config_bytes;
  std::uint32_t tick_count;
};

struct InputRecord {
  std::uint8_t has_command;  // apply `command` before this tick's step()
  std::uint8_t reserved[3];
  pmlsm_stage::MotionCommand command;
  pmlsm_stage::SensorSample sample;
};

struct OutputRecord {
  pmlsm_stage::ActuatorCommand actuator;
  std::uint8_t state;
  std::uint8_t fault;
  std::uint8_t command_result;  // 255: no command this tick
  std::uint8_t reserved;
  float w[pmlsm_stage::kAxes];
  float reference[pmlsm_stage::kAxes];
  float i_d_A[pmlsm_stage::kMotors];
  float i_q_A[pmlsm_stage::kMotors];
};

static_assert(sizeof(Header) == 16, "replay header layout");
static_assert(sizeof(pmlsm_stage::MotionCommand) == 32, "MotionCommand layout differs between host and M7?");
static_assert(sizeof(pmlsm_stage::SensorSample) == 24, "SensorSample layout");
static_assert(sizeof(InputRecord) == 60, "InputRecord layout");
static_assert(sizeof(OutputRecord) == 96, "OutputRecord layout");
static_assert(sizeof(pmlsm_stage::ActuatorCommand) == 18, "ActuatorCommand layout");

// Fills an OutputRecord with every byte defined (padding zeroed).
inline OutputRecord make_output(const pmlsm_stage::ActuatorCommand& a, const pmlsm_stage::PmlsmStatus& s,
                                std::uint8_t command_result) {
  OutputRecord o;
  std::memset(static_cast<void*>(&o), 0, sizeof o);
  o.actuator.amplifier_enable = a.amplifier_enable;
  for (int i = 0; i < pmlsm_stage::kDacChannels; ++i) o.actuator.dac_code[i] = a.dac_code[i];
  o.state = static_cast<std::uint8_t>(s.state);
  o.fault = static_cast<std::uint8_t>(s.fault);
  o.command_result = command_result;
  for (int i = 0; i < pmlsm_stage::kAxes; ++i) {
    o.w[i] = s.w[i];
    o.reference[i] = s.reference[i];
  }
  for (int m = 0; m < pmlsm_stage::kMotors; ++m) {
    o.i_d_A[m] = s.i_d_A[m];
    o.i_q_A[m] = s.i_q_A[m];
  }
  return o;
}

}  // namespace maglev::pmlsm_replay
