#include "maglev/controller_node/controller_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "maglev/motion_commands/to_motion_command.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/app/telemetry.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/numeric/fixed.hpp"

namespace maglev::hil {

const char* to_string(KernelKind k) { return k == KernelKind::kFloat32 ? "float32" : "q7.24"; }

bool parse_kernel_kind(const std::string& s, KernelKind* out) {
  if (s == "float32" || s == "float") {
    *out = KernelKind::kFloat32;
    return true;
  }
  if (s == "q7.24" || s == "q7_24" || s == "fixed") {
    *out = KernelKind::kQ7_24;
    return true;
  }
  return false;
}

// ------------------------------------------------------------------ NodePort
bool NodePort::wait(std::uint32_t timeout_us) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  bool got = queued_sensor_frames_ > 0;
  for (;;) {
    can::CanFrame in{};
    std::uint32_t left = 0;
    if (timeout_us > 0 && !got) {
      const auto us = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
      left = us > 0 ? static_cast<std::uint32_t>(us) : 0u;
    }
    if (port_.receive(in, left) != can::PortStatus::kOk) return got;
    const bool ok = rx_.accept(in) == can::RxStatus::kOk;  // rejections counted in receiver().stats()
    if (in.id == can::message(can::MessageKind::kHostCommand).can_id) {
      // The operator's channel: executed by the node, never by the servo tick.
      if (!ok) continue;
      can::HostCommandFrame hc{};
      can::decode_host_command(in, hc);
      commands_.push_back(hc);
      if (hc.code == can::HostCommandCode::kShutdown) {
        stop_requested_ = true;
        return got;
      }
      continue;
    }
    const bool sensor = ok && rx_.last_message() == &can::message(can::MessageKind::kSensor);
    queue_.push_back(Queued{in, sensor});
    if (sensor) {
      const std::uint8_t c = can::frame_counter(in);
      if (!synced_) {
        expected_ = c;
        synced_ = true;
      }
      if (queued_sensor_frames_ == 0) first_ = c;
      newest_ = c;
      ++queued_sensor_frames_;
      got = true;
    }
  }
}

bool NodePort::next_host_command(can::HostCommandFrame& out) {
  if (commands_.empty()) return false;
  out = commands_.front();
  commands_.pop_front();
  return true;
}

can::PortStatus NodePort::send(const can::CanFrame& f) {
  const can::PortStatus s = port_.send(f);
  if (s != can::PortStatus::kOk) ++tx_errors_;
  if (meter_ != nullptr) meter_->on_frame(f);
  return s;
}

int NodePort::lost() const {
  if (!synced_ || queued_sensor_frames_ == 0) return 0;
  const int d = static_cast<std::int8_t>(static_cast<std::uint8_t>(first_ - expected_));
  return d > 0 ? d : 0;
}

void NodePort::end_tick(bool fresh) {
  if (!synced_) return;
  expected_ = static_cast<std::uint8_t>((fresh ? newest_ : expected_) + 1u);
}

can::PortStatus NodePort::receive(can::CanFrame& f, std::uint32_t timeout_us) {
  (void)timeout_us;  // the app polls (0); nothing to wait for inside a tick
  if (held_ || queue_.empty()) return can::PortStatus::kTimeout;
  f = queue_.front().frame;
  if (queue_.front().accepted_sensor) --queued_sensor_frames_;
  queue_.pop_front();
  return can::PortStatus::kOk;
}

// ---------------------------------------------------------------- CanServoIo
namespace {
app::CanSensorConfig node_sensor_config(double servo_rate_Hz) {
  app::CanSensorConfig c{};
  c.period_us = static_cast<std::uint32_t>(std::lround(1e6 / servo_rate_Hz));
  c.now_us = nullptr;  // the tick clock: deterministic, what lockstep needs
  // The board bounds its ISR's drain at 16 frames; the host node drains all
  // that wait() queued (a backlog after a stall: newest sensor frame wins).
  c.max_frames_per_read = 255;
  return c;
}
// A catalog period (ticks at the default rate) at servo_rate_Hz: the same
// frame rate in Hz, so telemetry does not grow with the servo rate.
std::uint32_t period_ticks_at(std::uint32_t default_ticks, double servo_rate_Hz) {
  const double n = static_cast<double>(default_ticks) * servo_rate_Hz / io::stage::kServoRate_Hz;
  return std::max<std::uint32_t>(1u, static_cast<std::uint32_t>(std::lround(n)));
}
}  // namespace

