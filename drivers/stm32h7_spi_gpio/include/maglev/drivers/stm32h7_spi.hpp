// STM32H7 SPI v2 master (RM0433 §50), polled, behind the SpiMaster interface.
// Each device on the bus gets its own word size, clock divider and SPI mode,
// applied while SPE = 0 before its transaction; chip selects are GPIOs so one
// SPI can serve several devices (e.g. the two AD7606s of the polled
// ad7606::Adc).
//
// Transaction (RM0433 §50.4.9 "procedure for master"): SPE=0 -> CFG1 (DSIZE,
// MBR) / CFG2 (mode) -> CR2.TSIZE = words -> SPE=1 -> CS low -> CSTART ->
// per word: wait TXP, write TXDR; wait RXP, read RXDR -> wait EOT -> clear
// EOT/TXTF in IFCR -> SPE=0 -> CS high. With DSIZE > 16 a 32-bit TXDR/RXDR
// access moves exactly one frame, so no packing surprises.
//
// The board uses it for the AD5764 chain's boot write on SPI1. The 20 kHz
// interrupt paths are register-level drivers of their own, not this master:
// the chain's writes from SPI1's end-of-transfer interrupt are
// ad5764::Stm32IrqWriter (drivers/ad5764_dac), which takes SPI1 over after
// the boot write; the AD7606 pair is read by the SPI3 RX DMA with
// ad7606::Stm32DmaReader (drivers/ad7606_adc).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/bus.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers {

struct SpiDeviceSettings {
  OutputPin* chip_select;      // active low
  std::uint8_t clock_divider_log2;  // SCLK = kernel / 2^(n+1): MBR code n (0 -> /2 ... 7 -> /256)
  bool cpol;
  bool cpha;
};

template <stm32h7::RegisterBus Bus, std::size_t kDevices = 2>
class Stm32SpiMaster final : public SpiMaster {
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
    bus_.write32(base_ + s::kCfg2, s::cfg2_master(false, false));
    for (std::size_t i = 0; i < kDevices; ++i) devices_[i].chip_select->write(true);
  }

  BusStatus transfer(const SpiTransfer& t) override {
    namespace s = stm32h7::spi;
    if (!valid(t)) return BusStatus::kBadArgument;
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
    end_frame(d);
    return status;
  }

 private:
  bool valid(const SpiTransfer& t) const {
    return t.device < kDevices && t.word_bits >= 4 && t.word_bits <= 32 && t.words != 0 && t.words <= 0xFFFF;
  }
  const SpiDeviceSettings& begin_frame(const SpiTransfer& t) {
    namespace s = stm32h7::spi;
    const SpiDeviceSettings& d = devices_[t.device];
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);  // SPE = 0: configuration registers writable
    bus_.write32(base_ + s::kCfg1, s::cfg1(d.clock_divider_log2, t.word_bits));
    bus_.write32(base_ + s::kCfg2, s::cfg2_master(d.cpol, d.cpha));
    bus_.write32(base_ + s::kCr2, static_cast<std::uint32_t>(t.words));
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    d.chip_select->write(false);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
    return d;
  }
  void end_frame(const SpiDeviceSettings& d) {
    namespace s = stm32h7::spi;
    bus_.write32(base_ + s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);
    d.chip_select->write(true);
  }

  Bus& bus_;
  stm32h7::Addr base_;
  std::uint32_t max_polls_;
  SpiDeviceSettings devices_[kDevices]{};
};

}  // namespace maglev::drivers
