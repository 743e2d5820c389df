// The host controller node of the HIL bench: the firmware application
// (firmware/app) -- app::ServoLoop over app::CanSensorSource /
// app::CanActuatorSink, stepping maglev::kernel::Controller<Scalar> -- with
// its I/O over CAN frames of the one catalog. "The same kernel and firmware
// application code as on the board, with its I/O over CAN": the tick body,
// the stale-frame / frame-watchdog policy, the zero-current preset and the
// actuator-frame counter rule are the app's objects, not copies.
//
// What the node adds around them (host-only, STL allowed):
//   CanServoIo     -- the node's CAN front end. Its NodePort (a can::CanPort
//                     adapter between the real port and the app) waits, with
//                     a timeout, until an ACCEPTED sensor frame is queued,
//                     takes host_command frames out of the stream (they are
//                     the bench operator's channel, executed by the node
//                     before the step, acknowledged with host_command_ack),
//                     meters what the node sends, and hands everything else
//                     to the app's CanSensorSource in arrival order. Also
//                     sends controller_status (app::to_status_frame) and
//                     heartbeat_controller at their catalog ticks.
//   ControllerNode -- the kernel (float32 or Q7.24, chosen at run time) under
//                     app::ServoLoop; run_once() = wait for the tick's sensor
//                     frame, execute queued host commands, ServoLoop::on_tick(),
//                     telemetry.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>

#include "maglev/app/can_io.hpp"
#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_link/watchdog.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"

namespace maglev::hil {

enum class KernelKind : std::uint8_t { kFloat32 = 0, kQ7_24 = 1 };
const char* to_string(KernelKind k);
// "float32" / "float" -> kFloat32, "q7.24" / "q7_24" / "fixed" -> kQ7_24.
bool parse_kernel_kind(const std::string& s, KernelKind* out);

// can::CanPort between the node's real port and the app's CanSensorSource /
// CanActuatorSink. Every received frame goes through ONE LinkReceiver here
// (the node's receive-side statistics, as before: all frames, host commands
// included). The app's own receiver sees the same frames in the same order
// minus the host commands; E2E counters are per message, so its verdicts on
// the frames it sees equal this one's -- which is what lets wait() know, before
// the tick, whether the app will find a fresh sensor frame.
class NodePort final : public can::CanPort {
 public:
  NodePort(can::CanPort& port, can::BusLoadMeter* tx_meter) : port_(port), meter_(tx_meter) {}

  // Waits up to timeout_us for an accepted sensor frame, then moves whatever
  // else is already queued into the app's queue without waiting (a late frame
  // is then superseded by the newest, in the app). host_command frames go to
  // the command queue; a shutdown command ends the wait at once.
  // true: an accepted sensor frame is queued for the app.
  bool wait(std::uint32_t timeout_us);
  bool next_host_command(can::HostCommandFrame& out);
  bool stop_requested() const { return stop_requested_; }

  // can::CanPort, as the app sees it: receive() serves only what wait()
  // queued (never blocks, never reads the real port: frames arriving during
  // the tick belong to the next one, as on the board's FIFO snapshot).
  can::PortStatus send(const can::CanFrame& frame) override;
  can::PortStatus receive(can::CanFrame& frame, std::uint32_t timeout_us) override;
  const can::PortCounters& counters() const override { return port_.counters(); }

  const can::LinkReceiver& receiver() const { return rx_; }
  std::uint32_t tx_errors() const { return tx_errors_; }

  // The node's tick clock on the E2E counter (the plant numbers its sensor
  // frames tick mod 256). lost(): how many servo periods passed, unseen,
  // between the last tick and the oldest accepted sensor frame wait() queued
  // (0 before the first frame, or when the node is ahead). end_tick(): one
  // tick ran; fresh = it took the queued sensor frames.
  int lost() const;
  void end_tick(bool fresh);
  // While held, receive() serves nothing: the ticks that stand in for lost
  // frames must not consume the frame that arrived after them.
  void hold(bool held) { held_ = held; }