CanServoIo::CanServoIo(can::CanPort& port, can::BusLoadMeter* tx_meter, double servo_rate_Hz)
    : port_(port, tx_meter),
      sensors_(port_, node_sensor_config(servo_rate_Hz)),
      actuators_(port_, sensors_),
      servo_rate_Hz_(servo_rate_Hz),
      status_period_ticks_(period_ticks_at(can::kControllerStatusPeriodTicks, servo_rate_Hz)),
      heartbeat_period_ticks_(period_ticks_at(can::kHeartbeatPeriodTicks, servo_rate_Hz)) {}

void CanServoIo::announce() {
  can::HeartbeatFrame hb{can::NodeState::kInit, 0, 0, 0};
  can::CanFrame f{};
  can::encode_heartbeat(can::MessageKind::kHeartbeatController, hb, heartbeat_counter_++, f);
  send(f);
}

void CanServoIo::acknowledge(const can::HostCommandAckFrame& ack) {
  can::CanFrame f{};
  can::encode_host_command_ack(ack, ack_counter_++, f);
  send(f);
}

void CanServoIo::publish_status(const kernel::ControllerStatus& st) {
  // Catalog rates on the tick grid (10, 20, ...; 250, 500, ...): the bus
  // carries the same frames at the same ticks as every earlier bench run.
  ++ticks_;
  if (ticks_ % status_period_ticks_ == 0) {
    can::CanFrame f{};
    can::encode_controller_status(app::to_status_frame(st), status_counter_++, f);
    send(f);
  }
  if (ticks_ % heartbeat_period_ticks_ == 0) {
    // Same content as app::Application's heartbeat.
    can::HeartbeatFrame hb{};
    const bool fault = st.fault != kernel::FaultCode::kNone || st.state == kernel::SequencerState::kFault;
    hb.node_state = fault ? can::NodeState::kFault : can::NodeState::kOperational;
    hb.uptime_ms = static_cast<std::uint32_t>(static_cast<std::uint64_t>(ticks_) * 1000u /
                                              static_cast<std::uint64_t>(servo_rate_Hz_));
    hb.rx_rejected = static_cast<std::uint16_t>(std::min<std::uint32_t>(rx_stats().rejected_total(), 65535u));
    hb.bus_errors = static_cast<std::uint16_t>(std::min<std::uint32_t>(port_.counters().error_frames, 65535u));
    can::CanFrame f{};
    can::encode_heartbeat(can::MessageKind::kHeartbeatController, hb, heartbeat_counter_++, f);
    send(f);
  }
}

// ----------------------------------------------------------- ControllerNode
// The Kernel ServoLoop steps: step(sample, tick_overrun), as on the board.
struct ControllerNode::Kernel {
  virtual ~Kernel() = default;
  virtual io::ActuatorCommand step(const io::SensorSample& s, bool tick_overrun) = 0;
  virtual kernel::CommandResult command(const kernel::MotionCommand& c) = 0;
  virtual kernel::ConfigError apply_config(const kernel::KernelConfig& c) = 0;
  virtual const kernel::KernelConfig& config() const = 0;
  virtual const kernel::ControllerStatus& status() const = 0;
};

namespace {
template <typename Scalar>
struct KernelImpl final : ControllerNode::Kernel {
  kernel::Controller<Scalar> c;
  io::ActuatorCommand step(const io::SensorSample& s, bool tick_overrun) override { return c.step(s, tick_overrun); }
  kernel::CommandResult command(const kernel::MotionCommand& m) override { return c.command(m); }
  kernel::ConfigError apply_config(const kernel::KernelConfig& k) override { return c.apply_config(k); }
  const kernel::KernelConfig& config() const override { return c.config(); }
  const kernel::ControllerStatus& status() const override { return c.status(); }
};

// Remembers what ServoLoop wrote (after its safe preset), then hands it on.
class RememberingSink final : public app::ActuatorSink {
 public:
  explicit RememberingSink(app::ActuatorSink& inner) : inner_(inner) {}
  void write(const io::ActuatorCommand& command) override {
    last = command;
    inner_.write(command);
  }
  // A forwarding sink forwards the missed-deadline path too (the inner sink
  // decides what "safe" takes; ServoLoop::check_deadline).
  void force_safe() override {
    last = io::kSafeActuatorCommand;
    inner_.force_safe();
  }
  io::ActuatorCommand last = io::kSafeActuatorCommand;

