#include "maglev/app/telemetry.hpp"

#include <cstdint>

namespace maglev::app {
namespace {

std::int32_t pico_to_nano(std::int64_t v) {
  // Round half away from zero, then saturate.
  const std::int64_t q = v >= 0 ? (v + 500) / 1000 : (v - 500) / 1000;
  if (q > INT32_MAX) return INT32_MAX;
  if (q < INT32_MIN) return INT32_MIN;
  return static_cast<std::int32_t>(q);
}

std::int16_t amp_to_milliamp(float a) {
  const float mA = a * 1000.0f;
  if (!(mA == mA)) return 0;  // NaN: report 0, the supervisor owns the fault
  if (mA >= 32767.0f) return INT16_MAX;
  if (mA <= -32768.0f) return INT16_MIN;
  return static_cast<std::int16_t>(mA >= 0.0f ? mA + 0.5f : mA - 0.5f);
}

float magnitude(float v) { return v < 0.0f ? -v : v; }

}  // namespace

can::ControllerStatusFrame to_status_frame(const kernel::ControllerStatus& s) {
  can::ControllerStatusFrame f{};
  f.pose_nm_nrad[0] = pico_to_nano(s.pose[maglev::kernel::Axis::kX]);
  f.pose_nm_nrad[1] = pico_to_nano(s.pose[maglev::kernel::Axis::kY]);
  f.pose_nm_nrad[2] = pico_to_nano(s.pose[maglev::kernel::Axis::kZ]);
  f.pose_nm_nrad[3] = pico_to_nano(s.pose[maglev::kernel::Axis::kThetaX]);
  f.pose_nm_nrad[4] = pico_to_nano(s.pose[maglev::kernel::Axis::kThetaY]);
  f.pose_nm_nrad[5] = pico_to_nano(s.pose[maglev::kernel::Axis::kThetaZ]);
  f.sequencer_state = static_cast<std::uint8_t>(static_cast<std::uint8_t>(s.state) & 0x0Fu);
  f.fault_code = static_cast<std::uint16_t>(s.fault);
  float peak = 0.0f;
  for (int j = 0; j < io::kCoils; ++j) {
    if (magnitude(s.coil_current_A[j]) > peak) peak = magnitude(s.coil_current_A[j]);
  }
  std::uint8_t sat = 0;
  if (s.saturated && peak > 0.0f) {
    for (int j = 0; j < io::kCoils; ++j) {
      if (magnitude(s.coil_current_A[j]) >= peak * 0.999f) sat = static_cast<std::uint8_t>(sat | (1u << j));
    }
  }
  f.saturation_flags = sat;
  const float k = s.scale_k * 10000.0f;
  f.scale_k_e4 = !(k > 0.0f) ? std::uint16_t{0} : k >= 65535.0f ? std::uint16_t{65535} : static_cast<std::uint16_t>(k + 0.5f);
  for (int j = 0; j < io::kCoils; ++j) f.current_command_mA[j] = amp_to_milliamp(s.coil_current_A[j]);
  f.tick = s.tick;
  return f;
}

}  // namespace maglev::app
