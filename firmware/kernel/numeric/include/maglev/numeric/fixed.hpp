// Saturating fixed-point arithmetic for the control kernel.
//
// Fixed<F>   : int32 storage, Q(31-F).F. The kernel default is Q7.24
//              (range +-128, LSB 2^-24 = 5.96e-8): in kernel units (um, urad,
//              A) every servo signal is O(1), see docs/SCALING.md.
// Wide<F>    : int64 storage, Q(63-F).F, the accumulator for integrator and
//              filter states (default Q31.32, LSB 2.3e-10), so that tiny
//              per-tick increments (1 nm * Ki*T ~ 2.4e-7 A) are not lost.
//
// Every operation saturates to the symmetric range [-INT32_MAX, INT32_MAX]
// (resp. [-INT64_MAX, INT64_MAX]) and never invokes undefined behaviour:
// products and quotients use int64 intermediates (|a*b| < 2^62).
//
// ROUNDING (stated and tested): multiply, divide, conversion from double and
// narrowing a Wide to a Fixed all round to nearest, ties AWAY FROM ZERO, so
// the error is symmetric in sign (no drift towards -inf in integrators fed by
// a zero-mean signal). The one exception is Wide * coefficient
// (Wide::mul), which rounds ties towards +inf (floor(x + 1/2)); it is only
// used on the internal-model resonator states where the tie case has
// probability 2^-28.
#pragma once

#include <compare>
#include <cstdint>
#include <limits>
#include "maglev/numeric/int64_double.hpp"

namespace maglev::numeric {

namespace detail {

inline constexpr std::int32_t kRaw32Max = std::numeric_limits<std::int32_t>::max();
inline constexpr std::int32_t kRaw32Min = -kRaw32Max;  // symmetric: -x never overflows
inline constexpr std::int64_t kRaw64Max = std::numeric_limits<std::int64_t>::max();
inline constexpr std::int64_t kRaw64Min = -kRaw64Max;

constexpr std::int32_t saturate32(std::int64_t v) {
  if (v > kRaw32Max) return kRaw32Max;
  if (v < kRaw32Min) return kRaw32Min;
  return static_cast<std::int32_t>(v);
}

constexpr std::int64_t saturate64_add(std::int64_t a, std::int64_t b) {
  std::int64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return a > 0 ? kRaw64Max : kRaw64Min;
  if (r < kRaw64Min) return kRaw64Min;
  return r;
}

// Right shift by s >= 0 bits, rounding to nearest, ties away from zero.
// Valid for every v in [-INT64_MAX, INT64_MAX] (works on the magnitude in
// uint64, so v + half can never overflow). The magnitude form is also the
// cheap one on the M7: GCC then saturates a product with one unsigned
// compare per sign (measured: a branch-free floor/remainder form made the
// Q7.24 tick 2 400 instructions heavier).
constexpr std::int64_t shift_round(std::int64_t v, int s) {
  if (s <= 0) return v;
  const std::uint64_t half = std::uint64_t{1} << (s - 1);
  if (v >= 0) {
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(v) + half) >> s);
  }
  const std::uint64_t mag = std::uint64_t{0} - static_cast<std::uint64_t>(v);
  return -static_cast<std::int64_t>((mag + half) >> s);
}

// a + b and a - b saturated to [-INT32_MAX, INT32_MAX] for a, b in that
// range: the 32-bit operation and its overflow flag instead of a 64-bit sum
// and two 64-bit compares. On overflow the true result lies beyond the
// range on the side of its sign (a's sign for a sum of two same-signed
// values; a > b for a difference); without overflow it is exact, and the
// one value outside the symmetric range, INT32_MIN, goes to -INT32_MAX.
constexpr std::int32_t add_sat32(std::int32_t a, std::int32_t b) {
  std::int32_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return a > 0 ? kRaw32Max : kRaw32Min;
  return r < kRaw32Min ? kRaw32Min : r;
}
constexpr std::int32_t sub_sat32(std::int32_t a, std::int32_t b) {
  std::int32_t r = 0;
  if (__builtin_sub_overflow(a, b, &r)) return a > b ? kRaw32Max : kRaw32Min;
  return r < kRaw32Min ? kRaw32Min : r;
}

