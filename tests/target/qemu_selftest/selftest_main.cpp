// maglev-qemu-selftest: boots on QEMU mps2-an500 and runs every registered
// target test; QEMU's exit status is the number of failed tests.
//
// Command line (qemu ... -append "<words>"): CppUTest-like -v / -g <group>,
// plus --force-failure, which makes harness.forced_failure_is_reported fail.
// The qemu-selftest-failure-exits-nonzero ctest uses it to prove a failing
// case really makes QEMU exit non-zero. --force-fault executes an undefined
// instruction before the tests: the board's fault handler must report it and
// exit with kFaultExitCode (ctest qemu-selftest-fault-exits-nonzero).
#include <cstring>

#include "maglev/board/mps2_an500/semihosting.hpp"
#include "maglev/target_test/target_test.hpp"

namespace {

bool g_force_failure = false;
char g_command_line[256];

bool has_word(const char* text, const char* word) {
  const std::size_t length = std::strlen(word);
  for (const char* p = std::strstr(text, word); p != nullptr; p = std::strstr(p + 1, word)) {
    const bool starts = (p == text) || (p[-1] == ' ');
    const bool ends = (p[length] == '\0') || (p[length] == ' ');
    if (starts && ends) {
      return true;
    }
  }
  return false;
}

}  // namespace

MAGLEV_TARGET_TEST(harness, forced_failure_is_reported) { TT_CHECK(!g_force_failure); }

int main() {
  namespace hw = maglev::board::mps2_an500;
  if (!hw::semihost_command_line(g_command_line, sizeof(g_command_line))) {
    g_command_line[0] = '\0';
  }
  g_force_failure = has_word(g_command_line, "--force-failure");
  hw::semihost_write("maglev-qemu-selftest on mps2-an500 (Cortex-M7)\n");
  if (has_word(g_command_line, "--force-fault")) {
    __asm__ volatile("udf #0");  // UsageFault (escalates to HardFault)
  }
  const auto options = maglev::target_test::parse_options(g_command_line);
  return maglev::target_test::run_all(options);
}
