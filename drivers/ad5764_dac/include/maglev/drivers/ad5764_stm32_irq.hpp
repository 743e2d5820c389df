// The AD5764 chain written from the STM32H7 SPI's end-of-transfer interrupt,
// at the register level: the production board's DAC path at 20 kHz.
//
// Same words, frame order, LDAC rule and SDO-echo link check as
// ad5764::Chain::write_codes() (ad5764.hpp); the polled Chain still writes
// the chain at boot, through Stm32SpiMaster, before init() here.
//
//   servo tick      -> begin(codes): frame 0 loaded and started      (kOk)
//   SPI interrupt   -> advance():    frame k done, k+1 started       (kNextFrame)
//                                    frame 3 done, LDAC pulsed       (kComplete: result())
//
// Why registers, not the generic SPI master: the interrupt runs four times a
// tick, 80 000 times a second at 20 kHz, and each frame is the same shape on
// the same wires. Through the generic path this replaced (Stm32SpiMaster
// behind an asynchronous SPI interface, since removed) each frame
// paid two virtual calls into the master, two into the SYNC pin, the
// transfer's state machine and a runtime peripheral base: ~158 Cortex-M7
// instructions per frame for 12 register accesses (docs/PERFORMANCE.md
// "Whole servo interrupt at 20 kHz"). Here the SPI and the two GPIO lines are
// compile-time addresses (`Stm32ChainWiring`, from the board's pin map), so
// each access is one load or store with an immediate offset, and nothing is
// validated twice: the one configuration is written by init() and this
// writer owns the SPI after it.
//
// Register sequence (RM0433 §50.4.9, the TxFIFO may be filled before CSTART;
// a 48-bit SYNC frame is two 24-bit data frames and fits the FIFO of every
// SPI, so no TXP / RXP polls):
//   start of a frame: CR2.TSIZE = kDevices -> CR1.SPE -> SYNC low -> the
//     words into TXDR -> (first frame: IER.EOTIE) -> CR1.CSTART;
//   end of a frame (EOT): SR read -> the words out of RXDR -> (last frame,
//     overrun: IER = 0) -> IFCR -> CR1.SPE = 0 -> SYNC high (the AD5764
//     latches on this rising edge).
// IER.EOTIE stays set between the frames of one write: between them SPE = 0
// and EOT is cleared, so no interrupt can come until CSTART.
#pragma once

#include <atomic>  // std::atomic_signal_fence: a compiler barrier, no library code
#include <cstddef>
#include <cstdint>

#include "maglev/drivers/ad5764.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#include "maglev/stm32h7/registers.hpp"

namespace maglev::drivers::ad5764 {

// The chain's wiring, as template arguments (a structural type).
struct Stm32ChainWiring {
  stm32h7::Addr spi;                  // stm32h7::spi::kSpi1
  stm32h7::Addr sync_port;            // SYNC: the frame's chip select, active low
  std::uint8_t sync_pin;
  stm32h7::Addr ldac_port;            // LDAC: idles high, a low pulse updates every output
  std::uint8_t ldac_pin;
  std::uint8_t clock_divider_log2;    // SCLK = kernel / 2^(n+1) (CFG1.MBR)
  bool cpol;
  bool cpha;
};

// What one interrupt did (pinned values: diagnostics).
enum class IrqStep : std::uint8_t { kNextFrame = 0, kComplete = 1, kBusy = 2, kError = 3, kIdle = 4 };

template <stm32h7::RegisterBus Bus, Stm32ChainWiring kWiring, std::size_t kDevices = 2>
class Stm32IrqWriter {
 public:
  using Step = IrqStep;
  static constexpr std::size_t kChannels = kDevices * kChannelsPerDevice;
  static_assert(kDevices >= 1 && kDevices <= 2, "a frame of kDevices 24-bit words must fit the 8-byte TxFIFO");

  explicit Stm32IrqWriter(Bus& bus) : bus_(bus) {}

  // After the polled Chain wrote the chain (boot): the SPI idle and
  // configured for the chain, SYNC and LDAC high, no echo to compare yet.
  void init() {
    namespace s = stm32h7::spi;
    end_frame();
    write(s::kIer, 0u);
    write(s::kCfg1, kCfg1);
    write(s::kCfg2, kCfg2);
    pin(kWiring.ldac_port, kWiring.ldac_pin, true);
    phase_ = Phase::kIdle;
    have_previous_ = false;
  }