 private:
  struct Queued {
    can::CanFrame frame;
    bool accepted_sensor;
  };
  can::CanPort& port_;
  can::BusLoadMeter* meter_;
  can::LinkReceiver rx_;
  std::deque<Queued> queue_;
  std::uint32_t queued_sensor_frames_ = 0;
  std::deque<can::HostCommandFrame> commands_;
  bool stop_requested_ = false;
  std::uint32_t tx_errors_ = 0;
  bool held_ = false;
  bool synced_ = false;          // a sensor frame was accepted: expected_ is valid
  std::uint8_t expected_ = 0;    // the counter the next tick's frame should carry
  std::uint8_t first_ = 0;       // oldest accepted sensor frame queued since the last tick
  std::uint8_t newest_ = 0;      // newest accepted sensor frame queued
};

// The node's CAN I/O: NodePort + the app's CanSensorSource/CanActuatorSink +
// telemetry and host-command acknowledgements.
class CanServoIo {
 public:
  // servo_rate_Hz: the kernel's configured rate (KernelConfig::servo_rate_Hz):
  // the sensor source's tick clock, and the telemetry periods (kept in Hz).
  explicit CanServoIo(can::CanPort& port, can::BusLoadMeter* tx_meter = nullptr,
                      double servo_rate_Hz = io::stage::kServoRate_Hz);
  CanServoIo(const CanServoIo&) = delete;
  CanServoIo& operator=(const CanServoIo&) = delete;

  // The app's servo-side objects (ServoLoop's SensorSource / ActuatorSink).
  app::CanSensorSource& sensors() { return sensors_; }
  const app::CanSensorSource& sensors() const { return sensors_; }
  app::CanActuatorSink& actuators() { return actuators_; }
  NodePort& port() { return port_; }

  // Two-process start-up: one heartbeat_controller (node_state init) so the
  // plant knows the controller's socket is open before it sends tick 0.
  void announce();
  // After each servo tick: controller_status every kControllerStatusPeriodTicks
  // ticks (app::to_status_frame), heartbeat_controller every
  // kHeartbeatPeriodTicks -- on ticks 10, 20, ... and 250, 500, ... at the
  // default 2.5 kHz; at a higher rate the same 250 Hz / 10 Hz (more ticks).
  void publish_status(const kernel::ControllerStatus& status);
  void acknowledge(const can::HostCommandAckFrame& ack);
  bool next_host_command(can::HostCommandFrame& out) { return port_.next_host_command(out); }
  // A shutdown host command arrived (run_once returned early).
  bool stop_requested() const { return port_.stop_requested(); }

  // Every frame the node received, through one LinkReceiver.
  const can::RxStats& rx_stats() const { return port_.receiver().stats(); }
  std::uint32_t tx_errors() const { return port_.tx_errors(); }
  // Accepted sensor frames replaced by a newer one in the same tick (the app's count).
  std::uint32_t superseded() const { return sensors_.stats().superseded; }

 private:
  void send(const can::CanFrame& f) { (void)port_.send(f); }
  NodePort port_;
  app::CanSensorSource sensors_;
  app::CanActuatorSink actuators_;
  double servo_rate_Hz_;
  std::uint32_t status_period_ticks_;
  std::uint32_t heartbeat_period_ticks_;
  std::uint32_t ticks_ = 0;
  std::uint8_t status_counter_ = 0;
  std::uint8_t heartbeat_counter_ = 0;
  std::uint8_t ack_counter_ = 0;
};

// Former name of the node's I/O seam (now app::SensorSource/ActuatorSink).
using ServoIo = CanServoIo;

// Counters of the node's link supervision (lockstep clock: tick * period),
// from app::CanSensorSource's statistics.
struct NodeLinkStats {
  std::uint32_t fresh_ticks = 0;     // stepped on a sensor frame accepted this tick
  std::uint32_t stale_ticks = 0;     // stepped on the previous sample, io::kStaleFrame set
  std::uint32_t link_lost_ticks = 0; // SensorFrameWatchdog expired: outputs forced safe
  std::uint32_t first_stale_tick = 0xFFFFFFFFu;     // tick of the first stale step
  std::uint32_t first_link_lost_tick = 0xFFFFFFFFu; // tick the watchdog first expired
  std::uint32_t host_commands = 0;   // host commands executed (acked)
};

// The firmware servo application on the kernel, for either Scalar.
class ControllerNode {
 public:
  ControllerNode(KernelKind kind, CanServoIo& io);
  ~ControllerNode();
  ControllerNode(const ControllerNode&) = delete;
  ControllerNode& operator=(const ControllerNode&) = delete;

