// The STM32H743 amplifier board's registers, as far as the servo tick's
// drivers touch them, answered by a heap-free fake: the register-bus policy
// (stm32h7::RegisterBus: read32/write32) the real drivers are templated on,
// in place of MmioBus. What the drivers read is one recorded SensorSample
// (present()), so they take their normal full path:
//
//   * SPI1 SR: TXP, RXP and EOT always set (every poll succeeds at once: the
//     wire time of the polled DAC transfer is NOT in the count, see
//     docs/PERFORMANCE.md "Whole servo interrupt at 20 kHz");
//   * SPI3 + its RX DMA (DMA1 stream 0, DMAMUX1 channel 0): the shared
//     register-level model (drivers/stm32h7_dma spi_rx_dma_model.hpp): a
//     read set up completely completes at CSTART, the selected AD7606's
//     DOUTA words written into the mapped buffer (map_dma_memory), TCIF and
//     EOT set; set up wrongly, it never completes (sensor loss); fault
//     injection through dma_model();
//   * the AD7606 words (DMA or a polled SPI3 RXDR read): V(2w+1) << 16 |
//     V(2w+2), device chosen by its CS line (GPIOE BSRR: ADC0 CS PE15, ADC1
//     CS PE10), word index restarted on CS low; ADC0 V1..V3 displacement,
//     V4..V7 Hall, V8 0; ADC1 V1..V8 the coil current monitors
//     (amplifier_board_io.hpp's map_to_sample, inverted);
//   * SPI1 RXDR: the AD5764 chain's SDO, i.e. the word written two TXDR
//     writes earlier (48-bit chain: the driver's link check sees its echo),
//     through an RxFIFO (each TXDR write queues the word it shifts out, each
//     RXDR read takes the oldest), so a driver may read after writing all;
//   * TIM2 / TIM5 CNT: interferometer counts 0 / 1 (32-bit counters), TIM3
//     CNT: the low 16 bits of counts 2 (the driver extends them);
//   * GPIOE IDR: BUSY (PE11) low = conversion done; GPIOF IDR: the three
//     signal-loss lines (PF12..14, active low) high = no loss;
//   * EXTI CPUPR1: 0 (the next tick is not pending yet).
// Writes are kept where the tick's result shows: the DAC words (SPI1 TXDR),
// the amplifier-enable line (GPIOG BSRR, PG3). Everything else reads 0 and
// writes are dropped (clock, pin and peripheral set-up).
//
// kCountAccesses: count every read/write (a measurement pass that does not
// report the whole tick's instructions; counting costs instructions itself).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/spi_rx_dma_model.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/stm32h7/registers.hpp"

namespace maglev::servo_tick {

namespace r = maglev::stm32h7;

template <bool kCountAccesses>
class BoardRegisterFake final : public drivers::dma::WordSource {
 public:
  // The buffer the ADC DMA may write (the board's g_adc_dma_rx).
  void map_dma_memory(std::uint32_t* buffer, std::size_t words) { dma_.map_memory(buffer, words); }
  drivers::dma::SpiRxDmaModel& dma_model() { return dma_; }

  // The selected AD7606's next DOUTA word (WordSource: what the DMA moves).
  std::uint32_t next_word() override {
    const std::uint32_t w = adc_word_ < 4 ? adc_word_ : 3u;
    ++adc_word_;
    const std::int16_t* v = adc_[adc_selected_];
    return (static_cast<std::uint32_t>(static_cast<std::uint16_t>(v[2 * w])) << 16) |
           static_cast<std::uint16_t>(v[2 * w + 1]);
  }

  // The sensor values the next tick's drivers read.
  void present(const io::SensorSample& s) {
    for (int i = 0; i < 3; ++i) adc_[0][i] = s.displacement_adc[i];
    for (int i = 0; i < 4; ++i) adc_[0][3 + i] = s.hall_adc[i];
    adc_[0][7] = 0;
    for (int i = 0; i < 8; ++i) adc_[1][i] = s.coil_current_adc[i];
    for (int i = 0; i < 3; ++i) counts_[i] = s.interferometer_counts[i];
    dac_words_ = 0;
  }

  // One counter alone (TIM3's 16-bit extension is walked to the first
  // sample's count at boot, see servo_tick_main.cpp).
  void set_count(int axis, std::uint32_t count) { counts_[axis] = count; }

