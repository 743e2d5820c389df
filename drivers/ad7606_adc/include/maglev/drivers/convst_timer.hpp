// The servo clock: a timer whose PWM output drives AD7606 CONVST A/B. Every
// period the output rises (PWM mode 1: high while CNT < CCR1), which starts a
// conversion; its high time is the CONVST pulse. Register-level (RM0433
// §38 TIM1/TIM8): PSC/ARR from the timer kernel clock and the servo rate,
// CCMR1.OC1M = PWM mode 1 with preload, CCER.CC1E, BDTR.MOE (advanced timer),
// EGR.UG to load the preloads, CR1.ARPE|CEN.
#pragma once

#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers {

struct ConvstTiming {
  std::uint32_t psc;
  std::uint32_t arr;
  std::uint32_t ccr;
};

// Smallest prescaler that fits a 16-bit ARR; CCR = pulse width (>= 1 count).
constexpr ConvstTiming convst_timing(std::uint32_t timer_clock_Hz, std::uint32_t rate_Hz, std::uint32_t pulse_ns) {
  const std::uint32_t ticks = timer_clock_Hz / rate_Hz;
  const std::uint32_t psc = (ticks - 1u) / 65536u;
  const std::uint32_t counter_Hz = timer_clock_Hz / (psc + 1u);
  const std::uint32_t arr = ticks / (psc + 1u) - 1u;
  std::uint64_t ccr = (static_cast<std::uint64_t>(counter_Hz) * pulse_ns + 999999999u) / 1000000000u;
  if (ccr == 0) ccr = 1;
  return ConvstTiming{psc, arr, static_cast<std::uint32_t>(ccr)};
}

template <stm32h7::RegisterBus Bus>
void start_convst_timer(Bus& bus, stm32h7::Addr tim, const ConvstTiming& t) {
  namespace r = stm32h7::tim;
  bus.write32(tim + r::kCr1, 0u);
  bus.write32(tim + r::kPsc, t.psc);
  bus.write32(tim + r::kArr, t.arr);
  bus.write32(tim + r::kCcr1, t.ccr);
  bus.write32(tim + r::kCcmr1, stm32h7::field(6u, 4) | stm32h7::bit(3));  // OC1M = 0110 PWM1, OC1PE
  bus.write32(tim + r::kCcer, stm32h7::bit(0));                            // CC1E, active high
  bus.write32(tim + r::kBdtr, r::kBdtrMoe);
  bus.write32(tim + r::kEgr, stm32h7::bit(0));  // UG: load PSC/ARR/CCR preloads now
  bus.write32(tim + r::kCr1, r::kCr1Arpe | r::kCr1Cen);
}

}  // namespace maglev::drivers
