// maglev-qemu-lab-tick: the lab tools' cost per servo tick on the emulated
// Cortex-M7 (the same code as lab-tick-bench on the host), counted in
// instructions with SysTick under `-icount shift=6` (instruction_counter.hpp):
//   qemu-system-arm -M mps2-an500 -nographic -semihosting-config enable=on,target=native
//                   -icount shift=6 -kernel maglev-qemu-lab-tick.elf -append "lab-tick --icount"
// Per call, over 5000 ticks: Recorder::sample() idle and armed with 8 channels
// + a level trigger (steady: never fires), WaveGenerator::step() for a
// 28-tone multisine, a sine and a log sweep. Without --icount: runs, prints
// "not measured". Exit 0.
#include <cstdint>
#include <cstring>

#include "maglev/board/mps2_an500/instruction_counter.hpp"
#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"

namespace {

namespace hw = maglev::board::mps2_an500;
namespace lab = maglev::lab;
namespace kernel = maglev::kernel;
using namespace hw::icount;

float g_pool[lab::kBoardPoolWords];  // 512 KiB, as on the board
float g_table[lab::kWaveTableLen];
char g_command_line[128];
kernel::ControllerStatus g_status{};
maglev::io::SensorSample g_sample{};
lab::Recorder g_idle{g_pool, lab::kBoardPoolWords};
lab::Recorder g_rec{g_pool, lab::kBoardPoolWords};
lab::WaveGenerator g_multi{g_table, lab::kWaveTableLen};
float g_sine_table[2];
float g_sweep_table[2];
lab::WaveGenerator g_sine{g_sine_table, 2};
lab::WaveGenerator g_sweep{g_sweep_table, 2};
volatile float g_sink = 0.0f;

struct Stats {
  std::uint64_t count = 0, sum = 0, min = ~std::uint64_t{0}, max = 0;
  void add(std::uint64_t v) {
    ++count;
    sum += v;
    min = v < min ? v : min;
    max = v > max ? v : max;
  }
};

void print(const char* label, const Stats& s, const Calibration& cal) {
  hw::semihost_write("lab_tick_instructions ");
  hw::semihost_write(label);
  hw::semihost_write(": calls=");
  hw::semihost_write_unsigned(s.count);
  hw::semihost_write(" min=");
  hw::semihost_write_unsigned(cal.instructions(s.min));
  hw::semihost_write(" mean=");
  hw::semihost_write_unsigned(cal.instructions(s.count > 0 ? s.sum / s.count : 0));
  hw::semihost_write(" max=");
  hw::semihost_write_unsigned(cal.instructions(s.max));
  hw::semihost_write("\n");
}

}  // namespace

int main() {
  const bool have_line = hw::semihost_command_line(g_command_line, sizeof(g_command_line));
  const bool icount = have_line && std::strstr(g_command_line, "--icount") != nullptr;
  lab::RecorderConfig c{};
  c.channel_count = 8;
  const char* names[8] = {"x.pose", "x.reference", "x.error", "x.effort", "coil1.current", "coil1.current_cmd", "state", "fault"};
  for (int i = 0; i < 8; ++i) c.channel[i] = lab::find_signal(names[i]);
  c.length = 16384;
  c.pretrigger = 1000;
  c.mode = lab::TriggerMode::kLevel;
  c.trigger_signal = lab::find_signal("z.pose");
  c.level = 1.0f;  // never reached: the armed steady state
  if (g_rec.configure(c) != lab::RecorderError::kOk || g_rec.arm() != lab::RecorderError::kOk) return 1;
  const kernel::KernelConfig k = kernel::default_kernel_config();
  lab::WaveConfig w{};
  w.shape = lab::WaveShape::kMultisine;
  w.amplitude = 0.1f;
  w.f_start_Hz = 5.0f;
  w.f_end_Hz = 400.0f;
  w.tones = 28;
  if (g_multi.start(w, k) != lab::WaveError::kOk) return 1;
  w.shape = lab::WaveShape::kSine;
  if (g_sine.start(w, k) != lab::WaveError::kOk) return 1;
  w.shape = lab::WaveShape::kSweep;
  w.duration_s = 600.0f;
  if (g_sweep.start(w, k) != lab::WaveError::kOk) return 1;

  systick_start();
  Calibration cal;
  for (int i = 0; i < 4; ++i) {  // the first runs warm QEMU's translation cache
    cal.empty_counts = measure_empty();
    cal.nop_counts = measure_nops();
  }
  Stats idle, rec, multi, sine, sweep;
  for (std::uint32_t n = 0; n < 5000; ++n) {
    g_status.pose.pico[0] = static_cast<std::int64_t>(n) * 1000;
    g_status.coil_current_A[0] = static_cast<float>(n & 7u);
    g_sample.coil_current_adc[0] = static_cast<std::int16_t>(n & 1023u);
    std::uint32_t t0 = systick_now();
    g_idle.sample(g_status, g_sample);
    std::uint32_t t1 = systick_now();
    idle.add(systick_elapsed(t0, t1));
    t0 = systick_now();
    g_rec.sample(g_status, g_sample);
    t1 = systick_now();
    rec.add(systick_elapsed(t0, t1));
    t0 = systick_now();
    g_sink = g_multi.step(true).value;
    t1 = systick_now();
    multi.add(systick_elapsed(t0, t1));
    t0 = systick_now();
    g_sink = g_sine.step(true).value;
    t1 = systick_now();
    sine.add(systick_elapsed(t0, t1));
    t0 = systick_now();
    g_sink = g_sweep.step(true).value;
    t1 = systick_now();
    sweep.add(systick_elapsed(t0, t1));
  }
  if (!icount) {
    hw::semihost_write("lab_tick_instructions: not measured (run QEMU with -icount shift=6 and pass --icount)\n");
    return 0;
  }
  print("recorder_idle", idle, cal);
  print("recorder_8ch_level", rec, cal);
  print("wave_multisine", multi, cal);
  print("wave_sine", sine, cal);
  print("wave_sweep", sweep, cal);
  return 0;
}