// Left shift by s >= 0 bits with saturation.
constexpr std::int64_t shift_left_sat(std::int64_t v, int s) {
  if (s <= 0) return v;
  const std::int64_t limit = kRaw64Max >> s;
  if (v > limit) return kRaw64Max;
  if (v < -limit) return kRaw64Min;
  return v * (std::int64_t{1} << s);
}

// n / d rounded to nearest, ties away from zero. d != 0.
constexpr std::int64_t div_round(std::int64_t n, std::int64_t d) {
  const bool negative = (n < 0) != (d < 0);
  const std::uint64_t un = n < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(n) : static_cast<std::uint64_t>(n);
  const std::uint64_t ud = d < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(d) : static_cast<std::uint64_t>(d);
  const std::uint64_t q = DivRoundHalfUp(un, ud);  // (un + ud / 2) / ud, no libgcc division
  return negative ? -static_cast<std::int64_t>(q) : static_cast<std::int64_t>(q);
}

// a0 b0 + a1 b1 exactly: each product of raws in [-INT32_MAX, INT32_MAX] is
// at most (2^31 - 1)^2 < 2^62 in magnitude, so the sum is below 2^63.
constexpr std::int64_t product_sum2(std::int32_t a0, std::int32_t b0, std::int32_t a1, std::int32_t b1) {
  return std::int64_t{a0} * b0 + std::int64_t{a1} * b1;
}

constexpr double pow2(int n) {
  double r = 1.0;
  for (int i = 0; i < n; ++i) r *= 2.0;
  for (int i = 0; i > n; --i) r *= 0.5;
  return r;
}

// The general path (and the definition double_to_raw must agree with).
constexpr std::int64_t double_to_raw_general(double scaled, double limit) {
  if (!(scaled == scaled)) return 0;  // NaN
  if (scaled >= limit) return static_cast<std::int64_t>(limit);
  if (scaled <= -limit) return -static_cast<std::int64_t>(limit);
  // Below 2^51 without libgcc's __aeabi_d2lz (int64_double.hpp): the same value.
  const double t = scaled >= 0.0 ? scaled + 0.5 : scaled - 0.5;
  return (t < 2251799813685248.0 && t > -2251799813685248.0) ? TruncToInt64(t) : static_cast<std::int64_t>(t);
}

// double -> integer of the given symmetric limit, round half away from zero,
// NaN -> 0, saturating. No libm.
//
// The common case first: |scaled| below both the limit and 2^51 - 1, so
// scaled +- 0.5 rounds into [0, 2^51) in magnitude and truncates with
// 32-bit VCVTs (int64_double.hpp). Round half away from zero is odd, and
// 0.5 - scaled is exactly -(scaled - 0.5) in IEEE arithmetic, so the
// negative side is the positive one negated: one sign test instead of the
// NaN test, two limit tests, a sign test for +- 0.5 and two range tests
// (about 12 fewer M7 instructions per conversion; several per tick). NaN
// fails both comparisons and takes the general path above, as do values
// at or beyond either bound. Same value for every input (numeric_test
// checks it against the general path).
constexpr std::int64_t double_to_raw(double scaled, double limit) {
  constexpr double kFast = 2251799813685247.0;  // 2^51 - 1
  const double bound = limit < kFast ? limit : kFast;
  if (scaled >= 0.0) {
    if (scaled < bound) return TruncNonNegativeToInt64(scaled + 0.5);
  } else if (scaled > -bound) {
    return -TruncNonNegativeToInt64(0.5 - scaled);
  }
  return double_to_raw_general(scaled, limit);
}

}  // namespace detail

template <int FracBits>
class Fixed {
  static_assert(FracBits >= 1 && FracBits <= 30, "Fixed<F>: 1 <= F <= 30");

