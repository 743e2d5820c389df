#include "maglev/lockstep/plant_endpoint.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>

#include "maglev/virtual_can/virtual_can.hpp"

namespace maglev::lockstep {

namespace {
using Clock = std::chrono::steady_clock;
std::uint32_t remaining_us(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now()).count();
  return left <= 0 ? 0u : static_cast<std::uint32_t>(left);
}
}  // namespace

PlantEndpoint::PlantEndpoint(can::CanPort& port, can::BusLoadMeter* meter, Config config)
    : port_(port), meter_(meter), config_(config), virtual_bus_(config.same_thread && dynamic_cast<can::VirtualCanPort*>(&port) != nullptr) {}

can::PortStatus PlantEndpoint::send(const can::CanFrame& f) {
  const can::PortStatus s = port_.send(f);
  if (meter_ != nullptr) meter_->on_frame(f);
  return s;
}

std::uint8_t PlantEndpoint::send_tick(std::uint64_t n, double t_s, const io::SensorSample& s) {
  can::CanFrame f{};
  if (n % can::kCurrentMonitorPeriodTicks == 0) {
    can::CurrentMonitorFrame cm{};
    std::copy(std::begin(s.coil_current_adc), std::end(s.coil_current_adc), cm.coil_current_adc);
    can::encode_current_monitor(cm, current_monitor_counter_++, f);
    (void)send(f);
  }
  const auto counter = static_cast<std::uint8_t>(n & 0xFFu);
  can::encode_sensor(s, counter, f);
  (void)send(f);
  if (n % can::kHeartbeatPeriodTicks == 0) {
    const can::HeartbeatFrame hb{can::NodeState::kOperational, static_cast<std::uint32_t>(t_s * 1000.0), 0, 0};
    can::encode_heartbeat(can::MessageKind::kHeartbeatPlant, hb, heartbeat_counter_++, f);
    (void)send(f);
  }
  return counter;
}

bool PlantEndpoint::handle(const can::CanFrame& in, int counter, io::ActuatorCommand* out) {
  if (rx_.accept(in) != can::RxStatus::kOk) return false;  // counted in rx_.stats()
  if (config_.meter_received && meter_ != nullptr) meter_->on_frame(in);
  const can::Message& m = *rx_.last_message();
  if (&m == &can::message(can::MessageKind::kActuator) && counter >= 0 && can::frame_counter(in) == counter) {
    can::decode_actuator(in, *out);
    return true;
  }
  // An answer to an older tick is accepted by E2E but is not this tick's.
  if (other_) other_(m, in);
  return false;
}

bool PlantEndpoint::await_actuator(std::uint8_t counter, std::uint32_t timeout_us, io::ActuatorCommand* out) {
  if (virtual_bus_) {
    // Lockstep on one thread: every frame of this tick is already queued.
    // Drain it all (status and heartbeat frames queue behind the actuator).
    auto& vport = static_cast<can::VirtualCanPort&>(port_);
    bool got = false;
    while (vport.pending() > 0) {
      can::CanFrame in{};
      if (port_.receive(in, 0) != can::PortStatus::kOk) break;
      got = handle(in, counter, out) || got;
    }
    return got;
  }
  const auto deadline = Clock::now() + std::chrono::microseconds(timeout_us);
  for (;;) {
    can::CanFrame in{};
    const can::PortStatus ps = port_.receive(in, remaining_us(deadline));
    if (ps == can::PortStatus::kOk) {
      if (handle(in, counter, out)) return true;
      continue;
    }
    if (ps != can::PortStatus::kTimeout || Clock::now() >= deadline) return false;
  }
}

bool PlantEndpoint::poll(std::uint32_t timeout_us) {
  can::CanFrame in{};
  if (port_.receive(in, timeout_us) != can::PortStatus::kOk) return false;
  const std::size_t before = rx_.stats().accepted;
  io::ActuatorCommand ignored{};
  (void)handle(in, -1, &ignored);
  return rx_.stats().accepted != before;
}

}  // namespace maglev::lockstep
