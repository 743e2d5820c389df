#include "maglev/app/can_io.hpp"

namespace maglev::app {

CanSensorSource::CanSensorSource(can::CanPort& port, const Config& config)
    : port_(port), config_(config), watchdog_(config.watchdog) {}

std::uint32_t CanSensorSource::now() {
  if (config_.now_us != nullptr) return config_.now_us();
  return tick_clock_us_;
}

void CanSensorSource::handle(const can::CanFrame& frame, std::uint32_t now_us, bool& got_sensor) {
  const can::RxStatus status = receiver_.accept(frame);
  if (status != can::RxStatus::kOk) {
    ++stats_.rejected;
    return;
  }
  const can::Message* m = receiver_.last_message();
  if (m == &can::message(can::MessageKind::kSensor)) {
    if (got_sensor) ++stats_.superseded;
    got_sensor = true;
    can::decode_sensor(frame, last_);
    counter_ = can::frame_counter(frame);
    have_sample_ = true;
    watchdog_.feed(now_us);
  } else if (m == &can::message(can::MessageKind::kCurrentMonitor)) {
    can::CurrentMonitorFrame cm{};
    can::decode_current_monitor(frame, cm);
    for (int j = 0; j < io::kCoils; ++j) coil_current_adc_[j] = cm.coil_current_adc[j];
    ++stats_.current_monitor;
  } else if (m == &can::message(can::MessageKind::kHeartbeatPlant)) {
    can::decode_heartbeat(frame, heartbeat_);
    ++stats_.heartbeats;
  } else if (m == &can::message(can::MessageKind::kHostCommand)) {
    can::HostCommandFrame hc{};
    can::decode_host_command(frame, hc);
    if (host_commands_.push(hc)) ++stats_.host_commands;
  } else {
    ++stats_.ignored;
  }
}

bool CanSensorSource::read(io::SensorSample& sample) {
  ++stats_.reads;
  const std::uint32_t t = now();
  if (!armed_) {
    watchdog_.arm(t);
    armed_ = true;
  }
  bool got_sensor = false;
  can::CanFrame frame{};
  for (std::uint8_t i = 0; i < config_.max_frames_per_read; ++i) {
    if (port_.receive(frame, 0) != can::PortStatus::kOk) break;
    handle(frame, t, got_sensor);
  }
  const bool expired = watchdog_.check(t);
  fresh_ = got_sensor;

  sample = last_;
  for (int j = 0; j < io::kCoils; ++j) sample.coil_current_adc[j] = coil_current_adc_[j];
  if (got_sensor) {
    ++stats_.fresh;
  } else {
    // Nothing new: the kernel gets the previous sample, flagged, so its
    // supervisor (not this driver) decides how long that is acceptable.
    sample.status_flags = static_cast<std::uint16_t>(sample.status_flags | io::kStaleFrame);
    ++stats_.stale;
  }
  // The lockstep clock advances after the tick it timed.
  tick_clock_us_ += config_.period_us;
  if (expired || !have_sample_) {
    ++stats_.link_lost;
    return false;
  }
  return true;
}

void CanActuatorSink::write(const io::ActuatorCommand& command) {
  if (!sensors_.fresh()) {
    ++stats_.unanswered;
    return;
  }
  const std::uint32_t tick = sensors_.stats().reads;
  if (tick == answered_read_) {
    ++stats_.duplicates;
    return;
  }
  answered_read_ = tick;
  can::encode_actuator(command, sensors_.answer_counter(), frame_);
  if (port_.send(frame_) == can::PortStatus::kOk) {
    ++stats_.sent;
  } else {
    ++stats_.send_errors;
  }
}

}  // namespace maglev::app
