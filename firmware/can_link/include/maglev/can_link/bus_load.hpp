// Bits on the wire per CAN / CAN FD frame (ISO 11898-1:2015), worst-case bit
// stuffing, and a BusLoadMeter that sums them for frames sent. The same
// function produces the budget table in docs/CAN.md.
//
// CAN FD, base format (11-bit ID), BRS set:
//   nominal rate: SOF 1 + ID 11 + RRS 1 + IDE 1 + FDF 1 + res 1 + BRS 1 = 17
//                 + worst-case dynamic stuff bits in those 17 bits (4)
//                 + CRC delimiter 1 + ACK 1 + ACK delimiter 1 + EOF 7 + IFS 3 = 13
//   data rate:    ESI 1 + DLC 4 + 8*len
//                 + remaining worst-case dynamic stuff bits: floor((L-1)/4) - 4
//                   with L = 22 + 8*len the dynamically stuffed length (SOF..data)
//                 + stuff count 4 + CRC 17 (len <= 16) or 21 (len > 16)
//                 + fixed stuff bits 6 (CRC17) or 7 (CRC21)
// The CRC delimiter is counted at the nominal rate (the bit rate switches
// back at its sample point), which errs on the slow side.
#pragma once

#include <cstdint>

#include "maglev/can_port/can_port.hpp"

namespace maglev::can {

struct BusTiming {
  std::uint32_t nominal_bps = 1'000'000;
  std::uint32_t data_bps = 5'000'000;
};

struct FrameBits {
  std::uint32_t nominal_bits;  // sent at the nominal (arbitration) rate
  std::uint32_t data_bits;     // sent at the data rate (0 without BRS)
  constexpr std::uint32_t total() const { return nominal_bits + data_bits; }
};

constexpr FrameBits can_frame_bits(std::uint8_t len, bool fd, bool brs, bool extended_id = false) {
  const std::uint32_t n = 8u * len;
  if (!fd) {
    // Classical CAN: SOF, ID(11|29+SRR+IDE), RTR, IDE/r1, r0, DLC 4, data,
    // CRC 15, then CRC delim, ACK, ACK delim, EOF 7, IFS 3.
    const std::uint32_t header = extended_id ? 1u + 11u + 1u + 1u + 18u + 1u + 2u + 4u : 1u + 11u + 1u + 1u + 1u + 4u;
    const std::uint32_t stuffed = header + n + 15u;
    const std::uint32_t stuff = (stuffed - 1u) / 4u;
    return FrameBits{stuffed + stuff + 13u, 0u};
  }
  const std::uint32_t arb = extended_id ? 1u + 11u + 1u + 1u + 18u + 1u + 1u + 1u + 1u : 17u;
  const std::uint32_t arb_stuff = (arb - 1u) / 4u;
  const std::uint32_t dyn = arb + 5u + n;
  const std::uint32_t dyn_stuff_total = (dyn - 1u) / 4u;
  const std::uint32_t crc = len <= 16 ? 17u : 21u;
  const std::uint32_t fixed_stuff = len <= 16 ? 6u : 7u;
  const std::uint32_t data_phase = 5u + n + (dyn_stuff_total - arb_stuff) + 4u + crc + fixed_stuff;
  const std::uint32_t tail = 13u;
  if (brs) return FrameBits{arb + arb_stuff + tail, data_phase};
  return FrameBits{arb + arb_stuff + tail + data_phase, 0u};
}

constexpr FrameBits can_frame_bits(const CanFrame& f) {
  return can_frame_bits(f.len, (f.flags & kFlagFd) != 0, (f.flags & kFlagBrs) != 0,
                        (f.flags & kFlagExtendedId) != 0);
}

// Time on the wire in nanoseconds.
constexpr std::uint64_t frame_time_ns(FrameBits b, BusTiming t = {}) {
  return std::uint64_t{b.nominal_bits} * 1'000'000'000ull / t.nominal_bps +
         std::uint64_t{b.data_bits} * 1'000'000'000ull / t.data_bps;
}

// The budget in the header comment, checked at compile time.
static_assert(can_frame_bits(32, true, true).nominal_bits == 34);
static_assert(can_frame_bits(32, true, true).data_bits == 358);
static_assert(frame_time_ns(can_frame_bits(20, true, true)) == 81'600);

// Sums the wire time of frames (sent or seen). Load = busy / elapsed.
class BusLoadMeter {
 public:
  explicit BusLoadMeter(BusTiming timing = {}) : timing_(timing) {}
  void on_frame(const CanFrame& f) {
    const FrameBits b = can_frame_bits(f);
    ++frames_;
    bits_ += b.total();
    busy_ns_ += frame_time_ns(b, timing_);
  }
  void reset() { frames_ = 0; bits_ = 0; busy_ns_ = 0; }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t bits() const { return bits_; }
  std::uint64_t busy_ns() const { return busy_ns_; }
  // Load in parts per million over an elapsed time (integer, target friendly).
  std::uint32_t load_ppm(std::uint64_t elapsed_ns) const {
    if (elapsed_ns == 0) return 0;
    return static_cast<std::uint32_t>(busy_ns_ * 1'000'000ull / elapsed_ns);
  }

 private:
  BusTiming timing_;
  std::uint64_t frames_ = 0;
  std::uint64_t bits_ = 0;
  std::uint64_t busy_ns_ = 0;
};

}  // namespace maglev::can