  // One servo tick if an accepted sensor frame arrives within timeout_us:
  // execute the host commands that came with/before it, ServoLoop::on_tick()
  // (CanSensorSource::read -> Controller::step -> CanActuatorSink::write),
  // telemetry. stale_if_missing (lockstep, the plant's tick is known to be
  // due): no accepted sensor frame -> the tick runs anyway and the app
  // handles it: previous sample flagged io::kStaleFrame (the supervisor
  // latches kStaleFrames on the 3rd), no actuator frame, and once the
  // SensorFrameWatchdog (1.2 ms = 3 periods) expired read() fails, so
  // ServoLoop adds io::kAdcFault and writes io::kSafeActuatorCommand.
  // No tick before the first sensor frame, none after a shutdown command.
  // A board ticks on its own timer, so a lost sensor frame is a stale tick
  // there. The node ticks on frames, so it counts what it did not see: when
  // a frame arrives whose counter is k beyond the next tick's, k stale ticks
  // (the app's stale and link-lost path, docs/CAN.md "Watchdogs") run first,
  // then the fresh one; the node stays on the plant's tick whatever was lost
  // (two-process mode, where nothing else tells it a period passed).
  // Returns true if a tick ran; after_tick (if set) runs after every tick.
  bool run_once(std::uint32_t timeout_us, bool stale_if_missing = false);
  std::function<void()> after_tick;

  // Executes one host command (as received over CAN) on the kernel; the
  // result is a kernel::CommandResult value or can::kHostResultNotExecuted.
  std::uint8_t execute(const can::HostCommandFrame& cmd);
  const NodeLinkStats& link_stats() const { return link_; }
  const can::SensorFrameWatchdog& sensor_watchdog() const { return io_.sensors().watchdog(); }
  // Last actuator command ServoLoop wrote (safe preset applied), sent or not.
  const io::ActuatorCommand& last_output() const;
  // ServoLoop's own counters (ticks, overruns, sensor_faults = link-lost ticks).
  std::uint32_t servo_ticks() const;
  std::uint32_t sensor_faults() const;

  kernel::CommandResult command(const kernel::MotionCommand& cmd);
  kernel::ConfigError apply_config(const kernel::KernelConfig& config);
  const kernel::KernelConfig& config() const;
  const kernel::ControllerStatus& status() const;
  KernelKind kind() const { return kind_; }
  std::uint64_t ticks() const { return ticks_; }

  struct Kernel;  // type-erased Controller<float> / Controller<Q7_24>, step(sample, overrun)
  struct Servo;   // app::ServoLoop<Kernel> + the sink that remembers the last output

 private:
  void execute_pending();
  void tick();
  KernelKind kind_;
  CanServoIo& io_;
  std::unique_ptr<Kernel> kernel_;
  std::unique_ptr<Servo> servo_;
  std::uint64_t ticks_ = 0;
  NodeLinkStats link_{};
};

// The MotionCommand a host command means: motion_commands::to_motion_command
// (firmware/app host_command.hpp), the same mapping the HIL board's
// app::Application executes.
// Names of the kernel enums: kernel::to_string (one table next to each enum).
using kernel::to_string;

}  // namespace maglev::hil
