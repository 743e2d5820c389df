// The lab tools' part of the servo tick, as the plain-function ServoHooks the
// servo loop takes (app::ServoHooks::before_step / record):
//
//   lab::LabTick<float>::bind(&controller, &recorder, &wave);
//   hooks.before_step = lab::LabTick<float>::before_step;   // wave -> kernel injection
//   hooks.record = lab::LabTick<float>::record;             // kernel status -> recorder
//
// before_step: the generator runs only while the kernel is Ready (anything
// else aborts it); record: one Recorder::sample() of this tick's status.
#pragma once

#include "maglev/controller/controller.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"

namespace maglev::lab {

template <typename Scalar>
struct LabTick {
  static inline kernel::Controller<Scalar>* controller = nullptr;
  static inline Recorder* recorder = nullptr;
  static inline WaveGenerator* wave = nullptr;

  // The controller's injection is the idle generator's (Injection{}) and was
  // set since the last bind(): a tick with the generator not running has
  // nothing to do.
  static inline bool idle_injection_set = false;

  static void bind(kernel::Controller<Scalar>* c, Recorder* r, WaveGenerator* w) {
    controller = c;
    recorder = r;
    wave = w;
    idle_injection_set = false;
  }
  static void before_step() {
    // Not running: step() would return Injection{} and change nothing, so
    // the controller gets Injection{} once and the ticks after it skip the
    // call (nothing else sets the injection). Same injection every tick as
    // calling step() each time; ~30 Cortex-M7 instructions less per idle tick.
    if (wave->state() != WaveState::kRunning) {
      if (idle_injection_set) return;
      controller->set_injection(kernel::Injection{});
      idle_injection_set = true;
      return;
    }
    idle_injection_set = false;
    controller->set_injection(wave->step(controller->status().state == kernel::SequencerState::kReady));
  }
  static void record(const io::SensorSample& s, const io::ActuatorCommand&) { recorder->sample(controller->status(), s); }
};

}  // namespace maglev::lab
