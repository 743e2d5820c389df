// Register-level model of one STM32H7 SPI (v2) receiving through one DMA
// stream, for the heap-free fakes: the host tests' FakeRegisterBus hooks and
// the servo-tick QEMU image's BoardRegisterFake use the same model.
//
// A transfer completes when CSTART is written, IF AND ONLY IF the driver set
// up what the hardware needs (RM0433 §15.3.19, §17, §50.4.14): the DMAMUX
// channel routed to the SPI's RX request, the stream enabled peripheral ->
// memory with PAR = SPI RXDR, 32-bit PSIZE/MSIZE, MINC, NDTR > 0; SPI
// CFG1.RXDMAEN, CFG2.COMM = simplex receiver, CR1.SPE. Then NDTR words from
// the word source (the chip model: what it clocks out while CS is low) land
// in memory at M0AR, NDTR = 0, EN clears, TCIF and SPI EOT set. Anything
// missing: nothing moves, no flag (ad7606::Stm32DmaReader's advance() keeps
// answering kBusy and the tick reports the loss). M0AR outside the mapped
// buffer, or an injected fault: TEIF, EN cleared, nothing written. An injected stall: the
// transfer never ends. No DMA set up (a polled transfer): CSTART sets EOT and
// the fake's own RXDR answers the words.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/stm32h7/registers.hpp"

namespace maglev::drivers::dma {

// What the SPI clocks in, word by word (the selected chip's DOUT).
class WordSource {
 public:
  virtual std::uint32_t next_word() = 0;

 protected:
  WordSource() = default;
  ~WordSource() = default;
  WordSource(const WordSource&) = default;
  WordSource& operator=(const WordSource&) = default;
};

class SpiRxDmaModel {
 public:
  enum class Fault : std::uint8_t { kNone = 0, kTransferError = 1, kStall = 2 };

  SpiRxDmaModel(stm32h7::Addr spi, stm32h7::Addr controller, unsigned stream, std::uint32_t request)
      : spi_(spi), controller_(controller), stream_(stream), request_(request),
        regs_(stm32h7::dma::stream(controller, stream)), shift_(stm32h7::dma::flag_shift(stream)) {}

  // The only memory the DMA may write: `words` words at `buffer`.
  void map_memory(std::uint32_t* buffer, std::size_t words) {
    memory_ = buffer;
    memory_words_ = words;
  }
  void inject(Fault f) { fault_ = f; }
  std::uint32_t transfers() const { return transfers_; }

  // Reads of the registers this model owns; false: not one of them.
  bool read(stm32h7::Addr a, std::uint32_t* value) const {
    namespace d = stm32h7::dma;
    namespace s = stm32h7::spi;
    if (a == controller_ + d::isr(stream_)) return answer(value, isr_ << shift_);
    if (a == regs_ + d::kSxCr) return answer(value, cr_);
    if (a == regs_ + d::kSxNdtr) return answer(value, ndtr_);
    if (a == spi_ + s::kSr) return answer(value, s::kSrTxp | s::kSrRxp | sr_);
    return false;
  }

  // Writes (after the bus stored them); `source` gives the words clocked in.
  void write(stm32h7::Addr a, std::uint32_t v, WordSource& source) {
    namespace d = stm32h7::dma;
    namespace s = stm32h7::spi;
    if (a == d::dmamux_channel(controller_, stream_)) mux_ = v & 0x7Fu;
    else if (a == regs_ + d::kSxCr) cr_ = v;
    else if (a == regs_ + d::kSxNdtr) ndtr_ = v & 0xFFFFu;
    else if (a == regs_ + d::kSxPar) par_ = v;
    else if (a == regs_ + d::kSxM0ar) m0ar_ = v;
    else if (a == controller_ + d::ifcr(stream_)) isr_ &= ~((v >> shift_) & d::kFlagsAll);
    else if (a == spi_ + s::kCfg1) cfg1_ = v;
    else if (a == spi_ + s::kCfg2) cfg2_ = v;
    else if (a == spi_ + s::kIfcr) sr_ &= ~(v & (s::kIfcrEotc | s::kIfcrOvrc));
    else if (a == spi_ + s::kCr1) {
      if ((v & s::kCr1Spe) != 0u && (v & s::kCr1Cstart) != 0u) on_cstart(source);
    }
  }

 private:
  static bool answer(std::uint32_t* value, std::uint32_t v) {
    *value = v;
    return true;
  }
  void on_cstart(WordSource& source) {
    namespace d = stm32h7::dma;
    namespace s = stm32h7::spi;
    if ((cfg1_ & s::kCfg1Rxdmaen) == 0u) {  // polled: the fake's RXDR serves the words
      sr_ |= s::kSrEot;
      return;
    }
    const std::uint32_t want_cr = stm32h7::field(d::kDirPeripheralToMemory, d::kCrDirShift) | d::kCrMinc |
                                  stm32h7::field(d::kSizeWord, d::kCrPsizeShift) |
                                  stm32h7::field(d::kSizeWord, d::kCrMsizeShift) | d::kCrEn;
    const std::uint32_t cr_mask = (3u << d::kCrDirShift) | d::kCrMinc | (3u << d::kCrPsizeShift) |
                                  (3u << d::kCrMsizeShift) | d::kCrEn;
    const bool routed = mux_ == request_ && par_ == static_cast<std::uint32_t>(spi_ + s::kRxdr) &&
                        (cr_ & cr_mask) == want_cr && ndtr_ > 0u &&
                        ((cfg2_ & s::kCfg2CommMask) >> s::kCfg2CommShift) == s::kCommSimplexReceiver;
    if (!routed || fault_ == Fault::kStall) return;  // no request reaches the stream: it waits forever
    ++transfers_;
    const auto base = static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(memory_));
    const bool mapped = memory_ != nullptr && m0ar_ >= base && (m0ar_ - base) % 4u == 0u &&
                        (m0ar_ - base) / 4u + ndtr_ <= memory_words_;
    if (fault_ == Fault::kTransferError || !mapped) {
      fault_ = Fault::kNone;
      cr_ &= ~d::kCrEn;
      isr_ |= d::kFlagTe;
      return;
    }
    std::uint32_t* out = memory_ + (m0ar_ - base) / 4u;
    for (std::uint32_t i = 0; i < ndtr_; ++i) out[i] = source.next_word();
    ndtr_ = 0;
    cr_ &= ~d::kCrEn;
    isr_ |= d::kFlagTc;
    sr_ |= s::kSrEot;
  }

  stm32h7::Addr spi_, controller_;
  unsigned stream_;
  std::uint32_t request_;
  stm32h7::Addr regs_;
  unsigned shift_;
  std::uint32_t* memory_ = nullptr;
  std::size_t memory_words_ = 0;
  Fault fault_ = Fault::kNone;
  std::uint32_t mux_ = 0, cr_ = 0, ndtr_ = 0, par_ = 0, m0ar_ = 0, cfg1_ = 0, cfg2_ = 0;
  std::uint32_t isr_ = 0;  // the stream's flags, unshifted
  std::uint32_t sr_ = 0;   // SPI EOT / OVR
  std::uint32_t transfers_ = 0;
};

}  // namespace maglev::drivers::dma
