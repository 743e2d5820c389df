// Exact wide integer helpers for the pose arithmetic.
//
// Positions are int64 pm / prad. Scaling them by a non-integer coefficient
// (an ADC gain, a 1/separation, a plane-fit inverse) needs a 64 x 64 bit
// product, and arm32 has no __int128. So the product is formed from 32-bit
// limbs here: portable, branch-light, and identical on host and target.
#pragma once

#include <cstdint>

namespace maglev::kernel::wide {

// Coefficients are "Q40" int64: value = coeff / 2^40. Range +-2^23 (8.4e6),
// resolution 9.1e-13. With |position| < 2^40 pm (1.1 m) the coefficient
// quantisation costs < 0.5 pm, far under the 618 pm interferometer LSB.
inline constexpr int kCoeffShift = 40;

struct U128 {
  std::uint64_t hi;
  std::uint64_t lo;
};

// Full unsigned 64 x 64 -> 128 product from four 32 x 32 -> 64 partials.
constexpr U128 MulU64(std::uint64_t a, std::uint64_t b) {
  const std::uint64_t a_lo = a & 0xffffffffu;
  const std::uint64_t a_hi = a >> 32;
  const std::uint64_t b_lo = b & 0xffffffffu;
  const std::uint64_t b_hi = b >> 32;
  const std::uint64_t ll = a_lo * b_lo;
  const std::uint64_t lh = a_lo * b_hi;
  const std::uint64_t hl = a_hi * b_lo;
  const std::uint64_t hh = a_hi * b_hi;
  const std::uint64_t mid = (ll >> 32) + (lh & 0xffffffffu) + (hl & 0xffffffffu);
  U128 r{};
  r.lo = (ll & 0xffffffffu) | (mid << 32);
  r.hi = hh + (lh >> 32) + (hl >> 32) + (mid >> 32);
  return r;
}

// round(a * coeff / 2^shift), 1 <= shift <= 63, rounding half AWAY from zero
// (symmetric, so a mirrored input gives a mirrored output). The caller keeps
// the result inside int64 (true for every pose quantity by a wide margin).
constexpr std::int64_t MulShiftRound(std::int64_t a, std::int64_t coeff, int shift = kCoeffShift) {
  const bool negative = (a < 0) != (coeff < 0);
  // Magnitudes as uint64; -INT64_MIN is representable as uint64.
  const std::uint64_t ua = a < 0 ? (~static_cast<std::uint64_t>(a) + 1u) : static_cast<std::uint64_t>(a);
  const std::uint64_t uc =
      coeff < 0 ? (~static_cast<std::uint64_t>(coeff) + 1u) : static_cast<std::uint64_t>(coeff);
  U128 p = MulU64(ua, uc);
  // + 2^(shift-1) for rounding, with carry into hi.
  const std::uint64_t half = std::uint64_t{1} << (shift - 1);
  const std::uint64_t lo = p.lo + half;
  p.hi += (lo < p.lo) ? 1u : 0u;
  p.lo = lo;
  const std::uint64_t mag = (p.lo >> shift) | (p.hi << (64 - shift));
  const std::int64_t smag = static_cast<std::int64_t>(mag);
  return negative ? -smag : smag;
}

// Q40 coefficient from a double (configuration time only).
constexpr std::int64_t ToQ40(double value) {
  const double scaled = value * 1099511627776.0;  // 2^40
  return static_cast<std::int64_t>(scaled < 0.0 ? scaled - 0.5 : scaled + 0.5);
}

// floor division and non-negative modulo for int64 (C++ '/' truncates).
constexpr std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  const std::int64_t r = a % b;
  return ((r != 0) && ((r < 0) != (b < 0))) ? q - 1 : q;
}
constexpr std::int64_t FloorMod(std::int64_t a, std::int64_t b) { return a - FloorDiv(a, b) * b; }

}  // namespace maglev::kernel::wide
