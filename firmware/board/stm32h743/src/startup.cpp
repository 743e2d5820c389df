// STM32H743 startup: vector table, reset handler, fault handler.
//
// Reset_Handler order matters:
//   1. FPU on (CPACR CP10/CP11 full access) before any code that may use it;
//   2. copy .data (flash -> DTCM) and .itcm_text (flash -> ITCM), zero .bss,
//      .axi_bss and .dma_bss (the backup-SRAM fault log is NOT zeroed: it
//      must survive the reset it explains);
//   3. clocks to 480 MHz, MPU, caches (board_early_init, main.cpp);
//   4. static constructors (.init_array), then main().
#include <cstdint>

#include "maglev/stm32h7/registers.hpp"

extern "C" {
extern std::uint32_t __stack_top;
extern std::uint32_t __data_start, __data_end, __data_load;
extern std::uint32_t __itcm_start, __itcm_end, __itcm_load;
extern std::uint32_t __bss_start, __bss_end;
extern std::uint32_t __axi_bss_start, __axi_bss_end;
extern std::uint32_t __dma_bss_start, __dma_bss_end;
using InitFunction = void (*)();
extern InitFunction __init_array_start[], __init_array_end[];

void board_main();
void board_early_init();
[[noreturn]] void Reset_Handler();
void Default_Handler();
void HardFault_Handler();
void SysTick_Handler();
// Servo/encoder interrupts: each image defines the ones it enables
// (production: EXTI15_10 + DMA1_Stream0 + TIM3 + SPI1, HIL: TIM2); the others stay Default_Handler.
void EXTI15_10_IRQHandler() __attribute__((weak, alias("Default_Handler")));
void DMA1_Stream0_IRQHandler() __attribute__((weak, alias("Default_Handler")));
void TIM3_IRQHandler() __attribute__((weak, alias("Default_Handler")));
void TIM2_IRQHandler() __attribute__((weak, alias("Default_Handler")));
void SPI1_IRQHandler() __attribute__((weak, alias("Default_Handler")));
}

namespace {

inline void copy_words(std::uint32_t* dst, const std::uint32_t* end, const std::uint32_t* src) {
  while (dst < end) *dst++ = *src++;
}
inline void zero_words(std::uint32_t* dst, const std::uint32_t* end) {
  while (dst < end) *dst++ = 0;
}

using Handler = void (*)();
constexpr int kVectors = 16 + maglev::stm32h7::irq::kCount;
struct VectorTable {
  const void* initial_sp;
  Handler handlers[kVectors - 1];  // handlers[v - 1] is exception/vector number v
};

constexpr VectorTable make_vector_table() {
  VectorTable t{&__stack_top, {}};
  for (Handler& h : t.handlers) h = Default_Handler;
  t.handlers[1 - 1] = Reset_Handler;
  t.handlers[2 - 1] = Default_Handler;    // NMI
  t.handlers[3 - 1] = HardFault_Handler;
  t.handlers[4 - 1] = HardFault_Handler;  // MemManage (not enabled separately: escalates)
  t.handlers[5 - 1] = HardFault_Handler;  // BusFault
  t.handlers[6 - 1] = HardFault_Handler;  // UsageFault
  for (int v = 7; v <= 10; ++v) t.handlers[v - 1] = nullptr;  // reserved
  t.handlers[13 - 1] = nullptr;
  t.handlers[15 - 1] = SysTick_Handler;
  t.handlers[16 + maglev::stm32h7::irq::kExti15_10 - 1] = EXTI15_10_IRQHandler;
  t.handlers[16 + maglev::stm32h7::irq::kDma1Stream0 - 1] = DMA1_Stream0_IRQHandler;
  t.handlers[16 + maglev::stm32h7::irq::kTim3 - 1] = TIM3_IRQHandler;
  t.handlers[16 + maglev::stm32h7::irq::kTim2 - 1] = TIM2_IRQHandler;
  t.handlers[16 + maglev::stm32h7::irq::kSpi1 - 1] = SPI1_IRQHandler;
  return t;
}

}  // namespace

extern "C" {

[[gnu::section(".isr_vector"), gnu::used]] constinit const VectorTable g_vector_table = make_vector_table();

[[noreturn]] void Reset_Handler() {
  using maglev::stm32h7::scb::kBase;
  using maglev::stm32h7::scb::kCpacr;
  *reinterpret_cast<volatile std::uint32_t*>(kBase + kCpacr) |= 0xFu << 20;
  __asm__ volatile("dsb 0xF\n isb 0xF" ::: "memory");

  copy_words(&__data_start, &__data_end, &__data_load);
  copy_words(&__itcm_start, &__itcm_end, &__itcm_load);
  zero_words(&__bss_start, &__bss_end);
  zero_words(&__axi_bss_start, &__axi_bss_end);
  zero_words(&__dma_bss_start, &__dma_bss_end);
  __asm__ volatile("dsb 0xF\n isb 0xF" ::: "memory");  // ITCM code visible to fetch

  board_early_init();

  for (InitFunction* f = __init_array_start; f < __init_array_end; ++f) (*f)();
  board_main();
  for (;;) {
  }
}

void Default_Handler() {
  for (;;) {
  }
}

}  // extern "C"
