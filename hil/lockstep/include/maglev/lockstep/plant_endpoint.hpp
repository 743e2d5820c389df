// The plant endpoint of the HIL link (README.md): sends tick N's frames in
// the one order and waits for the actuator frame that answers N.
// Host only (std::function, std::chrono).
#pragma once

#include <cstdint>
#include <functional>

#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::lockstep {

// Accepted frames other than this tick's actuator frame.
using OtherFrameHandler = std::function<void(const can::Message& m, const can::CanFrame& f)>;

class PlantEndpoint {
 public:
  struct Config {
    // Meter received frames too (true when the controller runs in another
    // process, so its frames are not metered by its own sender).
    bool meter_received = false;
    // The controller runs on this thread between send_tick() and
    // await_actuator() (the bench's in-process run): on a virtual bus the
    // wait is then a drain of what is queued. false: always a blocking wait.
    bool same_thread = true;
  };

  // meter may be null.
  PlantEndpoint(can::CanPort& port, can::BusLoadMeter* meter, Config config);
  PlantEndpoint(can::CanPort& port, can::BusLoadMeter* meter) : PlantEndpoint(port, meter, Config{}) {}

  // Tick n's frames; returns the sensor frame's counter (the actuator frame
  // answering it carries the same).
  std::uint8_t send_tick(std::uint64_t n, double t_s, const io::SensorSample& s);
  // Waits up to timeout_us for the actuator frame answering `counter`; other
  // accepted frames go to the handler. false: none came (*out untouched: the
  // caller applies its actuator watchdog).
  bool await_actuator(std::uint8_t counter, std::uint32_t timeout_us, io::ActuatorCommand* out);
  // Any other frame the plant side sends (host commands), metered.
  can::PortStatus send(const can::CanFrame& f);
  // Receives one frame (up to timeout_us) and runs it through the receiver
  // and the handler; false: nothing accepted.
  bool poll(std::uint32_t timeout_us);

  void set_other_frame_handler(OtherFrameHandler h) { other_ = std::move(h); }
  const can::LinkReceiver& receiver() const { return rx_; }

 private:
  // true: it was the actuator frame for `counter` (decoded into *out).
  bool handle(const can::CanFrame& in, int counter, io::ActuatorCommand* out);
  can::CanPort& port_;
  can::BusLoadMeter* meter_;
  Config config_;
  bool virtual_bus_;
  can::LinkReceiver rx_;
  OtherFrameHandler other_;
  std::uint8_t current_monitor_counter_ = 0;
  std::uint8_t heartbeat_counter_ = 0;
};

}  // namespace maglev::lockstep
