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

  static void bind(kernel::Controller<Scalar>* c, Recorder* r, WaveGenerator* w) {
    controller = c;
    recorder = r;
    wave = w;
  }
  static void before_step() {
    controller->set_injection(wave->step(controller->status().state == kernel::SequencerState::kReady));
  }
  static void record(const io::SensorSample& s, const io::ActuatorCommand&) { recorder->sample(controller->status(), s); }
};

}  // namespace maglev::lab
