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
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  for (;;) {
    can::CanFrame in{};
    std::uint32_t left = 0;
    if (timeout_us > 0) {
      const auto us = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
      left = us > 0 ? static_cast<std::uint32_t>(us) : 0u;
    }
    if (port_.receive(in, left) != can::PortStatus::kOk) return false;
    if (rx_.accept(in) != can::RxStatus::kOk) continue;  // counted in rx_stats()
    const can::Message* m = rx_.last_message();
    if (m == &can::message(can::MessageKind::kCurrentMonitor)) {
      can::CurrentMonitorFrame cm{};
      can::decode_current_monitor(in, cm);
      std::copy(std::begin(cm.coil_current_adc), std::end(cm.coil_current_adc), coil_current_adc_);
      continue;
    }
    if (m == &can::message(can::MessageKind::kSensor)) {
      can::decode_sensor(in, sample);
      std::copy(std::begin(coil_current_adc_), std::end(coil_current_adc_), sample.coil_current_adc);
      last_sensor_counter_ = can::frame_counter(in);
      return true;
    }
    // Plant heartbeats and anything else the controller does not consume.
  }
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

bool ControllerNode::run_once(std::uint32_t timeout_us) {
  io::SensorSample sample{};
  if (!io_.read_sensors(sample, timeout_us)) return false;
  const io::ActuatorCommand cmd = kernel_->step(sample);
  io_.write_actuators(cmd);
  io_.publish_status(kernel_->status());
  ++ticks_;
  return true;
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
