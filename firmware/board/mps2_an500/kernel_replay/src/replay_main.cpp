// maglev-qemu-kernel-replay: replays recorded servo-tick inputs through
// Controller<float> on the emulated Cortex-M7 and writes every tick's outputs,
// so the host can compare them bit for bit with its own run of the same kernel
// (tests/target/bitexact). Also measures instructions per step() (SysTick in
// QEMU's virtual time; meaningful only under -icount, see docs/PERFORMANCE.md).
//
//   qemu-system-arm -M mps2-an500 -nographic -semihosting-config enable=on,target=native
//                   -kernel maglev-qemu-kernel-replay.elf -append "<vectors.bin> <outputs.bin>"
//   instructions per step(): add `-icount shift=6` and `--icount` after the paths.
//   The fixed-point kernel (Controller<Q7_24>): add `--q7.24` (the vectors
//   must come from `kernel-vector-recorder ... --q7.24`).
//
// Exit status: 0 replayed all ticks; 2 bad command line; 3 cannot open/read the
// vectors; 4 bad header; 5 cannot write the outputs; 6 apply_config refused.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/board/mps2_an500/instruction_counter.hpp"
#include "maglev/board/mps2_an500/instruction_stats.hpp"
#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/kernel_replay/replay_format.hpp"
#include "maglev/kernel_replay/semihost_file.hpp"
#include "maglev/kernel_replay/vectors_file.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

namespace {

namespace hw = maglev::board::mps2_an500;
namespace kr = maglev::kernel_replay;
namespace kernel = maglev::kernel;
namespace stage_profile = maglev::stage_profile;

enum ExitCode : int {
  kOk = 0,
  kBadCommandLine = 2,
  kCannotRead = 3,
  kBadHeader = 4,
  kCannotWrite = 5,
  kConfigRefused = 6,
};

// SysTick as an instruction counter: maglev/board/mps2_an500/instruction_counter.hpp.
using namespace hw::icount;

using Stats = TickStats;  // instruction_stats.hpp, shared with the whole-servo-tick image
void print_stats(const char* label, const Stats& s, const Calibration& cal) {
  print_tick_stats("step_instructions", label, s, cal);
}

// --- command line ------------------------------------------------------------------
char g_command_line[1024];
constexpr int kMaxWords = 5;
const char* g_words[kMaxWords] = {};

// --- buffers and the controller: all static (no heap) -------------------------
constexpr std::size_t kChunkTicks = 64;
std::uint8_t g_input[kChunkTicks * kr::kInputRecordBytes];
std::uint8_t g_output[kChunkTicks * kr::kOutputRecordBytes];
kernel::Controller<float> g_controller;
kernel::Controller<maglev::numeric::Q7_24> g_controller_q7_24;
stage_profile::StageProfile g_profile{};  // static: ~2 kB, not on the stack

int fail(const char* message, int code) {
  hw::semihost_write("kernel-replay: ");
  hw::semihost_write(message);
  hw::semihost_write("\n");
  return code;
}

}  // namespace

