// lab-tick-bench: instructions per servo tick spent in the lab tools, under
// callgrind (host x86-64; docs/LAB-TOOLS.md records the numbers):
//   recorder idle        : Recorder::sample() while idle / done (one compare)
//   recorder 8 ch level  : 8 channels (pose, reference, error, effort, coil
//                          currents, state, fault) + a level trigger that never
//                          fires: the heaviest steady recorder tick
//   wave multisine       : WaveGenerator::step() reading the period table
//   wave sine            : phase accumulator + the kernel's sine table
//   wave sweep           : log sweep (double phase and increment)
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/lab.out
//       build/host/firmware/lab_tools/registers/lab-tick-bench 20000      (one line)
//   callgrind_annotate --inclusive=yes /tmp/lab.out | grep 'measured_'
#include <cstdio>
#include <cstdlib>

#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"
#include "lab_tick_setup.hpp"

namespace {

using namespace maglev;

float g_pool[lab::kBoardPoolWords];
float g_table[lab::kWaveTableLen];

volatile unsigned g_a = 0, g_b = 0, g_c = 0, g_d = 0, g_e = 0;

__attribute__((noinline)) void measured_recorder_idle(lab::Recorder& r, const kernel::ControllerStatus& st,
                                                      const io::SensorSample& s) {
  g_a = g_a + 1u;
  r.sample(st, s);
}
__attribute__((noinline)) void measured_recorder_8ch_level(lab::Recorder& r, const kernel::ControllerStatus& st,
                                                           const io::SensorSample& s) {
  g_b = g_b + 2u;
  r.sample(st, s);
}
__attribute__((noinline)) float measured_wave_multisine(lab::WaveGenerator& w) {
  g_c = g_c + 3u;
  return w.step(true).value;
}
__attribute__((noinline)) float measured_wave_sine(lab::WaveGenerator& w) {
  g_d = g_d + 4u;
  return w.step(true).value;
}
__attribute__((noinline)) float measured_wave_sweep(lab::WaveGenerator& w) {
  g_e = g_e + 5u;
  return w.step(true).value;
}

}  // namespace

int main(int argc, char** argv) {
  const long ticks = argc > 1 ? std::atol(argv[1]) : 20000;
  static kernel::ControllerStatus st{};
  io::SensorSample s{};
  lab::Recorder idle(g_pool, lab::kBoardPoolWords);
  static lab::Recorder rec(g_pool, lab::kBoardPoolWords);
  static lab::WaveGenerator multi(g_table, lab::kWaveTableLen), sine(g_table, lab::kWaveTableLen),
      sweep(g_table, lab::kWaveTableLen);
  if (!lab::setup_lab_tick_scenario(rec, multi, sine, sweep)) return 1;
  double sum = 0;
  for (long n = 0; n < ticks; ++n) {
    st.pose.pico[0] = n * 1000;
    st.coil_current_A[0] = static_cast<float>(n & 7);
    s.coil_current_adc[0] = static_cast<std::int16_t>(n & 1023);
    measured_recorder_idle(idle, st, s);
    measured_recorder_8ch_level(rec, st, s);
    sum += static_cast<double>(measured_wave_multisine(multi) + measured_wave_sine(sine) + measured_wave_sweep(sweep));
  }
  std::printf("%ld ticks, recorder state %d, checksum %g\n", ticks, static_cast<int>(rec.state()), sum);
  return 0;
}
