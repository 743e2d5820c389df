// The HIL board's (and the host controller node's) SensorSource/ActuatorSink:
// sensor frames in, actuator frames out over any maglev::can::CanPort, coded
// by firmware/can_link. "The HIL build replaces only the sensor and actuator
// drivers with CAN frames": ServoLoop, kernel, Modbus, telemetry and the
// watchdog policy are the same objects the amplifier-board image runs.
//
// Per servo tick (CanSensorSource::read, servo interrupt context):
//   * drain the port (at most Config::max_frames_per_read frames, so the ISR
//     work is bounded); every frame goes through one LinkReceiver (E2E CRC,
//     length, format, counter): a rejected frame is NEVER applied;
//   * sensor frame accepted -> the sample for this tick, SensorFrameWatchdog
//     fed; several accepted in one tick -> the newest wins (older ones counted
//     superseded); current_monitor frames update coil_current_adc (decimated,
//     500 Hz); heartbeat_plant frames are counted; host_command frames are
//     decoded into host_commands() (Application executes and acks them in
//     thread mode: never in the servo tick);
//   * no accepted sensor frame this tick (lost, late, bad CRC, repeated
//     counter) -> the previous sample repeated with io::kStaleFrame set and
//     read() returns true: the kernel's supervisor decides (it tolerates
//     max_consecutive_stale_frames = 2 and latches kStaleFrames on the 3rd);
//   * SensorFrameWatchdog expired (no accepted frame for more than
//     watchdog.timeout_us, 1.2 ms = 3 periods) or no frame ever -> also
//     stale, and read() returns false: ServoLoop writes kSafeActuatorCommand
//     whatever the kernel says (defence in depth below the supervisor).
//
// CanActuatorSink::write encodes the command with the counter of the sensor
// frame this tick answered (catalog: "e2e_counter = counter of the sensor
// frame it answers"). A stale tick answers nothing: no frame is sent (the
// plant's ActuatorFrameWatchdog owns that case), the tick is counted; a
// second write in the same tick (ServoLoop::check_deadline) is not sent
// either: the plant would reject the repeated counter anyway.
//
// Time: Config::now_us (any wrapping 32-bit microsecond clock) or, when null,
// read() count * period_us -- the lockstep clock, deterministic.
// Heap-free, exception-free; host + Cortex-M7.
#pragma once

#include <cstdint>

#include "maglev/app/board_io.hpp"
#include "maglev/app/host_command_queue.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_link/watchdog.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::app {

struct CanSensorConfig {
  std::uint32_t period_us = 400;            // servo period (2.5 kHz); the tick clock when now_us is null
  can::FrameWatchdogConfig watchdog{};      // 1200 us = 3 periods
  std::uint32_t (*now_us)() = nullptr;      // wrapping microsecond clock, or null (tick clock)
  std::uint8_t max_frames_per_read = 16;    // bound on the ISR's drain loop
};

struct CanSensorStats {
  std::uint32_t reads = 0;
  std::uint32_t fresh = 0;             // ticks served by a sensor frame accepted in that tick
  std::uint32_t stale = 0;             // ticks served by a repeated (stale-flagged) sample
  std::uint32_t link_lost = 0;         // ticks with the frame watchdog expired (read() false)
  std::uint32_t superseded = 0;        // accepted sensor frames replaced by a newer one in the same tick
  std::uint32_t rejected = 0;          // frames the LinkReceiver rejected (all reasons)
  std::uint32_t current_monitor = 0;   // accepted current_monitor frames
  std::uint32_t heartbeats = 0;        // accepted heartbeat_plant frames
  std::uint32_t host_commands = 0;     // accepted host_command frames queued for the Application
  std::uint32_t ignored = 0;           // accepted catalog frames not meant for the controller
};

class CanSensorSource final : public SensorSource {
 public:
  using Config = CanSensorConfig;
  CanSensorSource(can::CanPort& port, const Config& config);

  bool read(io::SensorSample& sample) override;

  // This tick was answered by a fresh sensor frame; its E2E counter.
  bool fresh() const { return fresh_; }
  std::uint8_t answer_counter() const { return counter_; }
  // The last plant heartbeat (valid once stats().heartbeats > 0).
  const can::HeartbeatFrame& plant_heartbeat() const { return heartbeat_; }

  // Accepted host_command frames, oldest first (ApplicationHooks::host_commands).
  HostCommandQueue& host_commands() { return host_commands_; }
  const can::LinkReceiver& receiver() const { return receiver_; }
  const can::SensorFrameWatchdog& watchdog() const { return watchdog_; }
  const CanSensorStats& stats() const { return stats_; }
  // A new servo period (register servo.rate, applied landed; the HIL board
  // with its tick timer stopped): the tick clock's step when now_us is null.
  void set_period_us(std::uint32_t period_us) { config_.period_us = period_us; }

 private:
  std::uint32_t now();
  void handle(const can::CanFrame& frame, std::uint32_t now_us, bool& got_sensor);

  can::CanPort& port_;
  Config config_;
  can::LinkReceiver receiver_{};
  can::SensorFrameWatchdog watchdog_;
  io::SensorSample last_{};
  std::int16_t coil_current_adc_[io::kCoils] = {};
  can::HeartbeatFrame heartbeat_{};
  HostCommandQueue host_commands_{};
  CanSensorStats stats_{};
  std::uint32_t tick_clock_us_ = 0;
  bool armed_ = false;
  bool have_sample_ = false;
  bool fresh_ = false;
  std::uint8_t counter_ = 0;
};

struct CanActuatorStats {
  std::uint32_t sent = 0;
  std::uint32_t send_errors = 0;   // CanPort::send returned non-kOk
  std::uint32_t unanswered = 0;    // stale ticks: nothing to answer, no frame sent
  std::uint32_t duplicates = 0;    // a second write for the same tick (e.g. the deadline check): not sent
};

class CanActuatorSink final : public ActuatorSink {
 public:
  // `sensors` tells which sensor frame (counter) this tick answers.
  CanActuatorSink(can::CanPort& port, const CanSensorSource& sensors) : port_(port), sensors_(sensors) {}

  void write(const io::ActuatorCommand& command) override;

  const CanActuatorStats& stats() const { return stats_; }
  const can::CanFrame& last_frame() const { return frame_; }

 private:
  can::CanPort& port_;
  const CanSensorSource& sensors_;
  can::CanFrame frame_{};
  CanActuatorStats stats_{};
  std::uint32_t answered_read_ = 0;  // sensors_.stats().reads of the tick last answered
};

}  // namespace maglev::app
