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
  lab::RecorderConfig c{};
  c.channel_count = 8;
  const char* names[8] = {"x.pose", "x.reference", "x.error", "x.effort", "coil1.current", "coil1.current_cmd", "state", "fault"};
  for (int i = 0; i < 8; ++i) c.channel[i] = lab::find_signal(names[i]);
  c.length = 16384;
  c.pretrigger = 1000;
  c.mode = lab::TriggerMode::kLevel;
  c.trigger_signal = lab::find_signal("z.pose");
  c.level = 1.0f;  // never reached
  if (rec.configure(c) != lab::RecorderError::kOk || rec.arm() != lab::RecorderError::kOk) return 1;
  const kernel::KernelConfig k = kernel::default_kernel_config();
  static lab::WaveGenerator multi(g_table, lab::kWaveTableLen), sine(g_table, lab::kWaveTableLen),
      sweep(g_table, lab::kWaveTableLen);
  lab::WaveConfig w{};
  w.shape = lab::WaveShape::kMultisine;
  w.amplitude = 0.1f;
  w.f_start_Hz = 5.0f;
  w.f_end_Hz = 400.0f;
  w.tones = 28;
  if (multi.start(w, k) != lab::WaveError::kOk) return 1;
  w.shape = lab::WaveShape::kSine;
  if (sine.start(w, k) != lab::WaveError::kOk) return 1;
  w.shape = lab::WaveShape::kSweep;
  w.duration_s = 600.0f;
  if (sweep.start(w, k) != lab::WaveError::kOk) return 1;
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
