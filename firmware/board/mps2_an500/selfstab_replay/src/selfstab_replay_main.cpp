// maglev-qemu-selfstab-replay: replays recorded PSD codes and commands
// through the selfstab kernel (paper 001) on the emulated Cortex-M7 and
// writes every tick's outputs, for the host's bit-for-bit comparison
// (tests/target/bitexact, selfstab-bitexact-qemu-m7). The kernel's
// configuration is built from the recorded stage profile by the firmware's
// own MakeSelfstabKernelConfig.
//
//   qemu-system-arm -M mps2-an500 -nographic -semihosting-config enable=on,target=native
//                   -kernel maglev-qemu-selfstab-replay.elf -append "<vectors.bin> <outputs.bin>"
//
// Exit status: 0 replayed all ticks; 2 bad command line; 3 cannot open/read
// the vectors; 4 bad header; 5 cannot write the outputs; 6 profile or
// configuration refused.
#include <cstddef>
#include <cstdint>

#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/kernel_replay/semihost_file.hpp"
#include "maglev/selfstab_replay/selfstab_replay_format.hpp"
#include "maglev/stage_profile/selfstab_config.hpp"

namespace {

namespace hw = maglev::board::mps2_an500;
namespace kr = maglev::kernel_replay;
namespace sr = maglev::selfstab_replay;
namespace ss = maglev::selfstab;
namespace sp = maglev::stage_profile;

char g_command_line[1024];
const char* g_words[4] = {};
int split_words(char* text) {
  int n = 0;
  char* p = text;
  while (*p != '\0' && n < 4) {
    while (*p == ' ') ++p;
    if (*p == '\0') break;
    g_words[n++] = p;
    while (*p != '\0' && *p != ' ') ++p;
    if (*p == ' ') *p++ = '\0';
  }
  return n;
}

constexpr std::size_t kChunkTicks = 64;
std::uint8_t g_input[kChunkTicks * sr::kInputRecordBytes];
std::uint8_t g_output[kChunkTicks * sr::kOutputRecordBytes];
sp::StageProfile g_profile{};
ss::SelfstabKernelConfig g_config{};
ss::SelfstabKernel g_kernel;

int fail(const char* message, int code) {
  hw::semihost_write("selfstab-replay: ");
  hw::semihost_write(message);
  hw::semihost_write("\n");
  return code;
}

}  // namespace

int main() {
  if (!hw::semihost_command_line(g_command_line, sizeof(g_command_line))) return fail("no command line", 2);
  if (split_words(g_command_line) < 3) return fail("usage: -append \"<vectors.bin> <outputs.bin>\"", 2);
  const int in = kr::semihost_open(g_words[1], kr::OpenMode::kReadBinary);
  if (in < 0) return fail("cannot open the vectors file", 3);
  const long length = kr::semihost_file_length(in);
  std::uint8_t hb[sr::kHeaderBytes];
  sr::Header h{};
  if (!kr::semihost_read(in, hb, sizeof hb)) return fail("cannot read the header", 3);
  if (!sr::decode_header(hb, &h) || h.profile_bytes != sizeof(g_profile)) {
    return fail("bad header (magic, version or StageProfile size differ from this image)", 4);
  }
  const auto expected = static_cast<long>(sr::kHeaderBytes + h.profile_bytes +
                                          static_cast<std::size_t>(h.tick_count) * sr::kInputRecordBytes);
  if (length != expected) return fail("vectors file length does not match its header", 4);
  if (!kr::semihost_read(in, reinterpret_cast<std::uint8_t*>(&g_profile), sizeof g_profile)) {
    return fail("cannot read the stage profile", 3);
  }
  const sp::ProfileError e = sp::MakeSelfstabKernelConfig(g_profile, &g_config);
  if (e != sp::ProfileError::kOk) {
    hw::semihost_write(sp::to_string(e));
    return fail(": the stage profile was refused", 6);
  }
  if (g_kernel.configure(g_config) != ss::SelfstabConfigError::kOk) return fail("configure refused", 6);
  hw::semihost_write("selfstab-replay: stage profile ");
  hw::semihost_write(g_profile.name);
  hw::semihost_write("\n");
  const int out = kr::semihost_open(g_words[2], kr::OpenMode::kWriteBinary);
  if (out < 0) return fail("cannot open the outputs file", 5);
  std::uint32_t tick = 0;
  while (tick < h.tick_count) {
    const std::uint32_t left = h.tick_count - tick;
    const std::size_t n = left < kChunkTicks ? left : kChunkTicks;
    if (!kr::semihost_read(in, g_input, n * sr::kInputRecordBytes)) return fail("short read", 3);
    for (std::size_t i = 0; i < n; ++i, ++tick) {
      sr::InputRecord r{};
      sr::decode_input(&g_input[i * sr::kInputRecordBytes], &r);
      const ss::SelfstabResult res = sr::apply_command(g_kernel, r);
      const ss::SelfstabCoilCommand c = g_kernel.tick(r.sample);
      sr::encode_output(tick, res, c, g_kernel.telemetry(), &g_output[i * sr::kOutputRecordBytes]);
    }
    if (!kr::semihost_write_file(out, g_output, n * sr::kOutputRecordBytes)) return fail("cannot write", 5);
  }
  kr::semihost_close(out);
  kr::semihost_close(in);
  hw::semihost_write("selfstab-replay: replayed ");
  hw::semihost_write_unsigned(tick);
  hw::semihost_write(" ticks\n");
  return 0;
}
