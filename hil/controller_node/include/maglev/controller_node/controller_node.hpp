// The host controller node of the HIL bench: the firmware kernel
// (maglev::kernel::Controller<Scalar>) with its I/O over CAN frames.
//
// firmware/app (the shared servo application with its BoardIo seam) did not
// exist when this was written, so the node reproduces that seam here:
//   ServoIo        -- what the servo loop needs from "the board": read this
//                     tick's io::SensorSample, write its io::ActuatorCommand.
//   CanServoIo     -- ServoIo over the CAN link: sensor + current-monitor
//                     frames in (E2E-checked by a LinkReceiver), actuator frame
//                     out with the answered sensor frame's counter, status and
//                     heartbeat frames at their catalog rates.
//   ControllerNode -- the servo application: on every accepted sensor frame,
//                     one kernel step, one actuator frame. Commands come in
//                     through command() (in-process bench) -- the CAN
//                     host-command frame is not in the catalog yet.
// When firmware/app lands, ControllerNode should become a thin wrapper around
// it with CanServoIo as its BoardIo.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>

#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_link/watchdog.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::hil {

enum class KernelKind : std::uint8_t { kFloat32 = 0, kQ7_24 = 1 };
const char* to_string(KernelKind k);
// "float32" / "float" -> kFloat32, "q7.24" / "q7_24" / "fixed" -> kQ7_24.
bool parse_kernel_kind(const std::string& s, KernelKind* out);

// The BoardIo-shaped seam between the servo application and its I/O.
class ServoIo {
 public:
  virtual ~ServoIo() = default;
  // Waits up to timeout_us for this tick's sensors. false: nothing (yet).
  virtual bool read_sensors(io::SensorSample& sample, std::uint32_t timeout_us) = 0;
  virtual void write_actuators(const io::ActuatorCommand& command) = 0;
  // Telemetry after the step (decimated inside the transport).
  virtual void publish_status(const kernel::ControllerStatus& status) = 0;
  // Host commands received (in arrival order) and their acknowledgements.
  // Commands that arrived before this tick's sensor frame are executed before
  // its step: over CAN, exactly where the in-process bench applies them.
  virtual bool next_host_command(can::HostCommandFrame& out) {
    (void)out;
    return false;
  }
  virtual void acknowledge(const can::HostCommandAckFrame& ack) { (void)ack; }
  // A shutdown host command arrived (read_sensors returned early).
  virtual bool stop_requested() const { return false; }
};

// ServoIo over one CanPort (virtual bus or SocketCAN).
class CanServoIo final : public ServoIo {
 public:
  explicit CanServoIo(can::CanPort& port, can::BusLoadMeter* tx_meter = nullptr);
  bool read_sensors(io::SensorSample& sample, std::uint32_t timeout_us) override;
  void write_actuators(const io::ActuatorCommand& command) override;
  void publish_status(const kernel::ControllerStatus& status) override;
  bool next_host_command(can::HostCommandFrame& out) override;
  void acknowledge(const can::HostCommandAckFrame& ack) override;
  bool stop_requested() const override { return stop_requested_; }
  // Two-process start-up: one heartbeat_controller (node_state init) so the
  // plant knows the controller's socket is open before it sends tick 0.
  void announce();
  const can::RxStats& rx_stats() const { return rx_.stats(); }
  std::uint32_t tx_errors() const { return tx_errors_; }
  // Accepted sensor frames replaced by a newer one in the same read.
  std::uint32_t superseded() const { return superseded_; }

 private:
  void send(const can::CanFrame& f);
  can::CanPort& port_;
  can::BusLoadMeter* meter_;
  can::LinkReceiver rx_;
  std::uint8_t last_sensor_counter_ = 0;
  std::int16_t coil_current_adc_[io::kCoils] = {};
  std::uint32_t ticks_ = 0;
  std::uint8_t status_counter_ = 0;
  std::uint8_t heartbeat_counter_ = 0;
  std::uint8_t ack_counter_ = 0;
  std::uint32_t tx_errors_ = 0;
  std::uint32_t superseded_ = 0;
  std::deque<can::HostCommandFrame> commands_;
  bool stop_requested_ = false;
};

// Counters of the node's link supervision (lockstep clock: tick * period).
struct NodeLinkStats {
  std::uint32_t fresh_ticks = 0;     // stepped on a sensor frame accepted this tick
  std::uint32_t stale_ticks = 0;     // stepped on the previous sample, io::kStaleFrame set
  std::uint32_t link_lost_ticks = 0; // SensorFrameWatchdog expired: outputs forced safe
  std::uint32_t first_stale_tick = 0xFFFFFFFFu;     // tick of the first stale step
  std::uint32_t first_link_lost_tick = 0xFFFFFFFFu; // tick the watchdog first expired
  std::uint32_t host_commands = 0;   // host commands executed (acked)
};

// The servo application on the kernel, for either Scalar.
class ControllerNode {
 public:
  ControllerNode(KernelKind kind, ServoIo& io);
  ~ControllerNode();
  ControllerNode(const ControllerNode&) = delete;
  ControllerNode& operator=(const ControllerNode&) = delete;

  // One servo tick if sensors arrive within timeout_us: read, execute the
  // host commands that came before the sensor frame, step, write.
  // stale_if_missing (lockstep, the plant's tick is known to be due): no
  // accepted sensor frame -> step on the previous sample flagged
  // io::kStaleFrame (the supervisor latches kStaleFrames on the 3rd), send no
  // actuator frame (nothing to answer), and once the SensorFrameWatchdog
  // (1.2 ms = 3 periods) expired force io::kSafeActuatorCommand.
  // Returns true if a tick ran.
  bool run_once(std::uint32_t timeout_us, bool stale_if_missing = false);

  // Executes one host command (as received over CAN) on the kernel; the
  // result is a kernel::CommandResult value or can::kHostResultNotExecuted.
  std::uint8_t execute(const can::HostCommandFrame& cmd);
  const NodeLinkStats& link_stats() const { return link_; }
  const can::SensorFrameWatchdog& sensor_watchdog() const { return watchdog_; }
  // Last actuator command the kernel path produced (after the watchdog).
  const io::ActuatorCommand& last_output() const { return last_output_; }

  kernel::CommandResult command(const kernel::MotionCommand& cmd);
  kernel::ConfigError apply_config(const kernel::KernelConfig& config);
  const kernel::KernelConfig& config() const;
  const kernel::ControllerStatus& status() const;
  KernelKind kind() const { return kind_; }
  std::uint64_t ticks() const { return ticks_; }

  struct Kernel;  // type-erased Controller<float> / Controller<Q7_24>

 private:
  KernelKind kind_;
  ServoIo& io_;
  std::unique_ptr<Kernel> kernel_;
  std::uint64_t ticks_ = 0;
  void execute_pending();
  io::SensorSample last_sample_{};
  bool have_sample_ = false;
  can::SensorFrameWatchdog watchdog_{};
  NodeLinkStats link_{};
  io::ActuatorCommand last_output_ = io::kSafeActuatorCommand;
};

// The MotionCommand a host command means, given the present reference
// (relative moves: target = reference + distance, in double, exactly as the
// in-process bench computes it). false: code has no kernel MotionCommand.
bool to_motion_command(const can::HostCommandFrame& h, const kernel::Pose64& reference, kernel::MotionCommand* out);
// Reference of kernel axis a in SI (m or rad): int64 pm/prad * 1e-12.
double reference_si(const kernel::Pose64& reference, int kernel_axis);

const char* to_string(kernel::CommandResult r);
const char* to_string(kernel::SequencerState s);

}  // namespace maglev::hil
