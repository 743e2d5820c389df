// The AD7606 pair read by the STM32H7 SPI's RX DMA, at the register level:
// the production board's ADC path at 20 kHz (README "DMA schedule").
//
//   BUSY falls      -> begin():   ADC0's 4 words started (CS0 low, RX DMA);
//   DMA interrupt   -> advance(): ADC0 done -> CS0 high, ADC1 started -> kNextDevice;
//                                 ADC1 done -> kComplete (or kError): run the tick;
//   the servo tick  -> read():    decodes the completed buffer, ONCE.
// read() returns kNotReady unless exactly one complete pair was read since
// the last read(): a read not started, still running (then cancelled) or
// failed is sensor loss, never the previous tick's words again: the rules
// of the generic reader (over Stm32SpiMaster's DMA mode and a dma::Stream
// driver, since removed) that this one replaced.
//
// Why registers: the three bodies run 60 000 times a second at 20 kHz, on
// the same two devices with the same settings. Through the generic path
// each body paid virtual calls (the SPI master, the CS and BUSY pins), the
// transfer's validation, the DMA stream's argument checks and runtime
// register addresses: ~173 Cortex-M7 instructions a body for ~8 register
// accesses (docs/PERFORMANCE.md "Whole servo interrupt at 20 kHz"). Here the
// SPI, the DMA stream and the GPIO lines are compile-time addresses
// (`Stm32AdcWiring`, from the board's pin map) and what never changes
// (CFG1 / CFG2, the DMAMUX route, PAR, FCR) is written once by init().
//
// Register sequence per device (RM0433 §15.3.19 stream configuration,
// §50.4.14 "Communication using DMA": the stream before the SPI's start):
//   start: DMA SxCR.EN must read 0 -> M0AR, NDTR -> SxCR (P->M, MINC, 32-bit,
//     PL very high, TCIE / TEIE / DMEIE, EN) -> SPI CR2.TSIZE -> CR1.SPE ->
//     CS low -> CR1.CSTART;
//   end (the stream's interrupt): ISR flags -> IFCR (the flags, so the
//     interrupt does not re-enter) -> SPI SR.EOT (follows TC within a few SPI
//     kernel clocks: a bounded poll, normally one read), OVR -> SPI IFCR ->
//     CR1.SPE = 0 -> CS high.
#pragma once

#include <atomic>  // std::atomic_signal_fence: a compiler barrier, no library code
#include <cstddef>
#include <cstdint>

#include "maglev/drivers/ad7606.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#include "maglev/stm32h7/registers.hpp"

namespace maglev::drivers::ad7606 {

// The pair's wiring, as template arguments (a structural type).
struct Stm32AdcWiring {
  stm32h7::Addr spi;                      // stm32h7::spi::kSpi3
  stm32h7::Addr cs_port[kDevices];        // CS of ADC d, active low
  std::uint8_t cs_pin[kDevices];
  stm32h7::Addr busy_port;                // BUSY of ADC 0 (high while converting)
  std::uint8_t busy_pin;
  stm32h7::Addr dma;                      // stm32h7::dma::kDma1 / kDma2
  std::uint8_t dma_stream;                // 0..7
  std::uint8_t dma_request;               // DMAMUX1 request (stm32h7::dma::kReqSpi3Rx)
  std::uint8_t clock_divider_log2;        // SCLK = kernel / 2^(n+1) (CFG1.MBR)
  bool cpol;
  bool cpha;
};

template <stm32h7::RegisterBus Bus, Stm32AdcWiring kWiring>
class Stm32DmaReader {
 public:
  enum class Step : std::uint8_t { kNextDevice = 0, kComplete = 1, kBusy = 2, kError = 3, kIdle = 4 };
  static constexpr std::size_t kWords = kChannelsPerDevice / 2;

  // `rx_buffer`: kDevices x 4 words the DMA can reach (board: D2 SRAM).
  // `max_eot_polls`: how long advance() waits for EOT after the stream's TC.
  Stm32DmaReader(Bus& bus, std::uint32_t (&rx_buffer)[kDevices][kWords], std::uint32_t max_eot_polls = 10000)
      : bus_(bus), rx_buffer_(rx_buffer), max_eot_polls_(max_eot_polls) {}

