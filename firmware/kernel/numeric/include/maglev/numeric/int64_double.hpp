// int64 <-> double without the C library's conversion helpers.
//
// On the Cortex-M7 (fpv5-d16) a double add or multiply is one instruction,
// but `(double)int64` and `(int64)double` are libgcc calls (__aeabi_l2d,
// __aeabi_d2lz and the soft-float code under them: 100-300 instructions per
// conversion, measured in the replay's QEMU trace). The servo tick keeps
// positions as int64 pm and does its arithmetic in float/double, so it
// converts a few dozen values per tick: these forms use only 32-bit VCVTs,
// one multiply-add and a bit reinterpretation. All are exact IEEE
// operations, so the host and the target give the same bits by construction.
#pragma once

#include <bit>
#include <cstdint>

namespace maglev::numeric {

// The same value as static_cast<double>(v) for every int64: hi * 2^32 and lo
// are exact doubles, and their sum is one correctly rounded addition.
constexpr double Int64ToDouble(std::int64_t v) {
  const std::int32_t hi = static_cast<std::int32_t>(v >> 32);
  const std::uint32_t lo = static_cast<std::uint32_t>(v);
  return static_cast<double>(hi) * 4294967296.0 + static_cast<double>(lo);
}

// Nearest int64 to v, ties to even (the FPU's rounding mode), for
// |v| < 2^51. Adding 1.5 * 2^52 puts v's integer part in the low 52 bits of
// the significand (the sum lies in [2^52, 2^53), where one ulp is 1).
constexpr std::int64_t RoundToInt64(double v) {
  const double shifted = v + 6755399441055744.0;
  const std::uint64_t bits = std::bit_cast<std::uint64_t>(shifted);
  return static_cast<std::int64_t>(bits & ((std::uint64_t{1} << 52) - 1u)) - (std::int64_t{1} << 51);
}

// The same value as static_cast<std::int64_t>(v) (truncation toward zero)
// for |v| < 2^51.
constexpr std::int64_t TruncToInt64(double v) {
  const std::int64_t nearest = RoundToInt64(v);
  const double back = Int64ToDouble(nearest);
  return nearest - (v >= 0.0 ? (back > v ? 1 : 0) : (back < v ? -1 : 0));
}

// floor(a / d) exactly, for d > 0 and |a / d| < 2^50, given inv_d = 1.0 / d:
// the double estimate is within one of the quotient (three roundings of
// 2^-53 relative each, plus the rounding to an integer), and one exact int64
// remainder test on each side corrects it. Replaces an int64 division
// (__aeabi_ldivmod on the M7) in the tick.
constexpr std::int64_t FloorDiv(std::int64_t a, std::int64_t d, double inv_d) {
  std::int64_t q = RoundToInt64(Int64ToDouble(a) * inv_d);
  const std::int64_t r = a - q * d;
  q -= r < 0 ? 1 : 0;
  q += r >= d ? 1 : 0;
  return q;
}

}  // namespace maglev::numeric