  // The tick. A write still under way (its interrupts never came) is
  // abandoned without LDAC: kBusError, and the caller trips the amplifiers.
  Status begin(const std::int16_t (&codes)[kChannels]) {
    namespace s = stm32h7::spi;
    if (phase_ == Phase::kWriting) {
      abandon();
      return fail();
    }
    for (std::size_t ch = 0; ch < kChannelsPerDevice; ++ch) {
      for (std::size_t d = 0; d < kDevices; ++d) {
        const std::size_t device = kDevices - 1 - d;  // the last device's word goes out first
        tx_[ch][d] = data_word(static_cast<std::uint8_t>(ch), codes[device * kChannelsPerDevice + ch]);
      }
    }
    frame_ = 0;
    result_ = Status::kOk;
    // Writing before the frame can end: begin() may run below the SPI
    // interrupt's priority (the servo loop's missed-deadline path), and an
    // interrupt that found no write under way would end the frame.
    phase_ = Phase::kWriting;
    std::atomic_signal_fence(std::memory_order_seq_cst);
    load_frame(0);
    write(s::kIer, s::kIerEotie);
    write(s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
    return Status::kOk;
  }

  // The SPI's interrupt (or a poll). With no write under way it is a stray
  // (a frame whose write a higher-priority begin() abandoned): the frame is
  // ended and EOTIE cleared, so EOT cannot re-enter this interrupt for ever.
  Step advance() {
    namespace s = stm32h7::spi;
    if (phase_ != Phase::kWriting) {
      abandon();
      return Step::kIdle;
    }
    const std::uint32_t sr = read(s::kSr);
    if ((sr & s::kSrEot) == 0u) return Step::kBusy;
    // EOT: every frame of the transaction is in the RxFIFO.
    std::uint32_t rx[kDevices];
    for (std::size_t d = 0; d < kDevices; ++d) rx[d] = read(s::kRxdr);
    const bool last = frame_ + 1 == kChannelsPerDevice;
    if ((sr & s::kSrOvr) != 0u) {
      abandon();
      (void)fail();
      return Step::kError;  // LDAC not pulsed: never a partial update
    }
    if (last) write(s::kIer, 0u);
    end_frame();
    // Each frame's echo is the frame before it; the first frame's, the
    // previous write's last.
    const std::uint32_t* sent_before = frame_ == 0 ? previous_ : tx_[frame_ - 1];
    if (frame_ != 0 || have_previous_) {
      std::uint32_t differ = 0;
      for (std::size_t d = 0; d < kDevices; ++d) differ |= rx[d] ^ sent_before[d];
      if (differ != 0u) {
        ++state_.link_mismatches;
        result_ = Status::kLinkMismatch;
      }
    }
    if (!last) {
      load_frame(++frame_);
      write(s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
      return Step::kNextFrame;
    }
    for (std::size_t d = 0; d < kDevices; ++d) previous_[d] = tx_[kChannelsPerDevice - 1][d];
    have_previous_ = true;
    pin(kWiring.ldac_port, kWiring.ldac_pin, false);
    pin(kWiring.ldac_port, kWiring.ldac_pin, true);
    ++state_.writes;
    phase_ = Phase::kIdle;
    return Step::kComplete;
  }

  // The finished write's outcome (kOk or kLinkMismatch after kComplete,
  // kBusError after kError).
  Status result() const { return result_; }
  bool writing() const { return phase_ == Phase::kWriting; }
  const State& state() const { return state_; }

  static constexpr std::uint32_t kCfg1 = stm32h7::spi::cfg1(kWiring.clock_divider_log2, kWordBits);
  static constexpr std::uint32_t kCfg2 = stm32h7::spi::cfg2_master(kWiring.cpol, kWiring.cpha);

 private:
  enum class Phase : std::uint8_t { kIdle, kWriting };

  std::uint32_t read(stm32h7::Addr offset) { return bus_.read32(kWiring.spi + offset); }
  void write(stm32h7::Addr offset, std::uint32_t v) { bus_.write32(kWiring.spi + offset, v); }
  // BSRR: set (bits 0..15) / reset (16..31), no read-modify-write.
  void pin(stm32h7::Addr port, std::uint8_t n, bool high) {
    bus_.write32(port + stm32h7::gpio::kBsrr, stm32h7::gpio::bsrr(n, high));
  }
  // TSIZE, SPE = 1, SYNC low, the words (SPE = 0 flushed the FIFO before).
  // CSTART is the caller's.
  void load_frame(std::size_t frame) {
    namespace s = stm32h7::spi;
    write(s::kCr2, static_cast<std::uint32_t>(kDevices));
    write(s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    pin(kWiring.sync_port, kWiring.sync_pin, false);
    for (std::size_t d = 0; d < kDevices; ++d) write(s::kTxdr, tx_[frame][d]);
  }
  void end_frame() {
    namespace s = stm32h7::spi;
    write(s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc);
    write(s::kCr1, s::kCr1Ssi);
    pin(kWiring.sync_port, kWiring.sync_pin, true);
  }
  // The frame on the wire (if any) ended: no interrupt, SPE = 0, SYNC high.
  void abandon() {
    write(stm32h7::spi::kIer, 0u);
    end_frame();
  }
  // The write ends without LDAC; the next one has no echo to compare.
  Status fail() {
    ++state_.bus_errors;
    have_previous_ = false;
    phase_ = Phase::kIdle;
    result_ = Status::kBusError;
    return Status::kBusError;
  }

  Bus& bus_;
  State state_{};
  std::uint32_t tx_[kChannelsPerDevice][kDevices]{};
  std::uint32_t previous_[kDevices]{};
  std::size_t frame_ = 0;
  Phase phase_ = Phase::kIdle;
  Status result_ = Status::kOk;
  bool have_previous_ = false;
};

}  // namespace maglev::drivers::ad5764
