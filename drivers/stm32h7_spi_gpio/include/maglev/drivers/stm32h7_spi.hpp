// STM32H7 SPI v2 master (RM0433 §50), polled, behind the SpiMaster interface.
// Each device on the bus gets its own word size, clock divider and SPI mode,
// applied while SPE = 0 before its transaction; chip selects are GPIOs so one
// SPI can serve several devices (the two AD7606s share SPI2).
//
// Transaction (RM0433 §50.4.9 "procedure for master"): SPE=0 -> CFG1 (DSIZE,
// MBR) / CFG2 (mode) -> CR2.TSIZE = words -> SPE=1 -> CS low -> CSTART ->
// per word: wait TXP, write TXDR; wait RXP, read RXDR -> wait EOT -> clear
// EOT/TXTF in IFCR -> SPE=0 -> CS high. With DSIZE > 16 a 32-bit TXDR/RXDR
// access moves exactly one frame, so no packing surprises.
//
// Start/complete mode (AsyncSpiMaster, receive-only, needs attach_rx_dma()):
// RM0433 §50.4.14 "Communication using DMA": SPE=0 -> CFG1 (DSIZE, MBR,
// RXDMAEN) / CFG2 (mode, COMM = simplex receiver: the master clocks TSIZE
// frames with no TXDR writes, MOSI idle) -> CR2.TSIZE -> DMA stream armed on
// RXDR -> SPE=1 -> CS low -> CSTART, and return. complete(): the stream's
// TCIF (every frame read out of RXDR, so the wire is done) -> EOT checked,
// OVR checked -> IFCR -> SPE=0 -> CS high. The CPU never waits on the wire.
// start() refuses transfers with TX words (t.tx set: kBadArgument). The
// AD5764 chain, written from SPI1's end-of-transfer interrupt, has its own
// register-level writer (ad5764::Stm32IrqWriter, drivers/ad5764_dac) that
// takes SPI1 over after the boot write's polled transfer()s.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/bus.hpp"
#include "maglev/drivers/stm32h7_dma.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers {

struct SpiDeviceSettings {
  OutputPin* chip_select;      // active low
  std::uint8_t clock_divider_log2;  // SCLK = kernel / 2^(n+1): MBR code n (0 -> /2 ... 7 -> /256)
  bool cpol;
  bool cpha;
};

template <stm32h7::RegisterBus Bus, std::size_t kDevices = 2>
class Stm32SpiMaster final : public SpiMaster, public AsyncSpiMaster {
 public:
  Stm32SpiMaster(Bus& bus, stm32h7::Addr base, const SpiDeviceSettings (&devices)[kDevices],
                 std::uint32_t max_polls = 10000)
      : bus_(bus), base_(base), max_polls_(max_polls) {
    for (std::size_t i = 0; i < kDevices; ++i) devices_[i] = devices[i];
  }

