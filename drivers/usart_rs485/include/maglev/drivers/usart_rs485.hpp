// USART in RS-485 mode for Modbus RTU (RM0433 §48.5.20 "RS485 driver enable").
//
// The transceiver's DE pin is the USART's RTS/DE pin with CR3.DEM = 1, so the
// HARDWARE times the driver enable: DE rises DEAT sample times (1/16 bit at
// OVER8 = 0) before the start bit of the first character and falls DEDT
// sample times after the stop bit of the last one. No software turnaround
// timing, no GPIO race with the servo interrupt. DEAT/DEDT are 5-bit fields
// of CR1 that can only be written while UE = 0.
//
// Framing: 8 data bits + even parity (M0 = 1 for 9-bit word incl. parity,
// PCE = 1, PS = 0) + 1 stop, the Modbus RTU default. The receiver timeout
// (CR2.RTOEN, RTOR in bit times) marks the Modbus t3.5 end-of-frame gap:
// 3.5 characters x 11 bits = 38.5 -> 39 bits up to 19200 baud, fixed 1.75 ms
// above (Modbus over serial line V1.02 §2.5.1.1).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers::rs485 {

constexpr std::uint32_t brr_value(std::uint32_t kernel_Hz, std::uint32_t baud) {
  return (kernel_Hz + baud / 2) / baud;  // OVER8 = 0: USARTDIV = f_ck / baud, rounded
}
// A time in ns as a count of 1/16-bit sample times, rounded up, capped at 31.
constexpr std::uint32_t de_sample_times(std::uint32_t time_ns, std::uint32_t baud) {
  const std::uint64_t n = (static_cast<std::uint64_t>(time_ns) * baud * 16 + 999'999'999u) / 1'000'000'000u;
  return n > 31 ? 31u : static_cast<std::uint32_t>(n);
}
constexpr std::uint32_t modbus_t35_bits(std::uint32_t baud) {
  return baud > 19200 ? static_cast<std::uint32_t>((1750ull * baud + 999'999u) / 1'000'000u) : 39u;
}

struct Config {
  stm32h7::Addr base = stm32h7::usart::kUsart3;
  std::uint32_t kernel_Hz = 120'000'000;  // rcc_pclk1
  std::uint32_t baud = 115'200;
  std::uint32_t de_assert_ns = 1'000;    // transceiver driver-enable time (datasheet t_ZH/t_ZL) + margin
  std::uint32_t de_deassert_ns = 1'000;  // hold DE after the stop bit
};

struct Counters {
  std::uint32_t tx_bytes = 0;
  std::uint32_t rx_bytes = 0;
  std::uint32_t parity_errors = 0;
  std::uint32_t framing_errors = 0;
  std::uint32_t noise_errors = 0;
  std::uint32_t overruns = 0;
  std::uint32_t tx_timeouts = 0;
};

template <stm32h7::RegisterBus Bus>
class UsartRs485 {
 public:
  UsartRs485(Bus& bus, const Config& config) : bus_(bus), config_(config) {}

  void init() {
    namespace u = stm32h7::usart;
    write(u::kCr1, 0u);  // UE = 0: DEAT/DEDT and framing writable
    write(u::kBrr, brr_value(config_.kernel_Hz, config_.baud));
    write(u::kCr2, u::kCr2Rtoen);
    write(u::kRtor, modbus_t35_bits(config_.baud));
    write(u::kCr3, u::kCr3Dem);  // DEP = 0: DE active high
    const std::uint32_t cr1 = stm32h7::field(de_sample_times(config_.de_assert_ns, config_.baud), u::kCr1DeatShift) |
                              stm32h7::field(de_sample_times(config_.de_deassert_ns, config_.baud), u::kCr1DedtShift) |
                              u::kCr1M0 | u::kCr1Pce | u::kCr1Te | u::kCr1Re;
    write(u::kCr1, cr1);
    write(u::kCr1, cr1 | u::kCr1Ue);
  }

  // Blocking transmit of one Modbus frame; returns false on a stuck TXE/TC.
  bool transmit(const std::uint8_t* data, std::size_t n, std::uint32_t max_polls = 100000) {
    namespace u = stm32h7::usart;
    for (std::size_t i = 0; i < n; ++i) {
      if (!stm32h7::wait_for(bus_, config_.base + u::kIsr, u::kIsrTxe, u::kIsrTxe, max_polls)) {
        ++counters_.tx_timeouts;
        return false;
      }
      write(u::kTdr, data[i]);
      ++counters_.tx_bytes;
    }
    if (!stm32h7::wait_for(bus_, config_.base + u::kIsr, u::kIsrTc, u::kIsrTc, max_polls)) {
      ++counters_.tx_timeouts;
      return false;
    }
    return true;
  }

  // Non-blocking: one received byte, errors counted and cleared.
  bool receive_byte(std::uint8_t& byte) {
    namespace u = stm32h7::usart;
    const std::uint32_t isr = bus_.read32(config_.base + u::kIsr);
    const std::uint32_t errors = isr & (u::kIsrPe | u::kIsrFe | u::kIsrNe | u::kIsrOre);
    if (errors != 0) {
      counters_.parity_errors += (isr & u::kIsrPe) != 0 ? 1u : 0u;
      counters_.framing_errors += (isr & u::kIsrFe) != 0 ? 1u : 0u;
      counters_.noise_errors += (isr & u::kIsrNe) != 0 ? 1u : 0u;
      counters_.overruns += (isr & u::kIsrOre) != 0 ? 1u : 0u;
      write(u::kIcr, errors);  // PECF/FECF/NECF/ORECF share the ISR bit positions
    }
    if ((isr & u::kIsrRxne) == 0) return false;
    byte = static_cast<std::uint8_t>(bus_.read32(config_.base + u::kRdr) & 0xFFu);
    ++counters_.rx_bytes;
    return true;
  }

  // True once per received frame: the line has been idle for t3.5.
  bool frame_gap_elapsed() {
    namespace u = stm32h7::usart;
    if ((bus_.read32(config_.base + u::kIsr) & u::kIsrRtof) == 0) return false;
    write(u::kIcr, u::kIsrRtof);  // RTOCF
    return true;
  }

  const Counters& counters() const { return counters_; }

 private:
  void write(stm32h7::Addr offset, std::uint32_t v) { bus_.write32(config_.base + offset, v); }
  Bus& bus_;
  Config config_;
  Counters counters_{};
};

}  // namespace maglev::drivers::rs485
