// One STM32H7 DMA stream (DMA1/DMA2, RM0433 §15) and its DMAMUX1 channel
// (§17), peripheral -> memory, 32-bit items, direct mode (no FIFO), one
// shot. Used by Stm32SpiMaster's start()/complete() transaction mode so the
// AD7606 words reach D2 SRAM without the CPU polling the wire.
//
// Stream procedure (§15.3.19 "Stream configuration procedure"): EN = 0 (wait
// until it reads 0) -> clear the stream's flags in LIFCR/HIFCR -> PAR, M0AR,
// NDTR -> FCR (direct mode) -> CR (DIR, MINC, PSIZE/MSIZE, PL, TCIE/TEIE/
// DMEIE) -> CR |= EN. The DMAMUX channel's request ID is set once (init()).
// Completion = TCIF with no TEIF/DMEIF; the hardware clears EN itself at the
// end of the transfer and on an error.
//
// The memory address must be one the DMA can reach: D2 SRAM or AXI SRAM, not
// DTCM (§2.1 bus matrix); the board's buffers are in .dma_bss (D2 SRAM,
// MPU non-cacheable, so the CPU reads what the DMA wrote without cache
// maintenance).
#pragma once

#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers::dma {

struct StreamConfig {
  stm32h7::Addr controller;   // stm32h7::dma::kDma1 / kDma2
  std::uint8_t stream;        // 0..7
  std::uint8_t request;       // DMAMUX1 request input (stm32h7::dma::kReqSpi3Rx ...)
  bool interrupt;             // TCIE/TEIE/DMEIE: the stream's IRQ runs the next step
};

// Pinned values: they appear in diagnostics.
enum class Status : std::uint8_t {
  kIdle = 0,       // not started since the last completion was taken
  kBusy = 1,       // under way
  kComplete = 2,   // TCIF, no error: all items in memory
  kError = 3,      // TEIF or DMEIF: bus error / direct-mode error; memory contents undefined
  kBadArgument = 4,
  kStillRunning = 5,  // start refused: the previous transfer has not ended
};

template <stm32h7::RegisterBus Bus>
class Stream {
 public:
  Stream(Bus& bus, const StreamConfig& config)
      : bus_(bus), config_(config), regs_(stm32h7::dma::stream(config.controller, config.stream)),
        flag_shift_(stm32h7::dma::flag_shift(config.stream)) {}

  // Stream off, its flags cleared, the DMAMUX channel routed to the request.
  void init() {
    namespace r = stm32h7::dma;
    bus_.write32(regs_ + r::kSxCr, 0u);
    clear_flags();
    bus_.write32(r::dmamux_channel(config_.controller, config_.stream), config_.request & 0x7Fu);
    started_ = false;
    par_written_ = 0;
  }

  // Arms a peripheral -> memory transfer of `items` 32-bit words from the
  // peripheral data register `peripheral` into `memory` (a bus address). The
  // peripheral's own DMA enable and start come after this (RM0433 §50.4.14:
  // DMA stream first, then the SPI's RXDMAEN ... CSTART). Returns kBusy: the
  // transfer is under way; kStillRunning: the previous one has not ended
  // (it is never cut short).
  Status start_peripheral_to_memory(stm32h7::Addr peripheral, stm32h7::Addr memory, std::uint16_t items) {
    namespace r = stm32h7::dma;
    if (items == 0 || (memory & 3u) != 0u) return Status::kBadArgument;
    if ((bus_.read32(regs_ + r::kSxCr) & r::kCrEn) != 0u) return Status::kStillRunning;
    clear_flags();
    // PAR and FCR hold their values while EN = 0 (only M0AR / NDTR change
    // between the transfers of one peripheral): written when PAR changes.
    const bool new_peripheral = static_cast<std::uint32_t>(peripheral) != par_written_;
    if (new_peripheral) bus_.write32(regs_ + r::kSxPar, static_cast<std::uint32_t>(peripheral));
    bus_.write32(regs_ + r::kSxM0ar, static_cast<std::uint32_t>(memory));
    bus_.write32(regs_ + r::kSxNdtr, items);
    if (new_peripheral) {
      bus_.write32(regs_ + r::kSxFcr, 0u);  // direct mode
      par_written_ = static_cast<std::uint32_t>(peripheral);
    }
    const std::uint32_t irq = config_.interrupt ? (r::kCrTcie | r::kCrTeie | r::kCrDmeie) : 0u;
    bus_.write32(regs_ + r::kSxCr, stm32h7::field(r::kDirPeripheralToMemory, r::kCrDirShift) | r::kCrMinc |
                                       stm32h7::field(r::kSizeWord, r::kCrPsizeShift) |
                                       stm32h7::field(r::kSizeWord, r::kCrMsizeShift) |
                                       stm32h7::field(3u, r::kCrPlShift) | irq | r::kCrEn);
    started_ = true;
    return Status::kBusy;
  }

  // Where the transfer stands; kComplete / kError are reported once, then
  // the stream is kIdle again (its flags cleared): a result is never reused.
  Status poll() {
    namespace r = stm32h7::dma;
    if (!started_) return Status::kIdle;
    const std::uint32_t flags = (bus_.read32(config_.controller + r::isr(config_.stream)) >> flag_shift_) & r::kFlagsAll;
    if ((flags & (r::kFlagTe | r::kFlagDme)) != 0u) return finish(Status::kError);
    if ((flags & r::kFlagTc) != 0u) return finish(Status::kComplete);
    return Status::kBusy;
  }

  // Abandons a transfer (timeout): EN = 0, flags cleared.
  void abort() {
    bus_.write32(regs_ + stm32h7::dma::kSxCr, 0u);
    clear_flags();
    started_ = false;
  }

  // Items still to move (NDTR counts down).
  std::uint32_t remaining() { return bus_.read32(regs_ + stm32h7::dma::kSxNdtr) & 0xFFFFu; }
  const StreamConfig& config() const { return config_; }

 private:
  Status finish(Status s) {
    clear_flags();
    started_ = false;
    return s;
  }
  void clear_flags() {
    bus_.write32(config_.controller + stm32h7::dma::ifcr(config_.stream), stm32h7::dma::kFlagsAll << flag_shift_);
  }

  Bus& bus_;
  StreamConfig config_;
  stm32h7::Addr regs_;
  unsigned flag_shift_;
  bool started_ = false;
  std::uint32_t par_written_ = 0;  // PAR (and FCR) as last written; 0: not since init()
};

}  // namespace maglev::drivers::dma
