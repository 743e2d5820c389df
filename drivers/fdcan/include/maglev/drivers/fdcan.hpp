// STM32H7 FDCAN (Bosch M_CAN, RM0433 §56) as a maglev::can::CanPort:
// CAN FD with bit-rate switching, 1 Mbit/s nominal / 5 Mbit/s data.
//
// Kernel clock: pll1_q = 80 MHz (firmware/board/stm32h743 clock tree,
// RCC_D2CCIP1R.FDCANSEL = 01). 80 MHz divides both rates exactly:
//   nominal: NBRP 1, 80 tq/bit = 1 + NTSEG1 63 + NTSEG2 16, SP 80.0 %, NSJW 16
//            -> FDCAN_NBTP = 0x1E003E0F (fields hold value - 1)
//   data:    DBRP 1, 16 tq/bit = 1 + DTSEG1 11 + DTSEG2 4, SP 75.0 %, DSJW 4,
//            TDC on -> FDCAN_DBTP = 0x00800A33
//   transmitter delay compensation: TDCO = DBRP * (1 + DTSEG1) = 12 mtq (the
//   secondary sample point sits at the data sample point), TDCF = 0 (no
//   filter window) -> FDCAN_TDCR = 0x00000C00. TDC is required above
//   ~1 Mbit/s data rate because the transceiver loop delay (~100-200 ns)
//   exceeds a data bit's sample point margin.
//
// Message RAM (RM0433 §56.4.1, 10 KB at 0x4000AC00 shared with FDCAN2; the
// start-address fields hold word addresses in bits [15:2], i.e. the byte
// offset from the RAM start):
//   +0x000  Rx FIFO 0: 16 elements x 72 bytes (2 header words + 64 data)
//   +0x480  Tx FIFO:    8 elements x 72 bytes
//   +0x6C0  end (1728 bytes); no filter elements: GFC accepts every standard
//           frame into FIFO 0 (ANFS = 00), rejects extended and remote frames.
#pragma once

#include <cstdint>

#include "maglev/can_port/can_port.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers::fdcan {

struct BitTiming {
  std::uint32_t prescaler;  // BRP
  std::uint32_t tseg1;      // prop + phase seg 1, in tq
  std::uint32_t tseg2;      // phase seg 2, in tq
  std::uint32_t sjw;        // in tq
  bool valid;
};

// Smallest prescaler (most time quanta per bit) that divides the bit exactly
// and fits the segment limits; sample point in per mille.
constexpr BitTiming compute_bit_timing(std::uint32_t kernel_Hz, std::uint32_t bitrate, std::uint32_t sample_permille,
                                       std::uint32_t max_brp, std::uint32_t max_tseg1, std::uint32_t max_tseg2,
                                       std::uint32_t max_sjw) {
  for (std::uint32_t brp = 1; brp <= max_brp; ++brp) {
    if (kernel_Hz % (brp * bitrate) != 0) continue;
    const std::uint32_t tq = kernel_Hz / (brp * bitrate);
    if (tq < 4 || tq > 1 + max_tseg1 + max_tseg2) continue;
    const std::uint32_t sync_plus_tseg1 = (tq * sample_permille + 500) / 1000;
    const std::uint32_t tseg1 = sync_plus_tseg1 - 1;
    const std::uint32_t tseg2 = tq - sync_plus_tseg1;
    if (tseg1 < 1 || tseg1 > max_tseg1 || tseg2 < 1 || tseg2 > max_tseg2) continue;
    return BitTiming{brp, tseg1, tseg2, tseg2 < max_sjw ? tseg2 : max_sjw, true};
  }
  return BitTiming{0, 0, 0, 0, false};
}
constexpr BitTiming nominal_timing(std::uint32_t kernel_Hz, std::uint32_t bitrate, std::uint32_t sp) {
  return compute_bit_timing(kernel_Hz, bitrate, sp, 512, 256, 128, 128);  // NBTP field widths
}
constexpr BitTiming data_timing(std::uint32_t kernel_Hz, std::uint32_t bitrate, std::uint32_t sp) {
  return compute_bit_timing(kernel_Hz, bitrate, sp, 32, 32, 16, 16);  // DBTP field widths
}
constexpr std::uint32_t nbtp_value(const BitTiming& t) {
  return ((t.sjw - 1) << 25) | ((t.prescaler - 1) << 16) | ((t.tseg1 - 1) << 8) | (t.tseg2 - 1);
}
constexpr std::uint32_t dbtp_value(const BitTiming& t, bool tdc) {
  return (tdc ? (1u << 23) : 0u) | ((t.prescaler - 1) << 16) | ((t.tseg1 - 1) << 8) | ((t.tseg2 - 1) << 4) |
         (t.sjw - 1);
}
constexpr std::uint32_t tdcr_value(const BitTiming& data, std::uint32_t filter_window) {
  return ((data.prescaler * (1 + data.tseg1)) << 8) | (filter_window & 0x7Fu);
}

