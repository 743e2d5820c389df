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
#include "lab_tick_setup.hpp"

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

// SysTick counts around one call.
template <typename F>
void measure(Stats& s, F f) {
  const std::uint32_t t0 = systick_now();
  f();
  const std::uint32_t t1 = systick_now();
  s.add(systick_elapsed(t0, t1));
}

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
  if (!lab::setup_lab_tick_scenario(g_rec, g_multi, g_sine, g_sweep)) return 1;

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
    measure(idle, [] { g_idle.sample(g_status, g_sample); });
    measure(rec, [] { g_rec.sample(g_status, g_sample); });
    measure(multi, [] { g_sink = g_multi.step(true).value; });
    measure(sine, [] { g_sink = g_sine.step(true).value; });
    measure(sweep, [] { g_sink = g_sweep.step(true).value; });
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
