#include "maglev/controller_node/controller_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

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

// ---------------------------------------------------------------- CanServoIo
CanServoIo::CanServoIo(can::CanPort& port, can::BusLoadMeter* tx_meter) : port_(port), meter_(tx_meter) {}

void CanServoIo::send(const can::CanFrame& f) {
  if (port_.send(f) != can::PortStatus::kOk) ++tx_errors_;
  if (meter_ != nullptr) meter_->on_frame(f);
}

bool CanServoIo::read_sensors(io::SensorSample& sample, std::uint32_t timeout_us) {
  // Waits (up to timeout_us) for a sensor frame, then drains what is already
  // queued without waiting: a late (delayed) frame is superseded by the
  // newest one, as the board's CanSensorSource does. In lockstep nothing but
  // this tick's frames is queued, so draining changes nothing there.
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  bool got = false;
  for (;;) {
    can::CanFrame in{};
    std::uint32_t left = 0;
    if (timeout_us > 0 && !got) {
      const auto us = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
      left = us > 0 ? static_cast<std::uint32_t>(us) : 0u;
    }
    if (port_.receive(in, left) != can::PortStatus::kOk) return got;
    if (rx_.accept(in) != can::RxStatus::kOk) continue;  // counted in rx_stats()
    const can::Message* m = rx_.last_message();
    if (m == &can::message(can::MessageKind::kCurrentMonitor)) {
      can::CurrentMonitorFrame cm{};
      can::decode_current_monitor(in, cm);
      std::copy(std::begin(cm.coil_current_adc), std::end(cm.coil_current_adc), coil_current_adc_);
      if (got) std::copy(std::begin(coil_current_adc_), std::end(coil_current_adc_), sample.coil_current_adc);
      continue;
    }
    if (m == &can::message(can::MessageKind::kHostCommand)) {
      can::HostCommandFrame hc{};
      can::decode_host_command(in, hc);
      commands_.push_back(hc);
      if (hc.code == can::HostCommandCode::kShutdown) {
        stop_requested_ = true;
        return got;
      }
      continue;
    }
    if (m == &can::message(can::MessageKind::kSensor)) {
      if (got) ++superseded_;
      can::decode_sensor(in, sample);
      std::copy(std::begin(coil_current_adc_), std::end(coil_current_adc_), sample.coil_current_adc);
      last_sensor_counter_ = can::frame_counter(in);
      got = true;
      continue;
    }
    // Plant heartbeats and anything else the controller does not consume.
  }
}

void CanServoIo::announce() {
  can::HeartbeatFrame hb{can::NodeState::kInit, 0, 0, 0};
  can::CanFrame f{};
  can::encode_heartbeat(can::MessageKind::kHeartbeatController, hb, heartbeat_counter_++, f);
  send(f);
}

bool CanServoIo::next_host_command(can::HostCommandFrame& out) {
  if (commands_.empty()) return false;
  out = commands_.front();
  commands_.pop_front();
  return true;
}

void CanServoIo::acknowledge(const can::HostCommandAckFrame& ack) {
  can::CanFrame f{};
  can::encode_host_command_ack(ack, ack_counter_++, f);
  send(f);
}

void CanServoIo::write_actuators(const io::ActuatorCommand& command) {
  can::CanFrame f{};
  can::encode_actuator(command, last_sensor_counter_, f);
  send(f);
}

