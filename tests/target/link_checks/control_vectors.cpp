// Minimal vector table for the no-heap control images: they are only linked
// and inspected, never run, but must be complete, well-formed images.
#include <cstdint>

extern "C" {
extern std::uint32_t __stack_top__[];
int maglev_control_main() __asm__("main");
[[noreturn]] void Reset_Handler();
void Reset_Handler() {
  static_cast<void>(maglev_control_main());
  for (;;) {
  }
}
using VectorEntry = void (*)();
[[gnu::used, gnu::section(".isr_vector")]] const VectorEntry g_control_vectors[2] = {
    reinterpret_cast<VectorEntry>(__stack_top__), Reset_Handler};
}