inline constexpr std::uint32_t kKernelClock_Hz = 80'000'000;
inline constexpr std::uint32_t kElementBytes = 72;  // 8-byte header + 64 data bytes
inline constexpr std::uint32_t kRxFifoElements = 16;
inline constexpr std::uint32_t kTxFifoElements = 8;

struct Layout {
  std::uint32_t rx_fifo0;  // byte offsets from the message RAM start
  std::uint32_t tx_fifo;
  std::uint32_t end;
};
constexpr Layout layout(std::uint32_t ram_offset) {
  return Layout{ram_offset, ram_offset + kRxFifoElements * kElementBytes,
                ram_offset + (kRxFifoElements + kTxFifoElements) * kElementBytes};
}

struct Config {
  stm32h7::Addr base = stm32h7::fdcan::kFdcan1;
  std::uint32_t ram_offset = 0;  // FDCAN2 would take the space after FDCAN1's
  std::uint32_t kernel_Hz = kKernelClock_Hz;
  std::uint32_t nominal_bitrate = 1'000'000;
  std::uint32_t nominal_sample_permille = 800;
  std::uint32_t data_bitrate = 5'000'000;
  std::uint32_t data_sample_permille = 750;
  // Optional microsecond clock for receive() timeouts; null: receive() polls once.
  std::uint32_t (*now_us)() = nullptr;
};

enum class InitStatus : std::uint8_t { kOk = 0, kBadTiming, kTimeout };

template <stm32h7::RegisterBus Bus>
class Fdcan final : public can::CanPort {
 public:
  Fdcan(Bus& bus, const Config& config) : bus_(bus), config_(config), layout_(layout(config.ram_offset)) {}

  InitStatus init() {
    namespace f = stm32h7::fdcan;
    const BitTiming nominal = nominal_timing(config_.kernel_Hz, config_.nominal_bitrate, config_.nominal_sample_permille);
    const BitTiming data = data_timing(config_.kernel_Hz, config_.data_bitrate, config_.data_sample_permille);
    if (!nominal.valid || !data.valid) return InitStatus::kBadTiming;
    // RM0433 §56.4.1 "Software initialization": INIT, wait, then CCE.
    reg_write(f::kCccr, f::kCccrInit);
    if (!stm32h7::wait_for(bus_, config_.base + f::kCccr, f::kCccrInit, f::kCccrInit, 100000)) return InitStatus::kTimeout;
    reg_write(f::kCccr, f::kCccrInit | f::kCccrCce);
    reg_write(f::kNbtp, nbtp_value(nominal));
    reg_write(f::kDbtp, dbtp_value(data, true));
    reg_write(f::kTdcr, tdcr_value(data, 0));
    reg_write(f::kGfc, stm32h7::field(2u, 2) | stm32h7::bit(1) | stm32h7::bit(0));  // ANFE reject, RRFS/RRFE reject
    reg_write(f::kSidfc, 0u);
    reg_write(f::kXidfc, 0u);
    reg_write(f::kRxf0c, stm32h7::field(kRxFifoElements, 16) | (layout_.rx_fifo0 & 0xFFFCu));
    reg_write(f::kRxesc, 7u);  // F0DS = 64-byte data field
    reg_write(f::kTxbc, stm32h7::field(kTxFifoElements, 24) | (layout_.tx_fifo & 0xFFFCu));
    reg_write(f::kTxesc, 7u);  // TBDS = 64-byte data field
    reg_write(f::kIe, f::kIrRf0l | f::kIrBo | stm32h7::bit(0));  // RF0N, RF0L, BO (line 0)
    reg_write(f::kIle, stm32h7::bit(0));
    reg_write(f::kCccr, f::kCccrInit | f::kCccrCce | f::kCccrFdoe | f::kCccrBrse);
    reg_write(f::kCccr, f::kCccrFdoe | f::kCccrBrse);  // leave INIT: join the bus after 11 recessive bits
    if (!stm32h7::wait_for(bus_, config_.base + f::kCccr, f::kCccrInit, 0u, 100000)) return InitStatus::kTimeout;
    return InitStatus::kOk;
  }