 public:
  static constexpr int kFracBits = FracBits;
  static constexpr double kLsb = detail::pow2(-FracBits);
  static constexpr double kMaxValue = static_cast<double>(detail::kRaw32Max) * kLsb;

  constexpr Fixed() = default;

  static constexpr Fixed from_raw(std::int32_t raw) {
    Fixed f;
    f.raw_ = raw < detail::kRaw32Min ? detail::kRaw32Min : raw;
    return f;
  }
  // A raw already in [-INT32_MAX, INT32_MAX]: what every operation below
  // produces (saturate32, add_sat32 / sub_sat32 and double_to_raw clamp
  // there, and -raw_ of a raw in range stays in range). from_raw's own
  // clamp (INT32_MIN -> -INT32_MAX) is for raws from outside; after these it
  // never acts, and GCC cannot see that through the int64 arithmetic: it
  // cost ~2 M7 instructions an operation, ~400 a Q7.24 tick (issue 16).
  static constexpr Fixed from_raw_in_range(std::int32_t raw) {
    Fixed f;
    f.raw_ = raw;
    return f;
  }
  static constexpr Fixed from_double(double v) {
    // 2147483647.0 is exact in double; values at/above it saturate.
    return from_raw_in_range(static_cast<std::int32_t>(
        detail::double_to_raw(v * detail::pow2(FracBits), static_cast<double>(detail::kRaw32Max))));
  }
  static constexpr Fixed from_float(float v) { return from_double(static_cast<double>(v)); }
  static constexpr Fixed from_int(std::int32_t v) {
    return from_raw_in_range(detail::saturate32(detail::shift_left_sat(v, FracBits)));
  }
  static constexpr Fixed max() { return from_raw(detail::kRaw32Max); }
  static constexpr Fixed min() { return from_raw(detail::kRaw32Min); }
  static constexpr Fixed zero() { return from_raw(0); }
  static constexpr Fixed one() { return from_raw(std::int32_t{1} << FracBits); }

  constexpr std::int32_t raw() const { return raw_; }
  constexpr double to_double() const { return static_cast<double>(raw_) * kLsb; }
  // raw rounded to float, then scaled by the exact power of two 2^-F: the
  // same value as rounding raw 2^-F (exact in double) to float, because a
  // power-of-two scale commutes with rounding when nothing goes subnormal;
  // two instructions fewer on the M7 (no double). kernel_numeric_test
  // compares the two.
  constexpr float to_float() const { return static_cast<float>(raw_) * static_cast<float>(kLsb); }

  constexpr auto operator<=>(const Fixed&) const = default;

  constexpr Fixed operator-() const { return from_raw_in_range(-raw_); }  // raw_ >= -INT32_MAX
  friend constexpr Fixed operator+(Fixed a, Fixed b) {
    return from_raw_in_range(detail::add_sat32(a.raw_, b.raw_));
  }
  friend constexpr Fixed operator-(Fixed a, Fixed b) {
    return from_raw_in_range(detail::sub_sat32(a.raw_, b.raw_));
  }
  friend constexpr Fixed operator*(Fixed a, Fixed b) {
    return from_raw_in_range(detail::saturate32(detail::shift_round(std::int64_t{a.raw_} * b.raw_, FracBits)));
  }
  // Division by zero saturates towards the sign of the dividend (0/0 = 0).
  friend constexpr Fixed operator/(Fixed a, Fixed b) {
    if (b.raw_ == 0) return a.raw_ > 0 ? max() : (a.raw_ < 0 ? min() : zero());
    return from_raw_in_range(detail::saturate32(
        detail::div_round(std::int64_t{a.raw_} * (std::int64_t{1} << FracBits), b.raw_)));
  }
  constexpr Fixed& operator+=(Fixed b) { return *this = *this + b; }
  constexpr Fixed& operator-=(Fixed b) { return *this = *this - b; }
  constexpr Fixed& operator*=(Fixed b) { return *this = *this * b; }
  constexpr Fixed& operator/=(Fixed b) { return *this = *this / b; }

