// Heap for the CppUTest images (NOT firmware: firmware has no heap). The board's
// linker script places `end` above the main stack (linker/mps2-an500.ld), so
// librdimon's default _sbrk, which refuses to grow the heap past the stack
// pointer, would fail every allocation. This _sbrk hands out the board's
// 16 MiB PSRAM (0x60000000, unused by the images) instead: the closed-loop
// suite keeps ~12 MB of per-tick vectors (100 000 ticks), more than the 4 MiB
// SSRAM.
#include <cerrno>
#include <cstddef>
#include <cstdint>

extern "C" void* _sbrk(std::ptrdiff_t increment);

namespace {
constexpr std::uintptr_t kHeapBegin = 0x60000000U;  // PSRAM (QEMU mps2-an500)
constexpr std::uintptr_t kHeapEnd = kHeapBegin + 16U * 1024U * 1024U;
char* g_break = nullptr;
}  // namespace

extern "C" void* _sbrk(std::ptrdiff_t increment) {
  if (g_break == nullptr) {
    g_break = reinterpret_cast<char*>(kHeapBegin);
  }
  const auto next = reinterpret_cast<std::uintptr_t>(g_break) + static_cast<std::uintptr_t>(increment);
  if (increment < 0 || next > kHeapEnd) {
    errno = ENOMEM;
    return reinterpret_cast<void*>(-1);
  }
  char* previous = g_break;
  g_break += increment;
  return previous;
}