template <typename Controller>
int replay(Controller& controller, const char* vectors_path, const char* outputs_path, bool icount) {
  int in = -1;
  kr::InputHeader header{};
  if (const kr::VectorsOpen e = kr::open_vectors(vectors_path, &in, &header); e != kr::VectorsOpen::kOk) {
    const bool unreadable = e == kr::VectorsOpen::kCannotOpen || e == kr::VectorsOpen::kCannotReadHeader;
    return fail(kr::to_string(e), unreadable ? kCannotRead : kBadHeader);
  }
  if (header.profile_bytes != 0U && header.profile_bytes != sizeof(g_profile)) {
    return fail("the stage profile's size differs from this image's StageProfile", kBadHeader);
  }
  // The kernel configuration: the firmware's own profile path (check +
  // MakeKernelConfig) on the recorded profile, or the default.
  kernel::KernelConfig config = kernel::default_kernel_config();
  if (header.profile_bytes != 0U) {
    if (!kr::semihost_read(in, reinterpret_cast<std::uint8_t*>(&g_profile), sizeof(g_profile))) {
      return fail("cannot read the stage profile", kCannotRead);
    }
    const stage_profile::ProfileCheck check = stage_profile::MakeKernelConfig(g_profile, &config);
    if (check.error != stage_profile::ProfileError::kOk) {
      hw::semihost_write("kernel-replay: profile refused: ");
      hw::semihost_write(stage_profile::to_string(check.error));
      hw::semihost_write("\n");
      return fail("the stage profile was refused", kConfigRefused);
    }
    hw::semihost_write("kernel-replay: stage profile ");
    hw::semihost_write(g_profile.name);
    hw::semihost_write("\n");
  }

  const int out = kr::semihost_open(outputs_path, kr::OpenMode::kWriteBinary);
  if (out < 0) return fail("cannot open the outputs file", kCannotWrite);

  // The recorder applies the same configuration; apply it explicitly so a
  // refused config is visible here as well.
  if (controller.apply_config(config) != kernel::ConfigError::kOk) {
    return fail("apply_config refused", kConfigRefused);
  }

  const Calibration cal = start_and_calibrate();

  // Per sequencer state the tick STARTED in (homing's last tick, with its
  // one-off Hall solve, counts as Homing).
  constexpr int kStates = static_cast<int>(kernel::SequencerState::kFault) + 1;
  Stats all, per_state[kStates];
  std::uint32_t tick = 0;
  while (tick < header.tick_count) {
    const std::uint32_t left = header.tick_count - tick;
    const std::size_t n = left < kChunkTicks ? left : kChunkTicks;
    if (!kr::semihost_read(in, g_input, n * kr::kInputRecordBytes)) return fail("short read", kCannotRead);
    for (std::size_t i = 0; i < n; ++i, ++tick) {
      kr::InputRecord r;
      kr::decode_input(&g_input[i * kr::kInputRecordBytes], &r);
      kr::OutputRecord o;
      o.tick = tick;
      if (r.has_command) {
        o.command_result = static_cast<std::uint8_t>(controller.command(r.command));
      }
      const auto state_before = static_cast<int>(controller.status().state);
      const std::uint32_t t0 = systick_now();
      o.actuator = controller.step(r.sample, r.tick_overrun);
      const std::uint32_t t1 = systick_now();
      const std::uint32_t counts = systick_elapsed(t0, t1);
      o.status = &controller.status();
      all.add(counts, tick);
      if (state_before >= 0 && state_before < kStates) per_state[state_before].add(counts, tick);
      kr::encode_output(o, &g_output[i * kr::kOutputRecordBytes]);
      // The board's main loop between ticks (thread mode): homing's Hall
      // solve runs here, not in the timed step() (the same bits either way).
      (void)controller.background();
    }
    if (!kr::semihost_write_file(out, g_output, n * kr::kOutputRecordBytes)) {
      return fail("cannot write the outputs", kCannotWrite);
    }
  }
  kr::semihost_close(out);
  kr::semihost_close(in);

  hw::semihost_write("kernel-replay: replayed ");
  hw::semihost_write_unsigned(tick);
  hw::semihost_write(" ticks, wrote ");
  hw::semihost_write_unsigned(static_cast<std::uint64_t>(tick) * kr::kOutputRecordBytes);
  hw::semihost_write(" output bytes; Hall solves in step(): ");
  hw::semihost_write_unsigned(controller.hall_solves_in_tick());
  hw::semihost_write("\n");
  if (!icount) {
    hw::semihost_write("step_instructions: not measured (run QEMU with -icount shift=6 and pass --icount)\n");
    return kOk;
  }
  hw::semihost_write("systick calibration: empty=");
  hw::semihost_write_unsigned(cal.empty_counts);
  hw::semihost_write(" counts, 4096 nops=");
  hw::semihost_write_unsigned(cal.nop_counts);
  hw::semihost_write(" counts\n");
  print_stats("all", all, cal);
  for (int i = 0; i < kStates; ++i) {
    if (per_state[i].count > 0U) print_stats(kernel::to_string(static_cast<kernel::SequencerState>(i)), per_state[i], cal);
  }
  return kOk;
}

int main() {
  if (!hw::semihost_command_line(g_command_line, sizeof(g_command_line))) {
    return fail("no semihosting command line", kBadCommandLine);
  }
  // "<kernel path> <vectors> <outputs>"
  const int words = kr::split_words(g_command_line, g_words, kMaxWords);
  if (words < 3) {
    return fail("usage: -append \"<vectors.bin> <outputs.bin> [--icount] [--q7.24]\"", kBadCommandLine);
  }
  // SysTick counts are instructions only if QEMU runs with -icount; the caller says so.
  bool icount = false;
  bool q7_24 = false;
  for (int w = 3; w < words && w < kMaxWords; ++w) {
    if (std::strcmp(g_words[w], "--icount") == 0) {
      icount = true;
    } else if (std::strcmp(g_words[w], "--q7.24") == 0) {
      q7_24 = true;
    } else {
      return fail("unknown option (expected --icount or --q7.24)", kBadCommandLine);
    }
  }
  const char* vectors_path = g_words[1];
  const char* outputs_path = g_words[2];

  if (q7_24) hw::semihost_write("kernel-replay: Controller<Q7_24>\n");
  return q7_24 ? replay(g_controller_q7_24, vectors_path, outputs_path, icount)
               : replay(g_controller, vectors_path, outputs_path, icount);
}
