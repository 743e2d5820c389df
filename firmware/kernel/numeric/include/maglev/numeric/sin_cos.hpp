// Commutation sine/cosine from one shared quarter-wave table.
//
// The phase is a uint32 fraction of one turn (2^32 = 2*pi), so it wraps for
// free and a position -> phase conversion is a single integer multiply.
// The table holds sin(k * pi/2 / 1024), k = 0..1024, as Q1.30 integers; it is
// computed at compile time by a Taylor series in double (no libm, identical
// bits on host and target). Lookup: 2 quadrant bits, 10 index bits, 20
// interpolation bits, linear interpolation in int64.
//
// Error bound (tested against std::sin/std::cos over a dense sweep and at
// every knot): linear interpolation error <= h^2/8 with h = pi/2048, i.e.
// 2.95e-7, plus the Q1.30 rounding (4.7e-10). Result conversion adds
// <= 6e-8 (float) or <= 0.5 LSB = 3e-8 (Q7.24). Stated bound:
//   |error| <= 4.0e-7 (float)  and  <= 7 LSB of Q7.24 (4.2e-7).
#pragma once

#include <array>
#include <cstdint>

namespace maglev::numeric {

inline constexpr int kSinTableBits = 10;
inline constexpr int kSinTableSize = 1 << kSinTableBits;  // knots per quarter turn
inline constexpr int kSinTableFracBits = 30;               // Q1.30 entries

namespace detail {

constexpr double taylor_sin(double x) {
  // x in [0, pi/2]: the series converges to full double precision in < 20 terms.
  double term = x;
  double sum = x;
  for (int n = 1; n < 20; ++n) {
    term *= -x * x / static_cast<double>((2 * n) * (2 * n + 1));
    sum += term;
  }
  return sum;
}

constexpr std::array<std::int32_t, kSinTableSize + 1> make_sin_table() {
  std::array<std::int32_t, kSinTableSize + 1> t{};
  constexpr double kHalfPi = 1.57079632679489661923;
  for (int k = 0; k <= kSinTableSize; ++k) {
    const double v = taylor_sin(kHalfPi * static_cast<double>(k) / kSinTableSize) * 1073741824.0;
    t[static_cast<std::size_t>(k)] = static_cast<std::int32_t>(v + 0.5);
  }
  return t;
}

}  // namespace detail

inline constexpr std::array<std::int32_t, kSinTableSize + 1> kQuarterSineTable = detail::make_sin_table();

namespace detail {
// The quarter wave at x in [0, 2^30] (x = 2^30: the last knot): 10 index
// bits, 20 interpolation bits, linear interpolation (frac != 0 implies
// index < 1024). The knots lie in [0, 2^30] and never fall (checked at
// compile time below), so the step d between two is an unsigned 32-bit
// value and d * frac one 32 x 32 -> 64 multiply (UMULL on the M7); as
// int64 x int64 it was a three-instruction multiply and a borrow chain
// (~4 M7 instructions more per call, four to eight calls a tick). The same
// integers, so the same bits.
constexpr bool QuarterSineTableRises() {
  for (int k = 0; k < kSinTableSize; ++k) {
    if (kQuarterSineTable[static_cast<std::size_t>(k) + 1] < kQuarterSineTable[static_cast<std::size_t>(k)]) return false;
  }
  return kQuarterSineTable[0] == 0 && kQuarterSineTable[kSinTableSize] == (1 << 30);
}
static_assert(QuarterSineTableRises(), "quarter_wave_q30's unsigned step needs a table that never falls");

constexpr std::int32_t quarter_wave_q30(std::uint32_t x) {
  const std::uint32_t index = x >> (30 - kSinTableBits);
  const std::uint32_t frac = x & ((1u << (30 - kSinTableBits)) - 1u);
  std::int32_t v = kQuarterSineTable[index];
  if (frac != 0) {
    const auto d = static_cast<std::uint32_t>(kQuarterSineTable[index + 1] - v);
    const std::uint64_t p = std::uint64_t{d} * frac;
    v += static_cast<std::int32_t>((p + (std::uint64_t{1} << (29 - kSinTableBits))) >> (30 - kSinTableBits));
  }
  return v;
}
}  // namespace detail

// sin(2*pi*phase/2^32) as Q1.30 (exactly +-2^30 at the peaks).
constexpr std::int32_t sin_q30(std::uint32_t phase) {
  const std::uint32_t quadrant = phase >> 30;
  std::uint32_t p = phase & 0x3FFFFFFFu;   // position within the quadrant
  if (quadrant & 1u) p = 0x40000000u - p;  // mirror: 1..2^30
  const std::int32_t v = detail::quarter_wave_q30(p);
  return quadrant >= 2 ? -v : v;
}

constexpr std::int32_t cos_q30(std::uint32_t phase) { return sin_q30(phase + 0x40000000u); }


// sin_q30(phase) and cos_q30(phase), the same bits, with the quadrant
// decoded once: a quarter turn added changes only the quadrant bits, so the
// two read the quarter wave at p and at 2^30 - p (p = phase within its
// quadrant), which one by the quadrant's parity.
struct SinCosQ30 {
  std::int32_t sin;
  std::int32_t cos;
};
constexpr SinCosQ30 sin_cos_q30(std::uint32_t phase) {
  const std::uint32_t quadrant = phase >> 30;
  const std::uint32_t p = phase & 0x3FFFFFFFu;
  const std::int32_t at_p = detail::quarter_wave_q30(p);
  const std::int32_t at_mirror = detail::quarter_wave_q30(0x40000000u - p);
  const bool odd = (quadrant & 1u) != 0;
  const std::int32_t s = odd ? at_mirror : at_p;
  const std::int32_t c = odd ? at_p : at_mirror;
  // sin < 0 in quadrants 2, 3; cos (= sin one quadrant on) in 1, 2.
  return {quadrant >= 2 ? -s : s, (quadrant == 1 || quadrant == 2) ? -c : c};
}

// sin_cos_q30(phase + quarters * 2^30) from sin_cos_q30(phase), exactly: a
// whole quarter turn changes only the quadrant bits, so the same two table
// values come back swapped and negated (sin(p + 1/4) = cos p,
// cos(p + 1/4) = -sin p).
constexpr SinCosQ30 rotate_quarters(SinCosQ30 v, unsigned quarters) {
  switch (quarters & 3u) {
    case 1u:
      return {v.cos, -v.sin};
    case 2u:
      return {-v.sin, -v.cos};
    case 3u:
      return {-v.cos, v.sin};
    default:
      return v;
  }
}

template <typename Scalar>
struct SinCos {
  Scalar sin;
  Scalar cos;
};

}  // namespace maglev::numeric
