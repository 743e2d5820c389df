// Deliberately too big for DTCM (128 KB): 160 KB of .bss. Linking this with
// linker/stm32h743.ld must fail -- see the stm32h743-linker-overflow-fails test.
#include <cstdint>

// volatile: the stores must stay, so the array stays.
volatile std::uint8_t g_too_big[160 * 1024];

extern "C" void board_early_init() {}
extern "C" void HardFault_Handler() {}
extern "C" void SysTick_Handler() {}
extern "C" void EXTI15_10_IRQHandler() {}
extern "C" void TIM3_IRQHandler() {}

extern "C" void board_main() {
  for (std::uint32_t i = 0; i < sizeof g_too_big; ++i) g_too_big[i] = static_cast<std::uint8_t>(i);
}
