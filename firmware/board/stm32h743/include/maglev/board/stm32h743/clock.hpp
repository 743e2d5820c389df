// STM32H743 clock tree to 480 MHz (RM0433 §8 RCC, §6 PWR; DS12110 table 23
// for VOS0 / 480 MHz, which needs silicon revision V -- the Nucleo-H743ZI2's).
//
//   HSE 8 MHz, BYPASS: the Nucleo-H743ZI2's ST-LINK drives the MCO into
//   PH0-OSC_IN (no crystal fitted by default).
//   PLL1: DIVM1 = 1 -> 8 MHz reference (PLL1RGE = 3: 8..16 MHz), wide VCO,
//         DIVN1 = 120 -> VCO 960 MHz,
//         DIVP1 = 2 -> pll1_p 480 MHz (SYSCLK / CPU),
//         DIVQ1 = 12 -> pll1_q 80 MHz (FDCAN and SPI1/2/3 kernel clock),
//         DIVR1 = 2 -> pll1_r 480 MHz (unused).
//   D1CPRE /1 (CPU 480 MHz), HPRE /2 (AXI/AHB 240 MHz: the 240 MHz bus limit),
//   D1PPRE, D2PPRE1, D2PPRE2, D3PPRE /2 -> every APB 120 MHz; APB timers x2 =
//   240 MHz.
//   Voltage: LDO supply, VOS1 then SYSCFG_PWRCR.ODEN -> VOS0 (required above
//   400 MHz), wait VOSRDY after each step.
//   Flash: 4 wait states, WRHIGHFREQ = 2 (RM0433 table 17: VOS0, 225-240 MHz
//   AXI clock), programmed and read back BEFORE switching SYSCLK to PLL1.
#pragma once

#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::board::stm32h743 {

inline constexpr std::uint32_t kHse_Hz = 8'000'000;
inline constexpr std::uint32_t kDivm1 = 1, kDivn1 = 120, kDivp1 = 2, kDivq1 = 12, kDivr1 = 2;
inline constexpr std::uint32_t kVco_Hz = kHse_Hz / kDivm1 * kDivn1;
inline constexpr std::uint32_t kCpu_Hz = kVco_Hz / kDivp1;        // 480 MHz
inline constexpr std::uint32_t kPll1q_Hz = kVco_Hz / kDivq1;      // 80 MHz
inline constexpr std::uint32_t kAhb_Hz = kCpu_Hz / 2;             // 240 MHz
inline constexpr std::uint32_t kApb_Hz = kAhb_Hz / 2;             // 120 MHz
inline constexpr std::uint32_t kApbTimer_Hz = 2 * kApb_Hz;        // 240 MHz
static_assert(kCpu_Hz == 480'000'000 && kPll1q_Hz == 80'000'000);
static_assert(kVco_Hz >= 192'000'000 && kVco_Hz <= 960'000'000, "wide VCO range");

inline constexpr std::uint32_t kPll1divr =
    (kDivn1 - 1) | ((kDivp1 - 1) << 9) | ((kDivq1 - 1) << 16) | ((kDivr1 - 1) << 24);
static_assert(kPll1divr == 0x010B0277u);
inline constexpr std::uint32_t kFlashAcr = 4u | (2u << stm32h7::flash::kAcrWrhighfreqShift);  // 0x24

enum class ClockStatus : std::uint8_t { kOk = 0, kSupplyNotReady, kVosTimeout, kHseTimeout, kFlashLatency, kPllTimeout, kSwitchTimeout };

