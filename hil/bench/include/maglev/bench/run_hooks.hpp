// Hooks into the in-process run's tick, for fault injection and for judging
// a run from the plant's own truth (maglev-hil campaign, docs/RELIABILITY.md).
// Every hook sees the simulated tick n and time t. With no hooks, run() is
// the plain bench (the default scenario's traces do not change).
#pragma once

#include <cstdint>

#include "maglev/can_link/codec.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

namespace maglev::bench {

class RunHooks {
 public:
  virtual ~RunHooks() = default;
  // The run's private virtual bus, once, before the first tick (a hook may
  // open its own node on it: the babbling node).
  virtual void attach(can::VirtualBus& bus) = 0;
  // Before tick n: plant disturbances (plant.set_external_force, beam loss).
  virtual void before_tick(std::uint64_t n, double t_s, hil::Plant& plant) = 0;
  // The sensor sample the plant endpoint is about to send (sensor faults).
  virtual void on_sensor_sample(std::uint64_t n, double t_s, io::SensorSample* s) = 0;
  // Every frame sent on the bench's virtual bus (CAN faults); `seq` counts
  // frames on the bus.
  virtual can::FaultAction on_frame(const can::CanFrame& frame, std::uint64_t seq) = 0;
  // The actuator command the amplifiers are about to apply (actuator faults).
  virtual void on_actuator(std::uint64_t n, double t_s, io::ActuatorCommand* applied) = 0;
  // Before tick n's controller step: a host's configuration write (the
  // Modbus path ends in the same Controller::apply_config). When
  // config_write_due() says so, the runner hands the present configuration to
  // make_config_write(), applies the result, and reports the kernel's answer
  // and the configuration in force afterwards to config_result().
  virtual bool config_write_due(std::uint64_t /*n*/, double /*t_s*/) { return false; }
  virtual void make_config_write(kernel::KernelConfig* /*config*/) {}
  virtual void config_result(kernel::ConfigError /*result*/, const kernel::KernelConfig& /*in_force*/) {}
  // After tick n: the plant's truth and the controller's status (judging).
  virtual void after_tick(std::uint64_t n, double t_s, const hil::Plant& plant,
                          const kernel::ControllerStatus& status) = 0;
};

}  // namespace maglev::bench
