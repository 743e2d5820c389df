// maglev-qemu-pmlsm-replay: paper 002's PmlsmController replayed tick by
// tick on QEMU's Cortex-M7 from vectors the host bench recorded
// (`maglev-hil record-pmlsm`), writing every tick's outputs for the host's
// bit-for-bit comparison (tests/target/bitexact, ctest
// kernel-bitexact-qemu-m7-fmp2009-pmlsm). With -icount and --icount it also
// prints instructions per step().
//
//   qemu-system-arm -M mps2-an500 -nographic -semihosting-config enable=on,target=native
//                   -kernel maglev-qemu-pmlsm-replay.elf -append "<vectors.bin> <outputs.bin> [--icount]"
//
// Exit status: 0 replayed all ticks; 2 bad command line; 3 cannot read the
// vectors; 4 bad header; 5 cannot write the outputs; 6 apply_config refused.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/board/mps2_an500/instruction_counter.hpp"
#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/kernel_replay/semihost_file.hpp"
#include "maglev/pmlsm_replay/pmlsm_replay_format.hpp"

namespace {

namespace hw = maglev::board::mps2_an500;
namespace kr = maglev::kernel_replay;
namespace pr = maglev::pmlsm_replay;
namespace ps = maglev::pmlsm_stage;
using namespace hw::icount;

enum ExitCode : int { kOk = 0, kBadCommandLine = 2, kCannotRead = 3, kBadHeader = 4, kCannotWrite = 5, kConfigRefused = 6 };

char g_command_line[1024];
const char* g_words[4] = {};
constexpr std::size_t kChunk = 64;
pr::InputRecord g_in[kChunk];
pr::OutputRecord g_out[kChunk];
ps::PmlsmKernelConfig g_config;
ps::PmlsmController g_controller;

int fail(const char* message, int code) {
  hw::semihost_write("pmlsm-replay: ");
  hw::semihost_write(message);
  hw::semihost_write("\n");
  return code;
}

}  // namespace

int main() {
  if (!hw::semihost_command_line(g_command_line, sizeof(g_command_line)) || kr::split_words(g_command_line, g_words, 4) < 3) {
    return fail("usage: -append \"<vectors.bin> <outputs.bin> [--icount]\"", kBadCommandLine);
  }
  const bool icount = g_words[3] != nullptr && std::strcmp(g_words[3], "--icount") == 0;
  const int in = kr::semihost_open(g_words[1], kr::OpenMode::kReadBinary);
  if (in < 0) return fail("cannot open the vectors file", kCannotRead);
  const long length = kr::semihost_file_length(in);
  pr::Header h{};
  if (!kr::semihost_read(in, &h, sizeof h)) return fail("cannot read the header", kCannotRead);
  if (std::memcmp(h.magic, pr::kMagic, sizeof h.magic) != 0 || h.config_bytes != sizeof g_config) {
    return fail("bad header (magic or configuration size differ from this image)", kBadHeader);
  }
  const long expected = static_cast<long>(sizeof h + sizeof g_config + std::size_t{h.tick_count} * sizeof(pr::InputRecord));
  if (length != expected) return fail("vectors file length does not match its header", kBadHeader);
  if (!kr::semihost_read(in, &g_config, sizeof g_config)) return fail("cannot read the configuration", kCannotRead);
  if (g_controller.apply_config(g_config) != ps::PmlsmConfigError::kOk) return fail("apply_config refused", kConfigRefused);
  const int out = kr::semihost_open(g_words[2], kr::OpenMode::kWriteBinary);
  if (out < 0) return fail("cannot open the outputs file", kCannotWrite);

  systick_start();
  Calibration cal;
  for (int i = 0; i < 4; ++i) {
    cal.empty_counts = measure_empty();
    cal.nop_counts = measure_nops();
  }
  std::uint64_t n_ready = 0, sum_ready = 0, max_ready = 0, min_ready = ~std::uint64_t{0};
  std::uint32_t tick = 0;
  while (tick < h.tick_count) {
    const std::uint32_t left = h.tick_count - tick;
    const std::size_t n = left < kChunk ? left : kChunk;
    if (!kr::semihost_read(in, g_in, n * sizeof(pr::InputRecord))) return fail("short read", kCannotRead);
    for (std::size_t i = 0; i < n; ++i, ++tick) {
      std::uint8_t result = 255;
      if (g_in[i].has_command != 0U) result = static_cast<std::uint8_t>(g_controller.command(g_in[i].command));
      const bool ready = g_controller.status().state == ps::StageState::kReady;
      const std::uint32_t t0 = systick_now();
      const ps::ActuatorCommand a = g_controller.step(g_in[i].sample);
      const std::uint32_t counts = systick_elapsed(t0, systick_now());
      if (ready) {
        ++n_ready;
        sum_ready += counts;
        if (counts > max_ready) max_ready = counts;
        if (counts < min_ready) min_ready = counts;
      }
      g_out[i] = pr::make_output(a, g_controller.status(), result);
    }
    if (!kr::semihost_write_file(out, g_out, n * sizeof(pr::OutputRecord))) return fail("cannot write", kCannotWrite);
  }
  kr::semihost_close(out);
  kr::semihost_close(in);
  hw::semihost_write("pmlsm-replay: replayed ");
  hw::semihost_write_unsigned(tick);
  hw::semihost_write(" ticks\n");
  if (icount && n_ready > 0U) {
    hw::semihost_write("step_instructions ready: ticks=");
    hw::semihost_write_unsigned(n_ready);
    hw::semihost_write(" min=");
    hw::semihost_write_unsigned(cal.instructions(min_ready));
    hw::semihost_write(" mean=");
    hw::semihost_write_unsigned(cal.instructions(sum_ready / n_ready));
    hw::semihost_write(" max=");
    hw::semihost_write_unsigned(cal.instructions(max_ready));
    hw::semihost_write("\n");
  }
  return kOk;
}