  // SPI master in simplex-receiver mode with RXDMAEN (no request before
  // SPE = 1), both CS high, the stream off with its flags cleared, routed
  // to the SPI's RX request, PAR = RXDR, direct mode.
  void init() {
    namespace s = stm32h7::spi;
    namespace d = stm32h7::dma;
    spi(s::kCr1, s::kCr1Ssi);
    spi(s::kCfg2, kCfg2);
    spi(s::kCfg1, kCfg1);
    spi(s::kIer, 0u);
    for (std::size_t dev = 0; dev < kDevices; ++dev) pin(kWiring.cs_port[dev], kWiring.cs_pin[dev], true);
    stream(d::kSxCr, 0u);
    clear_dma_flags();
    bus_.write32(d::dmamux_channel(kWiring.dma, kWiring.dma_stream), kWiring.dma_request & 0x7Fu);
    stream(d::kSxPar, static_cast<std::uint32_t>(kWiring.spi + s::kRxdr));
    stream(d::kSxFcr, 0u);  // direct mode
    phase_ = Phase::kIdle;
  }

  // BUSY fell. A read still under way (its tick never ran) is cancelled and
  // counted; this conversion is then lost too (read() -> kNotReady).
  Status begin() {
    if (phase_ == Phase::kReading) {
      abort();
      ++state_.not_ready;
      return fail(Status::kNotReady);
    }
    if ((bus_.read32(kWiring.busy_port + stm32h7::gpio::kIdr) & (1u << kWiring.busy_pin)) != 0u) {
      ++state_.busy_faults;
      return fail(Status::kStillBusy);
    }
    device_ = 0;
    return start_device();
  }

  // The DMA stream's interrupt (or a poll).
  Step advance() {
    namespace s = stm32h7::spi;
    namespace d = stm32h7::dma;
    if (phase_ != Phase::kReading) return Step::kIdle;
    const std::uint32_t flags = (bus_.read32(kWiring.dma + d::isr(kWiring.dma_stream)) >> kFlagShift) & d::kFlagsAll;
    if ((flags & (d::kFlagTe | d::kFlagDme)) != 0u) return error();
    if ((flags & d::kFlagTc) == 0u) return Step::kBusy;
    clear_dma_flags();
    // The DMA read the last word out of RXDR: EOT follows within a few SPI
    // kernel clocks.
    std::uint32_t sr = read_spi(s::kSr);
    for (std::uint32_t n = 0; (sr & s::kSrEot) == 0u && n < max_eot_polls_; ++n) sr = read_spi(s::kSr);
    if ((sr & s::kSrEot) == 0u || (sr & s::kSrOvr) != 0u) return error();
    end_frame();
    if (++device_ < kDevices) return start_device() == Status::kOk ? Step::kNextDevice : Step::kError;
    phase_ = Phase::kDone;
    return Step::kComplete;
  }

  // The tick: the completed pair's codes, or why there are none.
  Status read(Codes& out) {
    const Status status = read_raw();
    if (status == Status::kOk) {
      for (std::size_t dev = 0; dev < kDevices; ++dev) decode_words(rx_buffer_[dev], out.channel[dev]);
    }
    return status;
  }

  // The same, without decoding: on kOk the completed pair's raw words are in
  // words() (words()[d], channel_code()) until the next begin(). The board
  // maps the channels it uses straight from them into its sample.
  Status read_raw() {
    const Phase phase = phase_;
    phase_ = Phase::kIdle;
    if (phase == Phase::kDone) {
      ++state_.reads;
      return Status::kOk;
    }
    if (phase == Phase::kFailed) return failure_;  // counted where it happened
    if (phase == Phase::kReading) abort();  // the tick came before the data: lost
    ++state_.not_ready;
    return Status::kNotReady;
  }

  const std::uint32_t (&words() const)[kDevices][kWords] { return rx_buffer_; }
  const State& state() const { return state_; }

