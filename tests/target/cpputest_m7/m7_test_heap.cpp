// Heap for the CppUTest images (NOT firmware: firmware has no heap). The board's
// linker script places `end` above the main stack (linker/mps2-an500.ld), so
// librdimon's default _sbrk, which refuses to grow the heap past the stack
// pointer, would fail every allocation. This _sbrk hands out RAM from `end` to
// the top of the 4 MiB SSRAM2&3 region instead.
#include <cerrno>
#include <cstddef>
#include <cstdint>

extern "C" {
extern char end;  // linker script: first byte after .stack
void* _sbrk(std::ptrdiff_t increment);
}

namespace {
constexpr std::uintptr_t kRamEnd = 0x20000000U + 4U * 1024U * 1024U;
char* g_break = nullptr;
}  // namespace

extern "C" void* _sbrk(std::ptrdiff_t increment) {
  if (g_break == nullptr) {
    g_break = &end;
  }
  const auto next = reinterpret_cast<std::uintptr_t>(g_break) + static_cast<std::uintptr_t>(increment);
  if (increment < 0 || next > kRamEnd) {
    errno = ENOMEM;
    return reinterpret_cast<void*>(-1);
  }
  char* previous = g_break;
  g_break += increment;
  return previous;
}