  std::uint32_t read32(r::Addr a) {
    if constexpr (kCountAccesses) ++reads_;
    if (a == r::spi::kSpi1 + r::spi::kSr) return r::spi::kSrTxp | r::spi::kSrRxp | r::spi::kSrEot;
    if (a == r::spi::kSpi3 + r::spi::kRxdr) return next_word();
    if (a == r::spi::kSpi1 + r::spi::kRxdr) return dac_rx_fifo_[dac_rx_read_++ % kDacRxFifo];
    if (a == r::tim::kTim2 + r::tim::kCnt) return counts_[0];
    if (a == r::tim::kTim5 + r::tim::kCnt) return counts_[1];
    if (a == r::tim::kTim3 + r::tim::kCnt) return counts_[2] & 0xFFFFu;
    if (a == r::gpio::port('F') + r::gpio::kIdr) return (1u << 12) | (1u << 13) | (1u << 14);
    if (std::uint32_t v = 0; dma_read(a, &v)) return v;  // SPI3 SR, the DMA stream's CR/NDTR/ISR
    return 0u;  // GPIOE IDR: BUSY low; EXTI CPUPR1: nothing pending; the rest
  }

  void write32(r::Addr a, std::uint32_t v) {
    if constexpr (kCountAccesses) ++writes_;
    if (a == r::spi::kSpi1 + r::spi::kTxdr) {
      dac_rx_fifo_[dac_rx_write_++ % kDacRxFifo] = dac_chain_[0];
      dac_chain_[0] = dac_chain_[1];
      dac_chain_[1] = v;
      if (dac_words_ < kDacWords) dac_word_[dac_words_] = v;
      ++dac_words_;
      return;
    }
    if ((a & ~r::Addr{0x3FF}) == r::spi::kSpi1) return;  // SPI1 set-up: dropped
    if (a == r::gpio::port('E') + r::gpio::kBsrr) {
      if ((v & (1u << (15 + 16))) != 0u) select_adc(0);  // ADC0 CS low
      if ((v & (1u << (10 + 16))) != 0u) select_adc(1);  // ADC1 CS low
      return;
    }
    if (a == r::gpio::port('G') + r::gpio::kBsrr) {
      if ((v & (1u << 3)) != 0u) amplifier_enable_ = true;
      if ((v & (1u << (3 + 16))) != 0u) amplifier_enable_ = false;
      return;
    }
    if ((a & ~r::Addr{0xFFF}) == r::dma::kDma1 || (a & ~r::Addr{0x3FF}) == r::spi::kSpi3) dma_write(a, v);
  }

  // What the AD5764 chain received this tick (since present()): eight words,
  // frames of two, the last device's word first (ad5764.hpp). False unless
  // exactly four frames with channels A..D arrived.
  bool dac_command(io::ActuatorCommand* out) const {
    if (dac_words_ != kDacWords) return false;
    for (std::size_t k = 0; k < kDacWords; ++k) {
      const std::uint32_t w = dac_word_[k];
      const std::size_t device = (k % 2u == 0u) ? 1u : 0u;
      const std::size_t channel = (w >> 16) & 7u;
      if (((w >> 19) & 0x1Fu) != 0b00010u || channel != k / 2u) return false;  // write, data register
      out->dac_code[device * 4u + channel] = static_cast<std::int16_t>(static_cast<std::uint16_t>(w & 0xFFFFu));
    }
    out->amplifier_enable = amplifier_enable_;
    return true;
  }

  std::uint32_t reads() const { return reads_; }
  std::uint32_t writes() const { return writes_; }

 private:
  static constexpr std::size_t kDacWords = 8;
  // Out of line: the model's decoding stays out of read32/write32, which
  // the drivers inline at every register access (as MmioBus's are).
  [[gnu::noinline]] bool dma_read(r::Addr a, std::uint32_t* v) const { return dma_.read(a, v); }
  [[gnu::noinline]] void dma_write(r::Addr a, std::uint32_t v) { dma_.write(a, v, *this); }
  void select_adc(std::uint32_t d) {
    adc_selected_ = d;
    adc_word_ = 0;
  }
  std::int16_t adc_[2][8]{};
  std::uint32_t counts_[3]{};
  std::uint32_t adc_selected_ = 0;
  std::uint32_t adc_word_ = 0;
  std::uint32_t dac_chain_[2]{};
  static constexpr std::uint32_t kDacRxFifo = 4;  // SPI1's 16-byte FIFO, 4-byte frames
  std::uint32_t dac_rx_fifo_[kDacRxFifo]{};
  std::uint32_t dac_rx_write_ = 0;
  std::uint32_t dac_rx_read_ = 0;
  std::uint32_t dac_word_[kDacWords]{};
  std::size_t dac_words_ = 0;
  bool amplifier_enable_ = false;
  drivers::dma::SpiRxDmaModel dma_{r::spi::kSpi3, r::dma::kDma1, 0, r::dma::kReqSpi3Rx};
  std::uint32_t reads_ = 0;
  std::uint32_t writes_ = 0;
};

}  // namespace maglev::servo_tick