  static constexpr std::uint32_t kCfg1 =
      stm32h7::spi::cfg1(kWiring.clock_divider_log2, kWordBits) | stm32h7::spi::kCfg1Rxdmaen;
  static constexpr std::uint32_t kCfg2 =
      stm32h7::spi::cfg2_master(kWiring.cpol, kWiring.cpha) |
      stm32h7::field(stm32h7::spi::kCommSimplexReceiver, stm32h7::spi::kCfg2CommShift);
  static constexpr std::uint32_t kStreamCr =
      stm32h7::field(stm32h7::dma::kDirPeripheralToMemory, stm32h7::dma::kCrDirShift) | stm32h7::dma::kCrMinc |
      stm32h7::field(stm32h7::dma::kSizeWord, stm32h7::dma::kCrPsizeShift) |
      stm32h7::field(stm32h7::dma::kSizeWord, stm32h7::dma::kCrMsizeShift) | stm32h7::field(3u, stm32h7::dma::kCrPlShift) |
      stm32h7::dma::kCrTcie | stm32h7::dma::kCrTeie | stm32h7::dma::kCrDmeie;

 private:
  enum class Phase : std::uint8_t { kIdle, kReading, kDone, kFailed };
  static constexpr unsigned kFlagShift = stm32h7::dma::flag_shift(kWiring.dma_stream);
  static constexpr stm32h7::Addr kStream = stm32h7::dma::stream(kWiring.dma, kWiring.dma_stream);

  std::uint32_t read_spi(stm32h7::Addr offset) { return bus_.read32(kWiring.spi + offset); }
  void spi(stm32h7::Addr offset, std::uint32_t v) { bus_.write32(kWiring.spi + offset, v); }
  void stream(stm32h7::Addr offset, std::uint32_t v) { bus_.write32(kStream + offset, v); }
  void pin(stm32h7::Addr port, std::uint8_t n, bool high) {
    bus_.write32(port + stm32h7::gpio::kBsrr, stm32h7::gpio::bsrr(n, high));
  }
  void clear_dma_flags() {
    bus_.write32(kWiring.dma + stm32h7::dma::ifcr(kWiring.dma_stream), stm32h7::dma::kFlagsAll << kFlagShift);
  }
  // The stream armed on this device's buffer, then the SPI started. A
  // stream that still runs (it never ended: the hardware clears EN at the
  // end of a transfer and on an error) is never reprogrammed: kBusError.
  Status start_device() {
    namespace s = stm32h7::spi;
    namespace d = stm32h7::dma;
    if ((bus_.read32(kStream + d::kSxCr) & d::kCrEn) != 0u) {
      ++state_.bus_errors;
      return fail(Status::kBusError);
    }
    stream(d::kSxM0ar, static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(rx_buffer_[device_])));
    stream(d::kSxNdtr, static_cast<std::uint32_t>(kWords));
    stream(d::kSxCr, kStreamCr | d::kCrEn);
    spi(s::kCr2, static_cast<std::uint32_t>(kWords));
    spi(s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    pin(kWiring.cs_port[device_], kWiring.cs_pin[device_], false);
    // Reading before the transfer can end (the stream's interrupt checks it).
    phase_ = Phase::kReading;
    std::atomic_signal_fence(std::memory_order_seq_cst);
    spi(s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
    return Status::kOk;
  }
  // SPI flags cleared, SPE = 0 (the FIFO flushed), this device's CS high.
  void end_frame() {
    namespace s = stm32h7::spi;
    spi(s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc);
    spi(s::kCr1, s::kCr1Ssi);
    pin(kWiring.cs_port[device_], kWiring.cs_pin[device_], true);
  }
  // The transfer abandoned: the stream off and its flags cleared, the frame ended.
  void abort() {
    stream(stm32h7::dma::kSxCr, 0u);
    clear_dma_flags();
    end_frame();
  }
  Step error() {
    abort();
    ++state_.bus_errors;
    (void)fail(Status::kBusError);
    return Step::kError;
  }
  Status fail(Status why) {
    phase_ = Phase::kFailed;
    failure_ = why;
    return why;
  }

  Bus& bus_;
  std::uint32_t (&rx_buffer_)[kDevices][kWords];
  std::uint32_t max_eot_polls_;
  std::size_t device_ = 0;
  Phase phase_ = Phase::kIdle;
  Status failure_ = Status::kNotReady;
  State state_{};
};

}  // namespace maglev::drivers::ad7606
