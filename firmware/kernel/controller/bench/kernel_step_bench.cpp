// kernel-step-bench: instructions per Controller::step() for float and Q7.24,
// measured under callgrind in two situations:
//   idle  : the first round's synthetic input (counter dither), sequencer in Idle
//   ready : closed loop around the test stage (tests/kernel/controller/axis_stage.hpp),
//           levitated in Ready with all six loops closed, a 5 mm sinusoid on x
//           (references, libm sin in double) and an 8-line multisine excitation on
//           theta_z running: the heaviest steady tick.
// Each measured call goes through a noinline wrapper so callgrind can count it alone:
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.out
//     build/<dir>/firmware/kernel/controller/kernel-step-bench 20000      (one line)
//   callgrind_annotate --inclusive=yes /tmp/cg.out | grep 'measured_'
// docs/PERFORMANCE.md records the numbers.
#include <cstdio>
#include <cstdlib>

#include "axis_stage.hpp"
#include "maglev/controller/controller.hpp"

namespace {

using maglev::io::ActuatorCommand;
using maglev::io::SensorSample;
using maglev::kernel::Controller;

// Distinct bodies (the counters), so that identical-code folding (-fipa-icf
// at -O2) cannot merge the two wrappers into one callgrind entry.
volatile unsigned g_idle_calls = 0;
volatile unsigned g_ready_calls = 0;

template <typename Scalar>
__attribute__((noinline)) ActuatorCommand measured_idle_step(Controller<Scalar>& c, const SensorSample& s) {
  g_idle_calls = g_idle_calls + 1u;
  return c.step(s, false);
}

template <typename Scalar>
__attribute__((noinline)) ActuatorCommand measured_ready_step(Controller<Scalar>& c, const SensorSample& s) {
  g_ready_calls = g_ready_calls + 3u;
  return c.step(s, false);
}

template <typename Scalar>
long run_idle(long ticks) {
  static Controller<Scalar> controller;  // static, as on the target
  SensorSample s{};
  long checksum = 0;
  for (long n = 0; n < ticks; ++n) {
    const auto d = static_cast<std::uint32_t>((n * 7919) % 13);
    s.interferometer_counts[0] = 1000u + d;
    s.interferometer_counts[1] = 2000u - d;
    s.interferometer_counts[2] = 3000u + d;
    for (int k = 0; k < 3; ++k) s.displacement_adc[k] = static_cast<std::int16_t>(-32000 + 300 + static_cast<int>(d));
    s.hall_adc[0] = 8000;
    s.hall_adc[1] = 8000;
    s.hall_adc[2] = 14000;
    s.hall_adc[3] = 14000;
    const ActuatorCommand c = measured_idle_step(controller, s);
    checksum += c.dac_code[0] + c.dac_code[3];
  }
  return checksum;
}

template <typename Scalar>
long run_ready(long ticks, bool* ok) {
  using namespace maglev::kernel;
  static Controller<Scalar> c;
  maglev::kernel::test::AxisStage stage(99);
  c.command(MotionCommand{MotionType::kLevitate});
  *ok = stage.run_until(c, SequencerState::kReady, 40000);
  MotionCommand sine;
  sine.type = MotionType::kSinusoid;
  sine.axis = Axis::kX;
  sine.amplitude = 5e-3;
  sine.frequency_Hz = 0.75;
  MotionCommand ex;
  ex.type = MotionType::kExcite;
  ex.axis = Axis::kThetaZ;
  ex.amplitude = 0.05;
  ex.frequency_Hz = 10.0;
  ex.harmonics = 8;
  *ok = *ok && c.command(sine) == CommandResult::kAccepted && c.command(ex) == CommandResult::kAccepted;
  long checksum = 0;
  for (long n = 0; n < ticks; ++n) {
    const ActuatorCommand cmd = measured_ready_step(c, stage.sample());
    stage.advance(cmd, c.status().pose[Axis::kX], c.status().pose[Axis::kY]);
    checksum += cmd.dac_code[0] + cmd.dac_code[3];
  }
  *ok = *ok && c.status().state == SequencerState::kReady && c.status().excitation_active;
  return checksum;
}

}  // namespace

int main(int argc, char** argv) {
  const long ticks = argc > 1 ? std::atol(argv[1]) : 100000;
  const long a = run_idle<float>(ticks);
  const long b = run_idle<maglev::numeric::Q7_24>(ticks);
  bool ok_f = false, ok_q = false;
  const long c = run_ready<float>(ticks, &ok_f);
  const long d = run_ready<maglev::numeric::Q7_24>(ticks, &ok_q);
  std::printf("ticks=%ld idle: float %ld q7_24 %ld; ready: float %ld (%s) q7_24 %ld (%s)\n", ticks, a, b, c,
              ok_f ? "ok" : "NOT READY", d, ok_q ? "ok" : "NOT READY");
  return ok_f && ok_q ? 0 : 1;
}