  // Product of two different formats, result in this format (rounded,
  // saturated): used for coefficient (Q3.28) * signal (Q7.24).
  template <int FB>
  static constexpr Fixed mul(Fixed<FB> coeff, Fixed v) {
    return from_raw_in_range(detail::saturate32(detail::shift_round(std::int64_t{coeff.raw()} * v.raw(), FB)));
  }

  // Sums of products rounded ONCE (issue 16): the exact int64 sum of the
  // raw products, then one shift with round half away from zero and one
  // saturation -- the value of rounding the exact sum, where a chain of
  // operator* and operator+ rounds and saturates every term (~17 M7
  // instructions a product, ~5 a sum; a dot3 is about half of its chain).
  // Each product of two raws in
  // [-INT32_MAX, INT32_MAX] is below 2^62 in magnitude, so two of them sum
  // exactly in int64; a third is added with saturation, and a sum that
  // saturated there is beyond the result's range on the same side, so the
  // result saturates as the exact sum's would.
  //   a0 b0 + a1 b1 (+ a2 b2), operands of this format.
  static constexpr Fixed dot2(Fixed a0, Fixed b0, Fixed a1, Fixed b1) {
    return round_product_sum<FracBits>(detail::product_sum2(a0.raw_, b0.raw_, a1.raw_, b1.raw_));
  }
  static constexpr Fixed dot3(Fixed a0, Fixed b0, Fixed a1, Fixed b1, Fixed a2, Fixed b2) {
    return round_product_sum<FracBits>(
        detail::saturate64_add(detail::product_sum2(a0.raw_, b0.raw_, a1.raw_, b1.raw_), std::int64_t{a2.raw_} * b2.raw_));
  }
  //   c0 v0 + c1 v1 for coefficients of format FB (Q3.28) and signals of this one.
  template <int FB>
  static constexpr Fixed mul_sum2(Fixed<FB> c0, Fixed v0, Fixed<FB> c1, Fixed v1) {
    return round_product_sum<FB>(detail::product_sum2(c0.raw(), v0.raw_, c1.raw(), v1.raw_));
  }
  // An exact sum of raw products whose LSB is 2^-(FracBits + FProduct)
  // (a product of this format with one of FProduct fraction bits), rounded
  // to this format and saturated.
  template <int FProduct>
  static constexpr Fixed round_product_sum(std::int64_t sum) {
    static_assert(FProduct >= 1 && FProduct <= 32);
    return from_raw_in_range(detail::saturate32(detail::shift_round(sum, FProduct)));
  }

 private:
  std::int32_t raw_ = 0;
};

using Q7_24 = Fixed<24>;
// Coefficient format for gains and filter taps in the fixed-point kernel:
// range +-8, LSB 3.7e-9 (the smallest default coefficient, ki T/2 of
// theta_x/y = 3.5e-6 A/(urad*tick), is then quantised to <= 0.053 %).
using Q3_28 = Fixed<28>;

// Wide accumulator, int64 Q(63-F).F. Saturating.
template <int FracBits = 32>
class Wide {
  static_assert(FracBits >= 1 && FracBits <= 48, "Wide<F>: 1 <= F <= 48");

 public:
  static constexpr int kFracBits = FracBits;
  static constexpr double kLsb = detail::pow2(-FracBits);

  constexpr Wide() = default;
  static constexpr Wide from_raw(std::int64_t raw) {
    Wide w;
    w.raw_ = raw < detail::kRaw64Min ? detail::kRaw64Min : raw;
    return w;
  }
  // A raw already in [-INT64_MAX, INT64_MAX] (Fixed::from_raw_in_range's
  // reason): every operation below clamps there itself.
  static constexpr Wide from_raw_in_range(std::int64_t raw) {
    Wide w;
    w.raw_ = raw;
    return w;
  }
  static constexpr Wide from_double(double v) {
    // 2^63 - 1024 is the largest double below 2^63; clamp there.
    return from_raw_in_range(detail::double_to_raw(v * detail::pow2(FracBits), 9223372036854774784.0));
  }
  template <int F>
  static constexpr Wide from_fixed(Fixed<F> v) {
    if constexpr (FracBits >= F) {
      return from_raw_in_range(detail::shift_left_sat(v.raw(), FracBits - F));
    } else {
      return from_raw_in_range(detail::shift_round(v.raw(), F - FracBits));
    }
  }
  template <int F>
  constexpr Fixed<F> to_fixed() const {
    if constexpr (FracBits >= F) {
      return Fixed<F>::from_raw_in_range(detail::saturate32(detail::shift_round(raw_, FracBits - F)));
    } else {
      return Fixed<F>::from_raw_in_range(detail::saturate32(detail::shift_left_sat(raw_, F - FracBits)));
    }
  }
  constexpr std::int64_t raw() const { return raw_; }
  constexpr double to_double() const { return static_cast<double>(raw_) * kLsb; }
  constexpr auto operator<=>(const Wide&) const = default;

