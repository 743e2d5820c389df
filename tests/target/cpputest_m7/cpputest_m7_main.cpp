// Entry point of the kernel's CppUTest suites on QEMU's Cortex-M7: the same
// CommandLineTestRunner as the host (tests/support/cpputest_main.cpp), with
// argv taken from the semihosting command line (qemu ... -append "-v").
// The board's startup calls main() and turns its return value (CppUTest's
// failure count) into QEMU's exit status.
#include <CppUTest/CommandLineTestRunner.h>

#include "maglev/board/mps2_an500/semihosting.hpp"

extern "C" void initialise_monitor_handles(void);  // librdimon: stdout/stderr over semihosting

namespace {
char g_command_line[512];
constexpr int kMaxArgs = 16;
char* g_argv[kMaxArgs + 1];
}  // namespace

int main() {
  initialise_monitor_handles();
  int argc = 0;
  if (maglev::board::mps2_an500::semihost_command_line(g_command_line, sizeof(g_command_line))) {
    // "<kernel path> <args...>": argv[0] is the image path, as on a host.
    char* p = g_command_line;
    while (*p != '\0' && argc < kMaxArgs) {
      while (*p == ' ') ++p;
      if (*p == '\0') break;
      g_argv[argc++] = p;
      while (*p != '\0' && *p != ' ') ++p;
      if (*p == ' ') *p++ = '\0';
    }
  }
  if (argc == 0) {
    static char name[] = "kernel-cpputest-m7";
    g_argv[argc++] = name;
  }
  g_argv[argc] = nullptr;
  return CommandLineTestRunner::RunAllTests(argc, g_argv);
}
