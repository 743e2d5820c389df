// Two AD7606 8-channel 16-bit simultaneous-sampling ADCs on one SPI bus
// (separate CS lines, CONVST A/B of both tied to one timer output, BUSY of
// device 0 on an EXTI line). RANGE pin high: +-10 V input range.
//
// Read sequence (AD7606 datasheet Rev. C, "Conversion control", "Serial
// interface", "Reading during/after conversion"):
//   1. A timer's PWM output drives CONVST A/B; the rising edge starts all 16
//      track-and-holds at the same instant, BUSY goes high (t_CONV ~4 us).
//   2. BUSY falling edge -> the top-priority interrupt -> read().
//   3. Per device: CS low for 128 SCLKs on DOUTA only (with one DOUT line the
//      datasheet recommends DOUTA because it outputs V1..V8 in ascending
//      order; DOUTB would start at V5). CS falling clocks out the MSB, each
//      SCLK RISING edge clocks out the next bit, data is valid on the
//      FALLING edge -> SPI mode 2 (CPOL = 1, CPHA = 0: idle high, sample on
//      the first = falling edge). We clock it as four 32-bit words:
//      word w = V(2w+1) << 16 | V(2w+2).
//   4. Codes are two's complement: 0x7FFF = +FS * 32767/32768, 0x8000 = -FS.
//
// Channel map (ours; docs/PINMAP in firmware/board/stm32h743/README.md):
//   ADC0 V1..V3 : laser displacement sensors 0..2   -> SensorSample::displacement_adc[0..2]
//   ADC0 V4..V7 : Hall A.Bx, A.By, B.Bx, B.By      -> SensorSample::hall_adc[0..3]
//   ADC0 V8     : spare (read, not mapped)
//   ADC1 V1..V8 : coil current monitors i_1..i_8    -> SensorSample::coil_current_adc[0..7]
// Both devices sample simultaneously, so every coil current and every
// position signal of one tick belongs to the same instant.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/bus.hpp"

namespace maglev::drivers::ad7606 {

inline constexpr std::size_t kChannelsPerDevice = 8;
inline constexpr std::size_t kDevices = 2;
inline constexpr std::uint8_t kWordBits = 32;  // two channels per SPI word

// Pinned values (diagnostics).
enum class Status : std::uint8_t {
  kOk = 0,
  kStillBusy = 1,  // BUSY high: the conversion has not finished
  kBusError = 2,   // the SPI (or its DMA) failed: no data
  kNotReady = 3,   // DMA read: none completed since the last read() (not started, still running, or lost)
};

struct Codes {
  std::int16_t channel[kDevices][kChannelsPerDevice];
};

struct State {
  std::uint32_t reads = 0;
  std::uint32_t busy_faults = 0;
  std::uint32_t bus_errors = 0;
  std::uint32_t not_ready = 0;  // DMA read: the tick found no completed read
};

// Channel k (0-based) of one device's raw DOUTA words: word w = V(2w+1) << 16 | V(2w+2).
constexpr std::int16_t channel_code(const std::uint32_t (&rx)[kChannelsPerDevice / 2], std::size_t k) {
  const std::uint32_t word = rx[k / 2];
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(k % 2 == 0 ? word >> 16 : word & 0xFFFFu));
}

// Raw DOUTA words of one device -> codes.
inline void decode_words(const std::uint32_t (&rx)[kChannelsPerDevice / 2], std::int16_t (&channel)[kChannelsPerDevice]) {
  for (std::size_t k = 0; k < kChannelsPerDevice; ++k) channel[k] = channel_code(rx, k);
}

class Adc {
 public:
  // cs_device[d] = the SPI master's chip-select index of ADC d.
  // `rx_buffer` (optional, kDevices x 4 words): where the raw SPI words land
  // (e.g. the non-cacheable D2 SRAM buffer Stm32DmaReader's DMA stream
  // fills, ad7606_stm32_dma.hpp); null: a stack buffer.
  Adc(SpiMaster& spi, const std::uint8_t (&cs_device)[kDevices], InputPin& busy,
      std::uint32_t (*rx_buffer)[kChannelsPerDevice / 2] = nullptr)
      : spi_(spi), busy_(busy), rx_buffer_(rx_buffer) {
    for (std::size_t d = 0; d < kDevices; ++d) cs_[d] = cs_device[d];
  }

  Status read(Codes& out) {
    if (busy_.read()) {  // conversion not finished: never read a half-converted result
      ++state_.busy_faults;
      return Status::kStillBusy;
    }
    for (std::size_t d = 0; d < kDevices; ++d) {
      std::uint32_t local[kChannelsPerDevice / 2];
      std::uint32_t (&rx)[kChannelsPerDevice / 2] = rx_buffer_ != nullptr ? rx_buffer_[d] : local;
      const BusStatus bs = spi_.transfer(SpiTransfer{cs_[d], kWordBits, nullptr, rx, kChannelsPerDevice / 2});
      if (bs != BusStatus::kOk) {
        ++state_.bus_errors;
        return Status::kBusError;
      }
      decode_words(rx, out.channel[d]);
    }
    ++state_.reads;
    return Status::kOk;
  }

  const State& state() const { return state_; }

 private:
  SpiMaster& spi_;
  InputPin& busy_;
  std::uint32_t (*rx_buffer_)[kChannelsPerDevice / 2];
  std::uint8_t cs_[kDevices]{};
  State state_{};
};

// The pair read by DMA before the tick (begin() on BUSY, advance() in the
// DMA interrupt, read() in the tick) is ad7606::Stm32DmaReader, at the
// register level (ad7606_stm32_dma.hpp; README.md "DMA schedule").

// Volts at the ADC input for a code (+-10 V range).
constexpr double code_to_V(std::int16_t code) { return 10.0 * code / 32768.0; }

}  // namespace maglev::drivers::ad7606