  friend constexpr Wide operator+(Wide a, Wide b) { return from_raw_in_range(detail::saturate64_add(a.raw_, b.raw_)); }
  friend constexpr Wide operator-(Wide a, Wide b) { return from_raw_in_range(detail::saturate64_add(a.raw_, -b.raw_)); }
  constexpr Wide operator-() const { return from_raw_in_range(-raw_); }
  constexpr Wide& operator+=(Wide b) { return *this = *this + b; }
  constexpr Wide& operator-=(Wide b) { return *this = *this - b; }

  // this += a * b exactly (the int64 product of two int32 raws is exact),
  // aligned to FracBits with round-half-away-from-zero.
  template <int FA, int FB>
  constexpr void mac(Fixed<FA> a, Fixed<FB> b) {
    const std::int64_t p = std::int64_t{a.raw()} * b.raw();
    constexpr int kShift = FA + FB - FracBits;
    const std::int64_t aligned = kShift >= 0 ? detail::shift_round(p, kShift) : detail::shift_left_sat(p, -kShift);
    raw_ = detail::saturate64_add(raw_, aligned);
  }

  // this += a * (b0 + b1), rounded once (the Tustin integrator's
  // ki T/2 (e_k + e_{k-1})): b0 + b1 is exact in int64 (|.| < 2^32) and so is
  // its product with a (|.| < 2^63), where two mac() calls round twice.
  template <int FA, int FB>
  constexpr void mac_sum(Fixed<FA> a, Fixed<FB> b0, Fixed<FB> b1) {
    const std::int64_t p = std::int64_t{a.raw()} * (std::int64_t{b0.raw()} + b1.raw());
    constexpr int kShift = FA + FB - FracBits;
    const std::int64_t aligned = kShift >= 0 ? detail::shift_round(p, kShift) : detail::shift_left_sat(p, -kShift);
    raw_ = detail::saturate64_add(raw_, aligned);
  }

  // this * c, c in Q(31-FC).FC, FC <= 32: 64x32-bit product split into two
  // exact 64-bit partial products (no __int128 on Cortex-M), saturated.
  template <int FC>
  constexpr Wide mul(Fixed<FC> c) const {
    static_assert(FC <= 32);
    const std::int64_t hi = raw_ >> 32;  // floor
    const std::int64_t lo = static_cast<std::int64_t>(static_cast<std::uint64_t>(raw_) & 0xFFFFFFFFu);
    const std::int64_t p_hi = hi * c.raw();                         // |.| < 2^62
    const std::int64_t p_lo = lo * c.raw();                         // |.| < 2^63
    const std::int64_t lo_part = (p_lo + (std::int64_t{1} << (FC - 1))) >> FC;  // floor(x+1/2)
    std::int64_t hi_part = 0;
    if (__builtin_mul_overflow(p_hi, std::int64_t{1} << (32 - FC), &hi_part)) {
      return from_raw_in_range(p_hi > 0 ? detail::kRaw64Max : detail::kRaw64Min);
    }
    return from_raw_in_range(detail::saturate64_add(hi_part, lo_part));
  }

 private:
  std::int64_t raw_ = 0;
};

using Q31_32 = Wide<32>;

}  // namespace maglev::numeric