  // Master, software slave management (SSM + SSI high: NSS is internal), and
  // AFCNTR so SCLK/MOSI keep their idle level between transactions.
  void init() {
    namespace s = stm32h7::spi;
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);
    bus_.write32(base_ + s::kCfg2, s::kCfg2Master | s::kCfg2Ssm | s::kCfg2Afcntr);
    forget_configuration();
    for (std::size_t i = 0; i < kDevices; ++i) devices_[i].chip_select->write(true);
  }

  // The RX DMA stream of the start/complete mode (init()ed by the caller).
  void attach_rx_dma(dma::Stream<Bus>* stream) { rx_dma_ = stream; }

  BusStatus transfer(const SpiTransfer& t) override {
    namespace s = stm32h7::spi;
    if (!valid(t)) return BusStatus::kBadArgument;
    if (in_flight_) return BusStatus::kBusy;  // a DMA transaction owns the bus
    const SpiDeviceSettings& d = begin_frame(t);
    BusStatus status = BusStatus::kOk;
    for (std::size_t i = 0; i < t.words && status == BusStatus::kOk; ++i) {
      if (!stm32h7::wait_for(bus_, base_ + s::kSr, s::kSrTxp, s::kSrTxp, max_polls_)) {
        status = BusStatus::kTimeout;
        break;
      }
      bus_.write32(base_ + s::kTxdr, t.tx != nullptr ? t.tx[i] : 0u);
      if (!stm32h7::wait_for(bus_, base_ + s::kSr, s::kSrRxp, s::kSrRxp, max_polls_)) {
        status = BusStatus::kTimeout;
        break;
      }
      const std::uint32_t word = bus_.read32(base_ + s::kRxdr);
      if (t.rx != nullptr) t.rx[i] = word;
    }
    if (status == BusStatus::kOk &&
        !stm32h7::wait_for(bus_, base_ + s::kSr, s::kSrEot, s::kSrEot, max_polls_)) {
      status = BusStatus::kTimeout;
    }
    end_frame(d, s::kIfcrEotc | s::kIfcrTxtfc);
    return status;
  }

  // Receive-only by DMA (t.rx the DMA-reachable buffer); t.tx must be null.
  BusStatus start(const SpiTransfer& t) override {
    namespace s = stm32h7::spi;
    if (t.tx != nullptr || !valid(t) || t.rx == nullptr || rx_dma_ == nullptr) return BusStatus::kBadArgument;
    if (in_flight_) return BusStatus::kBusy;
    const SpiDeviceSettings& d = devices_[t.device];
    // The AD7606 pair shares its settings, so CFG1 / CFG2 are written once
    // after boot; RXDMAEN left set since then raises no request before SPE = 1.
    configure(cfg1(d, t) | s::kCfg1Rxdmaen,
              cfg2(d) | stm32h7::field(s::kCommSimplexReceiver, s::kCfg2CommShift));
    bus_.write32(base_ + s::kCr2, static_cast<std::uint32_t>(t.words));
    const dma::Status armed = rx_dma_->start_peripheral_to_memory(
        base_ + s::kRxdr, reinterpret_cast<stm32h7::Addr>(t.rx), static_cast<std::uint16_t>(t.words));
    if (armed != dma::Status::kBusy) {
      bus_.write32(base_ + s::kCfg1, cfg1(d, t));
      forget_configuration();
      return armed == dma::Status::kStillRunning ? BusStatus::kBusy : BusStatus::kBadArgument;
    }
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    d.chip_select->write(false);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
    in_flight_ = true;
    device_ = t.device;
    return BusStatus::kOk;
  }

  BusStatus complete() override {
    namespace s = stm32h7::spi;
    if (!in_flight_) return BusStatus::kNotStarted;
    const dma::Status st = rx_dma_->poll();
    if (st == dma::Status::kBusy) return BusStatus::kBusy;
    BusStatus status = st == dma::Status::kComplete ? BusStatus::kOk : BusStatus::kTransferError;
    // The DMA read the last frame out of RXDR: EOT follows within a few SPI
    // kernel clocks (a bounded wait, normally one read).
    if (status == BusStatus::kOk && !stm32h7::wait_for(bus_, base_ + s::kSr, s::kSrEot, s::kSrEot, max_polls_)) {
      status = BusStatus::kTimeout;
    }
    if (status == BusStatus::kOk && (bus_.read32(base_ + s::kSr) & s::kSrOvr) != 0u) status = BusStatus::kTransferError;
    end_dma_frame();
    return status;
  }

  void cancel() override {
    if (!in_flight_) return;
    rx_dma_->abort();
    end_dma_frame();
  }

  bool busy() const { return in_flight_; }

 private:
  bool valid(const SpiTransfer& t) const {
    return t.device < kDevices && t.word_bits >= 4 && t.word_bits <= 32 && t.words != 0 && t.words <= 0xFFFF;
  }
  static std::uint32_t cfg1(const SpiDeviceSettings& d, const SpiTransfer& t) {
    return stm32h7::field(d.clock_divider_log2 & 7u, stm32h7::spi::kCfg1MbrShift) |
           static_cast<std::uint32_t>(t.word_bits - 1u);
  }
  static std::uint32_t cfg2(const SpiDeviceSettings& d) {
    namespace s = stm32h7::spi;
    return s::kCfg2Master | s::kCfg2Ssm | s::kCfg2Afcntr | (d.cpol ? s::kCfg2Cpol : 0u) | (d.cpha ? s::kCfg2Cpha : 0u);
  }
  const SpiDeviceSettings& begin_frame(const SpiTransfer& t) {
    namespace s = stm32h7::spi;
    const SpiDeviceSettings& d = devices_[t.device];
    forget_configuration();
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);  // SPE = 0: configuration registers writable
    bus_.write32(base_ + s::kCfg1, cfg1(d, t));
    bus_.write32(base_ + s::kCfg2, cfg2(d));
    bus_.write32(base_ + s::kCr2, static_cast<std::uint32_t>(t.words));
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    d.chip_select->write(false);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
    return d;
  }
  // CFG1 / CFG2 written only when they differ from what the last start()
  // wrote (every transaction ends with SPE = 0, so they are writable here).
  void configure(std::uint32_t c1, std::uint32_t c2) {
    namespace s = stm32h7::spi;
    if (c1 == cfg1_written_ && c2 == cfg2_written_) return;
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);  // SPE = 0: configuration registers writable
    bus_.write32(base_ + s::kCfg1, c1);
    bus_.write32(base_ + s::kCfg2, c2);
    cfg1_written_ = c1;
    cfg2_written_ = c2;
  }
  // The polled transfer() writes them every time, and a refused DMA start
  // leaves CFG1 as neither: the next start writes both.
  void forget_configuration() { cfg1_written_ = 0; }
  void end_frame(const SpiDeviceSettings& d, std::uint32_t clear) {
    namespace s = stm32h7::spi;
    bus_.write32(base_ + s::kIfcr, clear);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);
    d.chip_select->write(true);
  }
  void end_dma_frame() {
    namespace s = stm32h7::spi;
    end_frame(devices_[device_], s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc);
    in_flight_ = false;
  }

  Bus& bus_;
  stm32h7::Addr base_;
  std::uint32_t max_polls_;
  SpiDeviceSettings devices_[kDevices]{};
  dma::Stream<Bus>* rx_dma_ = nullptr;
  bool in_flight_ = false;  // a receive-only DMA transaction is open
  std::uint8_t device_ = 0;
  std::uint32_t cfg1_written_ = 0;  // CFG1 / CFG2 as the last start wrote them; 0: unknown
  std::uint32_t cfg2_written_ = 0;
};

}  // namespace maglev::drivers