void CanServoIo::publish_status(const kernel::ControllerStatus& st) {
  ++ticks_;
  if (ticks_ % can::kControllerStatusPeriodTicks == 0) {
    can::ControllerStatusFrame s{};
    const std::int64_t pose[6] = {st.pose.x_pm, st.pose.y_pm, st.pose.z_pm,
                                  st.pose.theta_x_prad, st.pose.theta_y_prad, st.pose.theta_z_prad};
    for (int i = 0; i < 6; ++i) {
      const std::int64_t v = pose[i] / 1000;  // pm -> nm, prad -> nrad
      s.pose_nm_nrad[i] = static_cast<std::int32_t>(std::clamp<std::int64_t>(v, INT32_MIN, INT32_MAX));
    }
    s.sequencer_state = static_cast<std::uint8_t>(st.state);
    s.fault_code = static_cast<std::uint16_t>(st.fault);
    s.saturation_flags = st.saturated ? 1u : 0u;
    s.scale_k_e4 = static_cast<std::uint16_t>(std::lround(std::clamp(st.scale_k, 0.0f, 1.0f) * 10000.0f));
    for (int j = 0; j < io::kCoils; ++j) {
      const float mA = std::clamp(st.coil_current_A[j] * 1000.0f, -32768.0f, 32767.0f);
      s.current_command_mA[j] = static_cast<std::int16_t>(std::lround(mA));
    }
    s.tick = st.tick;
    can::CanFrame f{};
    can::encode_controller_status(s, status_counter_++, f);
    send(f);
  }
  if (ticks_ % can::kHeartbeatPeriodTicks == 0) {
    can::HeartbeatFrame hb{};
    hb.node_state = st.state == kernel::SequencerState::kFault ? can::NodeState::kFault : can::NodeState::kOperational;
    hb.uptime_ms = static_cast<std::uint32_t>(static_cast<std::uint64_t>(ticks_) * 1000u /
                                              static_cast<std::uint64_t>(io::stage::kServoRate_Hz));
    hb.rx_rejected = static_cast<std::uint16_t>(std::min<std::uint32_t>(rx_.stats().rejected_total(), 65535u));
    can::CanFrame f{};
    can::encode_heartbeat(can::MessageKind::kHeartbeatController, hb, heartbeat_counter_++, f);
    send(f);
  }
}

// ----------------------------------------------------------- ControllerNode
struct ControllerNode::Kernel {
  virtual ~Kernel() = default;
  virtual io::ActuatorCommand step(const io::SensorSample& s) = 0;
  virtual kernel::CommandResult command(const kernel::MotionCommand& c) = 0;
  virtual kernel::ConfigError apply_config(const kernel::KernelConfig& c) = 0;
  virtual const kernel::KernelConfig& config() const = 0;
  virtual const kernel::ControllerStatus& status() const = 0;
};

namespace {
template <typename Scalar>
struct KernelImpl final : ControllerNode::Kernel {
  kernel::Controller<Scalar> c;
  io::ActuatorCommand step(const io::SensorSample& s) override { return c.step(s, false); }
  kernel::CommandResult command(const kernel::MotionCommand& m) override { return c.command(m); }
  kernel::ConfigError apply_config(const kernel::KernelConfig& k) override { return c.apply_config(k); }
  const kernel::KernelConfig& config() const override { return c.config(); }
  const kernel::ControllerStatus& status() const override { return c.status(); }
};
}  // namespace

ControllerNode::ControllerNode(KernelKind kind, ServoIo& io) : kind_(kind), io_(io) {
  if (kind == KernelKind::kFloat32) {
    kernel_ = std::make_unique<KernelImpl<float>>();
  } else {
    kernel_ = std::make_unique<KernelImpl<numeric::Q7_24>>();
  }
}

ControllerNode::~ControllerNode() = default;