  can::PortStatus send(const can::CanFrame& frame) override {
    namespace f = stm32h7::fdcan;
    const bool fd = (frame.flags & can::kFlagFd) != 0;
    if (frame.len > (fd ? can::kMaxCanFdPayload : 8u) || !can::is_valid_fd_len(frame.len)) {
      return fail(can::PortStatus::kBadFrame);
    }
    if ((reg_read(f::kPsr) & f::kPsrBo) != 0) return fail(can::PortStatus::kBusOff);
    const std::uint32_t txfqs = reg_read(f::kTxfqs);
    if ((txfqs & f::kTxfqsTfqf) != 0) return fail(can::PortStatus::kTxFull);
    const std::uint32_t index = (txfqs >> 16) & 0x1Fu;  // TFQPI
    const stm32h7::Addr element = stm32h7::fdcan::kMessageRam + layout_.tx_fifo + index * kElementBytes;
    const bool extended = (frame.flags & can::kFlagExtendedId) != 0;
    const std::uint32_t t0 = extended ? (f::kElemXtd | (frame.id & 0x1FFFFFFFu))
                                      : ((frame.id & 0x7FFu) << f::kElemStdIdShift);
    const std::uint32_t t1 = (fd ? f::kElemFdf : 0u) | ((fd && (frame.flags & can::kFlagBrs) != 0) ? f::kElemBrs : 0u) |
                             (static_cast<std::uint32_t>(can::len_to_dlc(frame.len)) << f::kElemDlcShift);
    bus_.write32(element, t0);
    bus_.write32(element + 4, t1);
    for (std::uint32_t w = 0; w < (frame.len + 3u) / 4u; ++w) {
      std::uint32_t word = 0;
      for (std::uint32_t b = 0; b < 4; ++b) {
        const std::uint32_t i = 4 * w + b;
        if (i < frame.len) word |= static_cast<std::uint32_t>(frame.data[i]) << (8 * b);
      }
      bus_.write32(element + 8 + 4 * w, word);
    }
    reg_write(f::kTxbar, 1u << index);
    ++counters_.tx_frames;
    return can::PortStatus::kOk;
  }

  can::PortStatus receive(can::CanFrame& frame, std::uint32_t timeout_us) override {
    namespace f = stm32h7::fdcan;
    const std::uint32_t start = config_.now_us != nullptr ? config_.now_us() : 0u;
    for (;;) {
      const std::uint32_t ir = reg_read(f::kIr);
      if ((ir & f::kIrRf0l) != 0) {
        ++counters_.rx_overruns;
        reg_write(f::kIr, f::kIrRf0l);  // write 1 to clear
      }
      const std::uint32_t rxf0s = reg_read(f::kRxf0s);
      if ((rxf0s & 0x7Fu) != 0) {  // F0FL: fill level
        const std::uint32_t index = (rxf0s >> 8) & 0x3Fu;  // F0GI
        read_element(stm32h7::fdcan::kMessageRam + layout_.rx_fifo0 + index * kElementBytes, frame);
        reg_write(f::kRxf0a, index);
        ++counters_.rx_frames;
        return can::PortStatus::kOk;
      }
      if (config_.now_us == nullptr || config_.now_us() - start >= timeout_us) break;
    }
    ++counters_.rx_timeouts;
    return can::PortStatus::kTimeout;
  }

  const can::PortCounters& counters() const override { return counters_; }
  const Layout& message_ram_layout() const { return layout_; }

 private:
  void read_element(stm32h7::Addr element, can::CanFrame& frame) {
    namespace f = stm32h7::fdcan;
    const std::uint32_t r0 = bus_.read32(element);
    const std::uint32_t r1 = bus_.read32(element + 4);
    const bool extended = (r0 & f::kElemXtd) != 0;
    frame.id = extended ? (r0 & 0x1FFFFFFFu) : ((r0 >> f::kElemStdIdShift) & 0x7FFu);
    frame.len = can::kDlcToLen[(r1 >> f::kElemDlcShift) & 0xFu];
    frame.flags = static_cast<std::uint8_t>(((r1 & f::kElemFdf) != 0 ? can::kFlagFd : 0) |
                                            ((r1 & f::kElemBrs) != 0 ? can::kFlagBrs : 0) |
                                            ((r0 & f::kElemEsi) != 0 ? can::kFlagEsi : 0) |
                                            (extended ? can::kFlagExtendedId : 0));
    for (std::uint32_t w = 0; w < (frame.len + 3u) / 4u; ++w) {
      const std::uint32_t word = bus_.read32(element + 8 + 4 * w);
      for (std::uint32_t b = 0; b < 4; ++b) {
        const std::uint32_t i = 4 * w + b;
        if (i < frame.len) frame.data[i] = static_cast<std::uint8_t>(word >> (8 * b));
      }
    }
  }
  can::PortStatus fail(can::PortStatus s) {
    ++counters_.tx_errors;
    return s;
  }
  std::uint32_t reg_read(stm32h7::Addr offset) { return bus_.read32(config_.base + offset); }
  void reg_write(stm32h7::Addr offset, std::uint32_t v) { bus_.write32(config_.base + offset, v); }

  Bus& bus_;
  Config config_;
  Layout layout_;
  can::PortCounters counters_{};
};

}  // namespace maglev::drivers::fdcan
