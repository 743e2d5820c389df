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

// Raw DOUTA words of one device -> codes: word w = V(2w+1) << 16 | V(2w+2).
inline void decode_words(const std::uint32_t (&rx)[kChannelsPerDevice / 2], std::int16_t (&channel)[kChannelsPerDevice]) {
  for (std::size_t w = 0; w < kChannelsPerDevice / 2; ++w) {
    channel[2 * w] = static_cast<std::int16_t>(static_cast<std::uint16_t>(rx[w] >> 16));
    channel[2 * w + 1] = static_cast<std::int16_t>(static_cast<std::uint16_t>(rx[w] & 0xFFFFu));
  }
}

class Adc {
 public:
  // cs_device[d] = the SPI master's chip-select index of ADC d.
  // `rx_buffer` (optional, kDevices x 4 words): where the raw SPI words land.
  // The board passes a buffer in non-cacheable D2 SRAM, the same one a DMA
  // stream fills in the DMA variant of the read; null: a stack buffer.
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

// The pair read by DMA (drivers/ad7606_adc/README.md "DMA schedule"): the
// CPU never waits on the 2 x 128 SCLKs.
//   BUSY falls      -> begin():   ADC0's 4 words started (CS0 low, SPI RX DMA);
//   DMA interrupt   -> advance(): ADC0 done -> CS0 high, ADC1 started -> kNextDevice;
//                                 ADC1 done -> kComplete (or kError): run the tick;
//   the servo tick  -> read():    decodes the completed buffer, ONCE.
// read() returns kNotReady unless exactly one complete pair was read since
// the last read(): a read not started, still running (then cancelled) or
// failed is sensor loss, never the previous tick's words again.
class DmaReader {
 public:
  enum class Step : std::uint8_t { kNextDevice = 0, kComplete = 1, kBusy = 2, kError = 3, kIdle = 4 };

  // `rx_buffer`: kDevices x 4 words the DMA can reach (board: D2 SRAM).
  DmaReader(AsyncSpiMaster& spi, const std::uint8_t (&cs_device)[kDevices], InputPin& busy,
            std::uint32_t (*rx_buffer)[kChannelsPerDevice / 2])
      : spi_(spi), busy_(busy), rx_buffer_(rx_buffer) {
    for (std::size_t d = 0; d < kDevices; ++d) cs_[d] = cs_device[d];
  }

  // BUSY fell. A read still under way (its tick never ran) is cancelled and
  // counted; this conversion is then lost too (read() -> kNotReady).
  Status begin() {
    if (phase_ == Phase::kReading) {
      spi_.cancel();
      ++state_.not_ready;
      return fail(Status::kNotReady);
    }
    if (busy_.read()) {
      ++state_.busy_faults;
      return fail(Status::kStillBusy);
    }
    device_ = 0;
    return start_device();
  }

  // The DMA stream's interrupt (or a poll).
  Step advance() {
    if (phase_ != Phase::kReading) return Step::kIdle;
    const BusStatus bs = spi_.complete();
    if (bs == BusStatus::kBusy) return Step::kBusy;
    if (bs != BusStatus::kOk) {
      ++state_.bus_errors;
      (void)fail(Status::kBusError);
      return Step::kError;
    }
    if (++device_ < kDevices) return start_device() == Status::kOk ? Step::kNextDevice : Step::kError;
    phase_ = Phase::kDone;
    return Step::kComplete;
  }

  // The tick: the completed pair's codes, or why there are none.
  Status read(Codes& out) {
    const Phase phase = phase_;
    phase_ = Phase::kIdle;
    if (phase == Phase::kDone) {
      for (std::size_t d = 0; d < kDevices; ++d) decode_words(rx_buffer_[d], out.channel[d]);
      ++state_.reads;
      return Status::kOk;
    }
    if (phase == Phase::kFailed) return failure_;  // counted where it happened
    if (phase == Phase::kReading) spi_.cancel();  // the tick came before the data: lost
    ++state_.not_ready;
    return Status::kNotReady;
  }

  const State& state() const { return state_; }

 private:
  enum class Phase : std::uint8_t { kIdle, kReading, kDone, kFailed };
  Status start_device() {
    const BusStatus bs = spi_.start(SpiTransfer{cs_[device_], kWordBits, nullptr, rx_buffer_[device_], kChannelsPerDevice / 2});
    if (bs != BusStatus::kOk) {
      ++state_.bus_errors;
      return fail(Status::kBusError);
    }
    phase_ = Phase::kReading;
    return Status::kOk;
  }
  Status fail(Status why) {
    phase_ = Phase::kFailed;
    failure_ = why;
    return why;
  }

  AsyncSpiMaster& spi_;
  InputPin& busy_;
  std::uint32_t (*rx_buffer_)[kChannelsPerDevice / 2];
  std::uint8_t cs_[kDevices]{};
  std::size_t device_ = 0;
  Phase phase_ = Phase::kIdle;
  Status failure_ = Status::kNotReady;
  State state_{};
};

// Volts at the ADC input for a code (+-10 V range).
constexpr double code_to_V(std::int16_t code) { return 10.0 * code / 32768.0; }

}  // namespace maglev::drivers::ad7606