bool ControllerNode::run_once(std::uint32_t timeout_us, bool stale_if_missing) {
  io::SensorSample sample{};
  const bool fresh = io_.read_sensors(sample, timeout_us);
  execute_pending();
  const auto period_us = static_cast<std::uint32_t>(1e6 / io::stage::kServoRate_Hz);
  const auto now_us = static_cast<std::uint32_t>(ticks_ * period_us);
  if (ticks_ == 0) watchdog_.arm(now_us);
  if (fresh) {
    last_sample_ = sample;
    have_sample_ = true;
    watchdog_.feed(now_us);
    ++link_.fresh_ticks;
  } else {
    if (!stale_if_missing || !have_sample_ || io_.stop_requested()) return false;
    sample = last_sample_;
    sample.status_flags = static_cast<std::uint16_t>(sample.status_flags | io::kStaleFrame);
    if (link_.stale_ticks == 0) link_.first_stale_tick = static_cast<std::uint32_t>(ticks_);
    ++link_.stale_ticks;
  }
  io::ActuatorCommand cmd = kernel_->step(sample);
  if (watchdog_.check(now_us)) {
    if (link_.link_lost_ticks == 0) link_.first_link_lost_tick = static_cast<std::uint32_t>(ticks_);
    ++link_.link_lost_ticks;
    cmd = io::kSafeActuatorCommand;  // defence in depth below the supervisor
  }
  last_output_ = cmd;
  if (fresh) io_.write_actuators(cmd);  // a stale tick answers no sensor frame
  io_.publish_status(kernel_->status());
  ++ticks_;
  return true;
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

double reference_si(const kernel::Pose64& r, int a) {
  // kernel::Axis order: x, y, theta_z, z, theta_x, theta_y.
  const std::int64_t v[6] = {r.x_pm, r.y_pm, r.theta_z_prad, r.z_pm, r.theta_x_prad, r.theta_y_prad};
  return static_cast<double>(v[a < 0 || a > 5 ? 0 : a]) * 1e-12;
}

bool to_motion_command(const can::HostCommandFrame& h, const kernel::Pose64& reference, kernel::MotionCommand* out) {
  using C = can::HostCommandCode;
  using kernel::MotionType;
  kernel::MotionCommand c;
  c.axis = static_cast<kernel::Axis>(h.axis);
  const double* a = h.arg;
  switch (h.code) {
    case C::kHome: c.type = MotionType::kHome; break;
    case C::kLevitate: c.type = MotionType::kLevitate; break;
    case C::kLand: c.type = MotionType::kLand; break;
    case C::kStop: c.type = MotionType::kStop; break;
    case C::kClearFault: c.type = MotionType::kClearFault; break;
    case C::kHold: c.type = MotionType::kHold; break;
    case C::kStep: c.type = MotionType::kStep; c.target = a[0]; break;
    case C::kMoveTo:
    case C::kMoveBy:
      c.type = MotionType::kMoveTo;
      c.target = h.code == C::kMoveBy ? reference_si(reference, h.axis) + a[0] : a[0];
      c.velocity = a[1];
      c.acceleration = a[2];
      break;
    case C::kMoveJerkTo:
    case C::kMoveJerkBy:
      c.type = MotionType::kMoveJerkLimited;
      c.target = h.code == C::kMoveJerkBy ? reference_si(reference, h.axis) + a[0] : a[0];
      c.velocity = a[1];
      c.acceleration = a[2];
      c.jerk = a[3];
      break;
    case C::kCircle: c.type = MotionType::kCircle; c.diameter_m = a[0]; c.period_s = a[1]; c.turns = a[2]; break;
    case C::kSinusoid:
      c.type = MotionType::kSinusoid; c.amplitude = a[0]; c.frequency_Hz = a[1]; c.period_s = a[2]; c.turns = a[3];
      break;
    case C::kExcite:
      c.type = MotionType::kExcite; c.amplitude = a[0]; c.frequency_Hz = a[1]; c.duration_s = a[2];
      c.harmonics = static_cast<std::uint8_t>(std::clamp(a[3], 1.0, 255.0));
      break;
    case C::kStopExcitation: c.type = MotionType::kStopExcitation; break;
    case C::kShutdown: return false;
  }
  *out = c;
  return true;
}

std::uint8_t ControllerNode::execute(const can::HostCommandFrame& h) {
  kernel::MotionCommand c;
  if (!to_motion_command(h, kernel_->status().reference, &c)) return can::kHostResultNotExecuted;
  return static_cast<std::uint8_t>(kernel_->command(c));
}

kernel::CommandResult ControllerNode::command(const kernel::MotionCommand& cmd) { return kernel_->command(cmd); }
kernel::ConfigError ControllerNode::apply_config(const kernel::KernelConfig& c) { return kernel_->apply_config(c); }
const kernel::KernelConfig& ControllerNode::config() const { return kernel_->config(); }
const kernel::ControllerStatus& ControllerNode::status() const { return kernel_->status(); }

const char* to_string(kernel::CommandResult r) {
  using R = kernel::CommandResult;
  switch (r) {
    case R::kAccepted: return "accepted";
    case R::kAlreadyThere: return "already there";
    case R::kRefusedBusy: return "refused: busy";
    case R::kRefusedNotLevitated: return "refused: not levitated";
    case R::kRefusedFaultLatched: return "refused: fault latched";
    case R::kRefusedNotFaulted: return "refused: not faulted";
    case R::kRefusedFaultActive: return "refused: fault active";
    case R::kRefusedNotReady: return "refused: not ready";
    case R::kRefusedOutOfRange: return "refused: out of range";
    case R::kRefusedBadProfile: return "refused: bad profile";
    case R::kUnsupported: return "unsupported by this kernel build";
    default: break;
  }
  return "?";
}

const char* to_string(kernel::SequencerState s) {
  using S = kernel::SequencerState;
  switch (s) {
    case S::kIdle: return "Idle";
    case S::kHoming: return "Homing";
    case S::kInPlaneLock: return "InPlaneLock";
    case S::kLift: return "Lift";
    case S::kZLock: return "ZLock";
    case S::kTiltLock: return "TiltLock";
    case S::kReady: return "Ready";
    case S::kLanding: return "Landing";
    case S::kFault: return "Fault";
  }
  return "?";
}

}  // namespace maglev::hil