 private:
  app::ActuatorSink& inner_;
};
}  // namespace

struct ControllerNode::Servo {
  Servo(CanServoIo& io, Kernel& kernel)
      : sink(io.actuators()), loop(io.sensors(), sink, kernel, app::ServoConfig{}, app::ServoHooks{}) {}
  RememberingSink sink;
  // No cycle budget / deadline hooks on the host: lockstep has no wall-clock
  // deadline, so tick_overrun stays false exactly as in a board tick that fits.
  app::ServoLoop<Kernel> loop;
};

ControllerNode::ControllerNode(KernelKind kind, CanServoIo& io) : kind_(kind), io_(io) {
  if (kind == KernelKind::kFloat32) {
    kernel_ = std::make_unique<KernelImpl<float>>();
  } else {
    kernel_ = std::make_unique<KernelImpl<numeric::Q7_24>>();
  }
  servo_ = std::make_unique<Servo>(io_, *kernel_);
}

ControllerNode::~ControllerNode() = default;

bool ControllerNode::run_once(std::uint32_t timeout_us, bool stale_if_missing) {
  NodePort& port = io_.port();
  const bool fresh = port.wait(timeout_us);
  if (!fresh && (!stale_if_missing || ticks_ == 0 || io_.stop_requested())) {
    execute_pending();
    return false;
  }
  if (fresh && ticks_ > 0 && !io_.stop_requested()) {
    // The periods whose frames never came: stale ticks, as a board's timer
    // would have run them (the 3rd latches kStaleFrames, the 4th finds the
    // frame watchdog expired).
    port.hold(true);
    for (int k = port.lost(); k > 0; --k) tick();
    port.hold(false);
  }
  // Commands that came with (or before) this tick's frame apply at this tick.
  execute_pending();
  tick();
  return true;
}

void ControllerNode::tick() {
  const app::CanSensorStats before = io_.sensors().stats();
  servo_->loop.on_tick();
  const app::CanSensorStats& after = io_.sensors().stats();
  const auto tick = static_cast<std::uint32_t>(ticks_);
  link_.fresh_ticks += after.fresh - before.fresh;
  if (after.stale != before.stale) {
    if (link_.stale_ticks == 0) link_.first_stale_tick = tick;
    link_.stale_ticks += after.stale - before.stale;
  }
  if (after.link_lost != before.link_lost) {
    if (link_.link_lost_ticks == 0) link_.first_link_lost_tick = tick;
    link_.link_lost_ticks += after.link_lost - before.link_lost;
  }
  io_.port().end_tick(after.fresh != before.fresh);
  io_.publish_status(kernel_->status());
  ++ticks_;
  if (after_tick) after_tick();
}

void ControllerNode::execute_pending() {
  can::HostCommandFrame h{};
  while (io_.next_host_command(h)) {
    can::HostCommandAckFrame ack{};
    ack.seq = h.seq;
    ack.code = h.code;
    ack.result = execute(h);
    ack.sequencer_state = static_cast<std::uint8_t>(kernel_->status().state);
    ack.tick = static_cast<std::uint32_t>(ticks_);
    io_.acknowledge(ack);
    ++link_.host_commands;
  }
}

const io::ActuatorCommand& ControllerNode::last_output() const { return servo_->sink.last; }
std::uint32_t ControllerNode::servo_ticks() const { return servo_->loop.state().ticks; }
std::uint32_t ControllerNode::sensor_faults() const { return servo_->loop.state().sensor_faults; }

std::uint8_t ControllerNode::execute(const can::HostCommandFrame& h) {
  kernel::MotionCommand c;
  if (!motion_commands::to_motion_command(h, kernel_->status().reference, &c)) return can::kHostResultNotExecuted;
  return static_cast<std::uint8_t>(kernel_->command(c));
}

kernel::CommandResult ControllerNode::command(const kernel::MotionCommand& cmd) { return kernel_->command(cmd); }
kernel::ConfigError ControllerNode::apply_config(const kernel::KernelConfig& c) { return kernel_->apply_config(c); }
const kernel::KernelConfig& ControllerNode::config() const { return kernel_->config(); }
const kernel::ControllerStatus& ControllerNode::status() const { return kernel_->status(); }

}  // namespace maglev::hil
