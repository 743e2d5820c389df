// Host-only lockstep exchange over any CanPort: deterministic, as fast as the
// CPU allows. Tick N:
//   plant:      send sensor frame (counter N mod 256) [+ current monitor every
//               kCurrentMonitorPeriodTicks], wait for the actuator frame whose
//               counter equals N mod 256.
//   controller: wait for a sensor frame, step, send the actuator frame with
//               the sensor frame's counter.
// Every received frame runs through a LinkReceiver (E2E + counters); frames of
// other messages (status, heartbeat, current monitor) are handed to an
// optional callback after acceptance.
#pragma once

#include <cstdint>
#include <functional>

#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::can {

enum class LockstepStatus : std::uint8_t { kOk, kTimeout, kPortError };

using OtherFrameHandler = std::function<void(const Message& m, const CanFrame& f)>;

class LockstepPlantLink {
 public:
  explicit LockstepPlantLink(CanPort& port) : port_(port) {}
  // One tick: sends `sample` for tick `tick`, waits up to timeout_us for the
  // matching actuator frame. On kTimeout `command` is left untouched (the
  // caller applies its actuator watchdog / safe command).
  LockstepStatus exchange(std::uint32_t tick, const io::SensorSample& sample,
                          io::ActuatorCommand& command, std::uint32_t timeout_us);
  void set_other_frame_handler(OtherFrameHandler h) { other_ = std::move(h); }
  const LinkReceiver& receiver() const { return rx_; }

 private:
  CanPort& port_;
  LinkReceiver rx_;
  OtherFrameHandler other_;
};

class LockstepControllerLink {
 public:
  explicit LockstepControllerLink(CanPort& port) : port_(port) {}
  // Waits for the next accepted sensor frame (current monitor frames arriving
  // meanwhile update sample.coil_current_adc). kTimeout: sample untouched.
  LockstepStatus wait_sensor(io::SensorSample& sample, std::uint32_t timeout_us);
  // Sends the actuator frame answering the last accepted sensor frame.
  LockstepStatus send_actuator(const io::ActuatorCommand& command);
  std::uint8_t last_sensor_counter() const { return last_counter_; }
  void set_other_frame_handler(OtherFrameHandler h) { other_ = std::move(h); }
  const LinkReceiver& receiver() const { return rx_; }

 private:
  CanPort& port_;
  LinkReceiver rx_;
  OtherFrameHandler other_;
  std::uint8_t last_counter_ = 0;
  std::int16_t coil_current_adc_[io::kCoils]{};
};

}  // namespace maglev::can
