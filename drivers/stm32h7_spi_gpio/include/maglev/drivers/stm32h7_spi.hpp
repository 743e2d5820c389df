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
    bus_.write32(base_ + s::kCfg2, s::kCfg2Master | s::kCfg2Ssm | s::kCfg2Afcntr);
    for (std::size_t i = 0; i < kDevices; ++i) devices_[i].chip_select->write(true);
  }

  BusStatus transfer(const SpiTransfer& t) override {
    namespace s = stm32h7::spi;
    if (t.device >= kDevices || t.word_bits < 4 || t.word_bits > 32 || t.words == 0 || t.words > 0xFFFF) {
      return BusStatus::kBadArgument;
    }
    const SpiDeviceSettings& d = devices_[t.device];
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);  // SPE = 0: configuration registers writable
    bus_.write32(base_ + s::kCfg1, stm32h7::field(d.clock_divider_log2 & 7u, s::kCfg1MbrShift) |
                                       static_cast<std::uint32_t>(t.word_bits - 1u));
    bus_.write32(base_ + s::kCfg2, s::kCfg2Master | s::kCfg2Ssm | s::kCfg2Afcntr |
                                       (d.cpol ? s::kCfg2Cpol : 0u) | (d.cpha ? s::kCfg2Cpha : 0u));
    bus_.write32(base_ + s::kCr2, static_cast<std::uint32_t>(t.words));
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe);
    d.chip_select->write(false);
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart);
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
    bus_.write32(base_ + s::kIfcr, stm32h7::bit(3) | stm32h7::bit(4));  // EOTC | TXTFC
    bus_.write32(base_ + s::kCr1, s::kCr1Ssi);
    d.chip_select->write(true);
    return status;
  }

 private:
  Bus& bus_;
  stm32h7::Addr base_;
  std::uint32_t max_polls_;
  SpiDeviceSettings devices_[kDevices]{};
};

}  // namespace maglev::drivers
