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

// static_cast<std::int64_t>(v) (truncation toward zero) for 0 <= v < 2^51.
// v = q 2^32 + r with q = trunc(v 2^-32) (q < 2^19: one 32-bit VCVT, which
// truncates) and r = v - q 2^32: exact, because q 2^32 is a multiple of v's
// ulp and r <= v; 0 <= r < 2^32, so trunc(v) = q 2^32 + trunc(r), the last
// one unsigned 32-bit VCVT. (detail::double_to_raw, which knows the sign,
// calls it directly.)
constexpr std::int64_t TruncNonNegativeToInt64(double v) {
  const std::int32_t q = static_cast<std::int32_t>(v * 0x1.0p-32);
  const double r = v - static_cast<double>(q) * 0x1.0p32;
  return std::int64_t{q} * (std::int64_t{1} << 32) + std::int64_t{static_cast<std::uint32_t>(r)};
}

// The same value as static_cast<std::int64_t>(v) for |v| < 2^51: truncation
// is odd, so the negative side is the non-negative one of -v, negated. About
// 12 M7 instructions; the round-and-compare form this replaced took ~45 (it
// is on the tick's path through Fixed::from_double).
constexpr std::int64_t TruncToInt64(double v) {
  return v >= 0.0 ? TruncNonNegativeToInt64(v) : -TruncNonNegativeToInt64(-v);
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

// floor((n + floor(d / 2)) / d) exactly, for n <= 2^63 and d > 0 (rounding
// n / d half up: Fixed's division and the pico -> Q7.24 error). A uint64
// division is a libgcc call on the M7 (__aeabi_uldivmod -> __udivmoddi4,
// ~100-200 instructions). When d < 2^40 and the quotient is known to be below
// 2^50 (n < 2^50, or d >= 2^12 and n < 2^62) FloorDiv gives the same quotient
// from a double estimate and one exact remainder test each side (its q * d
// stays below 2^62 + 2^40: no overflow). Otherwise (never in the tick) the
// integer division.
constexpr std::uint64_t DivRoundHalfUp(std::uint64_t n, std::uint64_t d) {
  const std::uint64_t m = n + d / 2u;
  if (d < (std::uint64_t{1} << 40) &&
      (n < (std::uint64_t{1} << 50) || (d >= (std::uint64_t{1} << 12) && n < (std::uint64_t{1} << 62)))) {
    const auto md = static_cast<std::int64_t>(m), dd = static_cast<std::int64_t>(d);
    return static_cast<std::uint64_t>(FloorDiv(md, dd, 1.0 / Int64ToDouble(dd)));
  }
  return m / d;
}

// pm (prad) -> m (rad) as a float, the one form in which the kernel reports
// and checks a position or an error (the controller's supervisor inputs,
// fault values, the recorder): one correctly rounded conversion, product
// and narrowing each.
constexpr float PicoToSi(std::int64_t v) { return static_cast<float>(Int64ToDouble(v) * 1e-12); }

// Every step of PicoToSi is a correctly rounded, monotone operation, so
// PicoToSi is monotone (non-decreasing) and odd (round-to-nearest-even is
// symmetric: PicoToSi(-v) = -PicoToSi(v)). A comparison of PicoToSi(v) with
// a float limit is then a comparison of v with ONE integer, found once at
// configuration (a 64-step bisection) -- the supervisor's limit checks with
// no int64 -> float conversion in the tick, and the same outcome for every
// v with |v| <= 2^62 (4.6e6 m in pm: any pose and any difference of two):
//   PicoToSi(v) >  limit  <=>  v >= PicoFirstAbove(limit)
//   PicoToSi(v) <  limit  <=>  v <  PicoFirstAtOrAbove(limit)
//   |PicoToSi(v)| > limit <=>  |v| >= PicoFirstAbove(limit)   (limit >= 0)
// A limit no v in the domain passes gives 2^62 + 1 (never reached), one
// that every v passes gives -2^62.
inline constexpr std::int64_t kPicoDomain = std::int64_t{1} << 62;

template <typename Pred>
constexpr std::int64_t PicoFirstWhere(Pred holds) {
  std::int64_t lo = -kPicoDomain, hi = kPicoDomain;
  if (holds(lo)) return lo;
  if (!holds(hi)) return kPicoDomain + 1;
  // !holds(lo), holds(hi); hi - lo <= 2^63 is formed unsigned (no overflow).
  while (static_cast<std::uint64_t>(hi) - static_cast<std::uint64_t>(lo) > 1u) {
    const auto mid = static_cast<std::int64_t>(static_cast<std::uint64_t>(lo) +
                                               (static_cast<std::uint64_t>(hi) - static_cast<std::uint64_t>(lo)) / 2u);
    if (holds(mid)) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

constexpr std::int64_t PicoFirstAbove(float limit) {
  return PicoFirstWhere([limit](std::int64_t v) { return PicoToSi(v) > limit; });
}

constexpr std::int64_t PicoFirstAtOrAbove(float limit) {
  return PicoFirstWhere([limit](std::int64_t v) { return PicoToSi(v) >= limit; });
}

// |v| as uint64, exact for every int64 (INT64_MIN: 2^63).
constexpr std::uint64_t UnsignedMagnitude64(std::int64_t v) {
  return v < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
}

}  // namespace maglev::numeric
