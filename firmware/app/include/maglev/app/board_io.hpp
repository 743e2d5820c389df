// The seam between the servo application and whatever produces sensor
// samples and consumes actuator commands.
//
//   board      : SensorSource = AD7606 pair + three quadrature counters,
//                ActuatorSink = AD5764 chain + amplifier-enable line
//                (firmware/board/stm32h743/amplifier_board_io.hpp)
//   HIL board  : the SAME firmware with only these two objects replaced by
//                CAN-frame implementations (sensor frame in, actuator frame
//                out, firmware/can_link) -- the servo loop, kernel, watchdog,
//                Modbus and telemetry stay identical.
//   QEMU/host  : in-memory implementations.
//
// Both are called from the servo interrupt only.
#pragma once

#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::app {

class SensorSource {
 public:
  // Fill `sample` for this tick. false: no trustworthy sample (ADC busy/bus
  // error, missing CAN frame); the loop then flags it and outputs zero current.
  virtual bool read(io::SensorSample& sample) = 0;

 protected:
  SensorSource() = default;
  ~SensorSource() = default;
  SensorSource(const SensorSource&) = default;
  SensorSource& operator=(const SensorSource&) = default;
};

class ActuatorSink {
 public:
  virtual void write(const io::ActuatorCommand& command) = 0;
  // The missed-deadline path (ServoLoop::check_deadline), called from an
  // interrupt BELOW the tick's priority: make the outputs safe without
  // starting anything the tick could preempt half-way. A sink whose write()
  // is a multi-step bus transaction (the board's DAC chain) overrides this
  // with one atomic action (the amplifier-enable line low); the default,
  // for sinks whose write is one store or one frame, writes the safe command.
  virtual void force_safe() { write(io::kSafeActuatorCommand); }

 protected:
  ActuatorSink() = default;
  ~ActuatorSink() = default;
  ActuatorSink(const ActuatorSink&) = default;
  ActuatorSink& operator=(const ActuatorSink&) = default;
};

}  // namespace maglev::app