template <stm32h7::RegisterBus Bus>
ClockStatus configure_clock_480MHz(Bus& bus, std::uint32_t max_polls = 1'000'000) {
  using namespace stm32h7;
  const Addr rcc_b = rcc::kBase, pwr_b = pwr::kBase;
  // Supply: LDO only (clear SCUEN/BYPASS). CR3 is write-once after reset.
  modify32(bus, pwr_b + pwr::kCr3, pwr::kCr3Scuen | pwr::kCr3Bypass | pwr::kCr3Ldoen, pwr::kCr3Ldoen);
  if (!wait_for(bus, pwr_b + pwr::kCsr1, pwr::kCsr1Actvosrdy, pwr::kCsr1Actvosrdy, max_polls)) {
    return ClockStatus::kSupplyNotReady;
  }
  // VOS1, then overdrive -> VOS0.
  modify32(bus, pwr_b + pwr::kD3cr, 3u << pwr::kD3crVosShift, 3u << pwr::kD3crVosShift);
  if (!wait_for(bus, pwr_b + pwr::kD3cr, pwr::kD3crVosrdy, pwr::kD3crVosrdy, max_polls)) return ClockStatus::kVosTimeout;
  modify32(bus, rcc_b + rcc::kApb4enr, 0u, bit(1));  // SYSCFGEN
  (void)bus.read32(rcc_b + rcc::kApb4enr);           // read back: clock enable has taken effect
  modify32(bus, syscfg::kBase + syscfg::kPwrcr, 0u, syscfg::kPwrcrOden);
  if (!wait_for(bus, pwr_b + pwr::kD3cr, pwr::kD3crVosrdy, pwr::kD3crVosrdy, max_polls)) return ClockStatus::kVosTimeout;

  // HSE from the ST-LINK MCO.
  modify32(bus, rcc_b + rcc::kCr, 0u, rcc::kCrHsebyp | rcc::kCrHseon);
  if (!wait_for(bus, rcc_b + rcc::kCr, rcc::kCrHserdy, rcc::kCrHserdy, max_polls)) return ClockStatus::kHseTimeout;

  // PLL1.
  modify32(bus, rcc_b + rcc::kPllckselr, 0x3u | (0x3Fu << rcc::kDivm1Shift),
           rcc::kPllsrcHse | (kDivm1 << rcc::kDivm1Shift));
  modify32(bus, rcc_b + rcc::kPllcfgr, 0xFu, 3u << rcc::kPll1rgeShift);  // FRACEN 0, wide VCO, 8..16 MHz
  modify32(bus, rcc_b + rcc::kPllcfgr, 0u, rcc::kDivp1en | rcc::kDivq1en | rcc::kDivr1en);
  bus.write32(rcc_b + rcc::kPll1divr, kPll1divr);
  modify32(bus, rcc_b + rcc::kCr, 0u, rcc::kCrPll1on);
  if (!wait_for(bus, rcc_b + rcc::kCr, rcc::kCrPll1rdy, rcc::kCrPll1rdy, max_polls)) return ClockStatus::kPllTimeout;

  // Bus prescalers before the switch so no bus ever exceeds its limit.
  bus.write32(rcc_b + rcc::kD1cfgr, rcc::kHpreDiv2 | (rcc::kPpreDiv2 << 4));  // D1CPRE /1, HPRE /2, D1PPRE /2
  bus.write32(rcc_b + rcc::kD2cfgr, (rcc::kPpreDiv2 << 4) | (rcc::kPpreDiv2 << 8));
  bus.write32(rcc_b + rcc::kD3cfgr, rcc::kPpreDiv2 << 4);

  // Flash wait states first, verified.
  bus.write32(flash::kBase + flash::kAcr, kFlashAcr);
  if ((bus.read32(flash::kBase + flash::kAcr) & 0x3Fu) != kFlashAcr) return ClockStatus::kFlashLatency;

  modify32(bus, rcc_b + rcc::kCfgr, rcc::kCfgrSwMask, rcc::kSwPll1);
  if (!wait_for(bus, rcc_b + rcc::kCfgr, rcc::kCfgrSwMask << rcc::kCfgrSwsShift, rcc::kSwPll1 << rcc::kCfgrSwsShift,
                max_polls)) {
    return ClockStatus::kSwitchTimeout;
  }
  // Kernel clocks: FDCAN <- pll1_q (01); SPI1/2/3 <- pll1_q (000, reset value);
  // USART2 <- pclk1 (000, reset value).
  modify32(bus, rcc_b + rcc::kD2ccip1r, (0x3u << rcc::kFdcanselShift) | (0x7u << rcc::kSpi123selShift),
           1u << rcc::kFdcanselShift);
  return ClockStatus::kOk;
}

}  // namespace maglev::board::stm32h743
