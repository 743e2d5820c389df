#include "maglev/can_port/lockstep.hpp"

#include <chrono>

namespace maglev::can {

namespace {
using Clock = std::chrono::steady_clock;
std::uint32_t remaining_us(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
  return left <= 0 ? 0u : static_cast<std::uint32_t>(left);
}
}  // namespace

LockstepStatus LockstepPlantLink::exchange(std::uint32_t tick, const io::SensorSample& sample,
                                           io::ActuatorCommand& command, std::uint32_t timeout_us) {
  const auto counter = static_cast<std::uint8_t>(tick & 0xFFu);
  CanFrame f{};
  encode_sensor(sample, counter, f);
  if (port_.send(f) != PortStatus::kOk) return LockstepStatus::kPortError;
  if (tick % kCurrentMonitorPeriodTicks == 0) {
    CurrentMonitorFrame cm{};
    for (int j = 0; j < io::kCoils; ++j) cm.coil_current_adc[j] = sample.coil_current_adc[j];
    encode_current_monitor(cm, static_cast<std::uint8_t>((tick / kCurrentMonitorPeriodTicks) & 0xFFu), f);
    if (port_.send(f) != PortStatus::kOk) return LockstepStatus::kPortError;
  }
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  for (;;) {
    CanFrame in{};
    const PortStatus ps = port_.receive(in, remaining_us(deadline));
    if (ps == PortStatus::kTimeout) return LockstepStatus::kTimeout;
    if (ps != PortStatus::kOk) return LockstepStatus::kPortError;
    if (rx_.accept(in) != RxStatus::kOk) continue;  // counted in rx_.stats()
    const Message& m = *rx_.last_message();
    if (&m == &message(MessageKind::kActuator)) {
      if (frame_counter(in) == counter) {
        decode_actuator(in, command);
        return LockstepStatus::kOk;
      }
      continue;  // an answer to an older tick: accepted by E2E but not this tick's
    }
    if (other_) other_(m, in);
  }
}

LockstepStatus LockstepControllerLink::wait_sensor(io::SensorSample& sample, std::uint32_t timeout_us) {
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  for (;;) {
    CanFrame in{};
    const PortStatus ps = port_.receive(in, remaining_us(deadline));
    if (ps == PortStatus::kTimeout) return LockstepStatus::kTimeout;
    if (ps != PortStatus::kOk) return LockstepStatus::kPortError;
    if (rx_.accept(in) != RxStatus::kOk) continue;
    const Message& m = *rx_.last_message();
    if (&m == &message(MessageKind::kSensor)) {
      decode_sensor(in, sample);
      for (int j = 0; j < io::kCoils; ++j) sample.coil_current_adc[j] = coil_current_adc_[j];
      last_counter_ = frame_counter(in);
      return LockstepStatus::kOk;
    }
    if (&m == &message(MessageKind::kCurrentMonitor)) {
      CurrentMonitorFrame cm{};
      decode_current_monitor(in, cm);
      for (int j = 0; j < io::kCoils; ++j) coil_current_adc_[j] = cm.coil_current_adc[j];
    }
    if (other_) other_(m, in);
  }
}

LockstepStatus LockstepControllerLink::send_actuator(const io::ActuatorCommand& command) {
  CanFrame f{};
  encode_actuator(command, last_counter_, f);
  return port_.send(f) == PortStatus::kOk ? LockstepStatus::kOk : LockstepStatus::kPortError;
}

}  // namespace maglev::can
