// Saturation helpers and the 64-bit position -> Scalar error conversion.
#pragma once

#include <cstdint>

#include "maglev/numeric/int64_double.hpp"
#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::numeric {

template <typename T>
constexpr T clamp(T v, T lo, T hi) {
  return v < lo ? lo : (hi < v ? hi : v);
}

// Symmetric clamp to [-limit, limit] (limit >= 0).
template <typename T>
constexpr T clamp_abs(T v, T limit) {
  return clamp(v, -limit, limit);
}
// float: one |v| test (VABS and one compare on the M7, the two-sided clamp
// took two): the same value for every v -- inside, v itself; outside, the
// limit with v's sign; NaN fails the test and passes through, as it fails
// both of clamp's (issue 16: the six loop outputs a tick).
template <>
constexpr float clamp_abs(float v, float limit) {
  return __builtin_fabsf(v) > limit ? (v > 0.0f ? limit : -limit) : v;
}

// Picometres (or picoradians) per kernel unit (um or urad).
inline constexpr std::int64_t kPicoPerMicro = 1000000;

// Converts a 64-bit fixed-point position difference (1 pm or 1 prad per LSB)
// to a Scalar in um (urad). The result saturates cleanly at the Scalar range
// (+-128 um for both float and Q7.24, see ScalarTraits<float>::kMaxMagnitude):
// a huge difference (e.g. a lost interferometer count) gives +-max, never a
// wrapped value. Q7.24: the exact quotient rounded half away from zero.
template <typename Scalar>
constexpr Scalar pico_to_micro(std::int64_t diff_pico) {
  using Traits = ScalarTraits<Scalar>;
  if constexpr (Traits::kIsFixed) {
    // The same raw as the exact integer form (pico_to_micro_exact, below)
    // from one double product and one 32-bit VCVT, with no int64 division
    // estimate and remainder tests (~33 M7 instructions an axis, issue 16).
    // Why it is exact: the quotient d 2^F / 10^6 = d 2^(F-6) / 5^6 has an odd
    // denominator, so it is never a tie and lies at least 1/31250 = 3.2e-5
    // from every half-integer; the double product (d exact below 2^53, the
    // factor and the product each rounded once) and the + 0.5 are within
    // 7.3e-7 of it wherever |q| < 2^31 (beyond, both saturate), so
    // truncating q + 0.5 rounds as the exact form does, ties away from zero
    // on both sides by symmetry. kernel_numeric_test compares the two over
    // every boundary and a dense sweep.
    constexpr int F = Scalar::kFracBits;
    static_assert(F >= 6, "the no-tie argument needs 2^F / 10^6 to have an odd denominator");
    constexpr double kRawPerPico = detail::pow2(F) / 1e6;
    const double q = Int64ToDouble(diff_pico) * kRawPerPico;
    if (q >= 0.0) {
      const double t = q + 0.5;
      return Scalar::from_raw_in_range(t < 2147483648.0 ? static_cast<std::int32_t>(t) : detail::kRaw32Max);
    }
    const double t = 0.5 - q;
    return Scalar::from_raw_in_range(t < 2147483648.0 ? -static_cast<std::int32_t>(t) : detail::kRaw32Min);
  } else {
    // No int64 clamp (two 64-bit compares and selects on the M7): the
    // conversion is exact below 2^53 pm, and from_double's own clamp at
    // +-128 um does what the clamp at 130 um did (both saturate), so the
    // bits are those of the clamped form for every diff (issue 16).
    return Traits::from_double(Int64ToDouble(diff_pico) * 1e-6);
  }
}

// The definition pico_to_micro's fixed-point form must agree with: the
// difference clamped, then exact integer division, round half away from zero.
template <typename Scalar>
constexpr Scalar pico_to_micro_exact(std::int64_t diff_pico) {
  // 2^31 / 2^24 um = 128 um = 1.28e8 pm; clamp first so the product below
  // cannot overflow (1.3e8 * 2^24 ~ 2.2e15 << 2^63).
  constexpr std::int64_t kClampPico = 130000000;
  const std::int64_t d = diff_pico > kClampPico ? kClampPico : (diff_pico < -kClampPico ? -kClampPico : diff_pico);
  constexpr int F = Scalar::kFracBits;
  const std::int64_t raw = detail::div_round(d * (std::int64_t{1} << F), kPicoPerMicro);
  return Scalar::from_raw_in_range(detail::saturate32(raw));
}

// Positions in um (urad) as double -> 64-bit pm (prad), round half away from
// zero, saturating at +-2^62 (4.6e6 m: never reached by a real stage).
constexpr std::int64_t micro_to_pico(double micro) {
  return detail::double_to_raw(micro * 1e6, 4611686018427387904.0);
}
constexpr std::int64_t si_to_pico(double si) {  // m or rad -> pm or prad
  return detail::double_to_raw(si * 1e12, 4611686018427387904.0);
}

}  // namespace maglev::numeric
