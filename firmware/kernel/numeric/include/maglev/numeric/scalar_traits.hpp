// ScalarTraits<Scalar>: the one place where float and fixed point differ.
//
// Kernel code is written once against these traits:
//   Scalar  the signal type (errors um/urad, efforts A)      float | Q7.24
//   Coeff   gains and filter taps                           float | Q3.28
//   Acc     integrator / filter accumulators                double| Q31.32
// float's accumulator is double because a float integrator holding ~1 A
// cannot absorb a 2.4e-7 A increment (float eps at 1 is 1.2e-7); the
// Cortex-M7 has a double-precision FPU, so this costs nothing in libm.
#pragma once

#include <cstdint>

#include "maglev/numeric/fixed.hpp"
#include "maglev/numeric/sin_cos.hpp"

namespace maglev::numeric {

template <typename Scalar>
struct ScalarTraits;

template <>
struct ScalarTraits<float> {
  using Scalar = float;
  using Coeff = float;
  using Acc = double;
  static constexpr bool kIsFixed = false;
  // Largest magnitude any kernel signal may take. Set equal to Q7.24's range
  // so that float and fixed kernels saturate identically.
  static constexpr double kMaxMagnitude = Q7_24::kMaxValue;
  static constexpr double kCoeffMaxMagnitude = 3.0e38;
  static constexpr float kMaxMagnitudeFloat = static_cast<float>(kMaxMagnitude);
  static_assert(kMaxMagnitudeFloat == 128.0f && kMaxMagnitude < 128.0);

  // Saturates at +-kMaxMagnitude. One |v| test (VABS and one compare on the
  // M7; the two-sided form took two compares): the same value for every v --
  // inside the range both pass v through, outside both give +-max, and NaN
  // fails both tests and passes through (issue 16; every conversion of the
  // float kernel goes through here, ~20 a tick). The test is on the float
  // the double rounds to, against 128.0f (kMaxMagnitude's own float): the
  // same value for every v -- |v| > kMaxMagnitude rounds to |f| >= 128.0f
  // (rounding is monotonic), where both give +-128.0f, and |v| <=
  // kMaxMagnitude to |f| <= 128.0f, where both give f -- and a float compare
  // in place of a double one, ~14 M7 instructions fewer a tick (issue 16;
  // test Saturation.OneTestSaturationsEqualTheTwoSidedForms).
  static constexpr Scalar from_double(double v) {
    const float f = static_cast<float>(v);
    return __builtin_fabsf(f) > kMaxMagnitudeFloat ? (f > 0.0f ? kMaxMagnitudeFloat : -kMaxMagnitudeFloat) : f;
  }
  static constexpr Scalar from_float(float v) { return from_double(static_cast<double>(v)); }
  // |v| below the saturation limit (one VABS and one compare on the M7; a NaN
  // is not inside).
  static constexpr bool inside_limit(Scalar v) { return __builtin_fabsf(v) < kMaxMagnitudeFloat; }
  static constexpr float to_float(Scalar v) { return v; }
  static constexpr double to_double(Scalar v) { return static_cast<double>(v); }
  static constexpr Scalar zero() { return 0.0f; }
  static constexpr Scalar one() { return 1.0f; }
  static constexpr Scalar max() { return static_cast<float>(kMaxMagnitude); }

  static constexpr Coeff coeff_from_double(double v) { return static_cast<float>(v); }
  static constexpr double coeff_to_double(Coeff c) { return static_cast<double>(c); }
  static constexpr bool coeff_fits(double v) { return v < kCoeffMaxMagnitude && v > -kCoeffMaxMagnitude; }
  static constexpr Scalar mul(Coeff c, Scalar v) { return c * v; }

  // A gain that only ever enters the double accumulator (the loops' MACs):
  // the float coefficient's value, held as a double. The same value exactly,
  // so every MAC gives the bits it gave with the float, one VCVT fewer each
  // (~30 M7 instructions a tick over the six loops, issue 16).
  //
  // Not inlined, on purpose: Debian's GCC 12.2 for x86-64 at -O2 / -O3
  // miscompiles this double -> float -> double round trip when its SLP
  // vectorizer packs several of them and one operand comes from a branch
  // (design_pid2dof's a_d, b_d): the rounding to float is dropped and the
  // host's loops then differ from the M7's in the last bits
  // (kernel-bitexact-qemu-m7 caught it; -fno-tree-slp-vectorize or -O1 give
  // the right value; the Cortex-M7 build has no double SIMD and was right).
  // A call is configuration-time cost only, and the vectorizer does not
  // reach into it.
  using AccCoeff = double;
  [[gnu::noinline, gnu::cold]] static AccCoeff acc_coeff_from_double(double v) {
    return static_cast<double>(static_cast<float>(v));
  }
  static constexpr double acc_coeff_to_double(AccCoeff c) { return c; }

  static constexpr Acc acc_zero() { return 0.0; }
  static constexpr Acc acc_from_scalar(Scalar v) { return static_cast<double>(v); }
  static constexpr Acc acc_from_double(double v) { return v; }
  static constexpr double acc_to_double(Acc a) { return a; }
  static constexpr Scalar acc_to_scalar(Acc a) { return from_double(a); }
  static constexpr void mac(Acc& acc, Coeff c, Scalar v) { acc += static_cast<double>(c) * static_cast<double>(v); }
  static constexpr void mac(Acc& acc, AccCoeff c, Scalar v) { acc += c * static_cast<double>(v); }
  // acc += c (v0 + v1) and c0 v0 + c1 v1: the fixed-point kernel rounds each
  // once (Fixed::mac_sum, mul_sum2); here they are the two macs they always
  // were, in the same order, so the float kernel keeps its bits.
  template <typename C>
  static constexpr void mac_sum(Acc& acc, C c, Scalar v0, Scalar v1) {
    mac(acc, c, v0);
    mac(acc, c, v1);
  }
  template <typename C>
  static constexpr Scalar mul_sum2(C c0, Scalar v0, C c1, Scalar v1) {
    Acc acc = acc_zero();
    mac(acc, c0, v0);
    mac(acc, c1, v1);
    return acc_to_scalar(acc);
  }
  static constexpr Acc acc_mul(Acc a, Coeff c) { return a * static_cast<double>(c); }
  static constexpr Acc acc_mul(Acc a, AccCoeff c) { return a * c; }

  static constexpr SinCos<Scalar> sin_cos(std::uint32_t phase) {
    return from_q30(sin_cos_q30(phase));
  }
  static constexpr Scalar from_q30(std::int32_t v) { return static_cast<float>(v) * (1.0f / 1073741824.0f); }
  static constexpr SinCos<Scalar> from_q30(SinCosQ30 q) { return {from_q30(q.sin), from_q30(q.cos)}; }
  // The sine alone (one quarter-wave read, not the pair's two): from_q30's
  // .sin for the same phase, bit for bit.
  static constexpr Scalar sin(std::uint32_t phase) { return from_q30(sin_q30(phase)); }
};

template <int F>
struct ScalarTraits<Fixed<F>> {
  using Scalar = Fixed<F>;
  using Coeff = Q3_28;
  using Acc = Q31_32;
  static constexpr bool kIsFixed = true;
  static constexpr double kMaxMagnitude = Scalar::kMaxValue;
  static constexpr double kCoeffMaxMagnitude = Coeff::kMaxValue;

  static constexpr Scalar from_double(double v) { return Scalar::from_double(v); }
  static constexpr Scalar from_float(float v) { return Scalar::from_float(v); }
  // |v| below the saturation limit: raw in [-(INT32_MAX - 1), INT32_MAX - 1],
  // one add and one unsigned compare: raw + (INT32_MAX - 1) taken mod 2^32
  // maps that interval onto [0, 2^32 - 4] and +-INT32_MAX (and INT32_MIN)
  // above it (test Pid2Dof.TheIntegratorIsHeldWhileTheErrorIsAtTheScalarsLimit).
  static constexpr bool inside_limit(Scalar v) {
    return static_cast<std::uint32_t>(v.raw()) + 0x7FFFFFFEu < 0xFFFFFFFDu;
  }
  static constexpr float to_float(Scalar v) { return v.to_float(); }
  static constexpr double to_double(Scalar v) { return v.to_double(); }
  static constexpr Scalar zero() { return Scalar::zero(); }
  static constexpr Scalar one() { return Scalar::one(); }
  static constexpr Scalar max() { return Scalar::max(); }

  static constexpr Coeff coeff_from_double(double v) { return Coeff::from_double(v); }
  static constexpr double coeff_to_double(Coeff c) { return c.to_double(); }
  // Fixed point has one coefficient format (ScalarTraits<float>::AccCoeff).
  using AccCoeff = Coeff;
  static constexpr AccCoeff acc_coeff_from_double(double v) { return Coeff::from_double(v); }
  static constexpr double acc_coeff_to_double(AccCoeff c) { return c.to_double(); }
  static constexpr bool coeff_fits(double v) { return v < kCoeffMaxMagnitude && v > -kCoeffMaxMagnitude; }
  static constexpr Scalar mul(Coeff c, Scalar v) { return Scalar::mul(c, v); }

  static constexpr Acc acc_zero() { return Acc{}; }
  static constexpr Acc acc_from_scalar(Scalar v) { return Acc::from_fixed(v); }
  static constexpr Acc acc_from_double(double v) { return Acc::from_double(v); }
  static constexpr double acc_to_double(Acc a) { return a.to_double(); }
  static constexpr Scalar acc_to_scalar(Acc a) { return a.template to_fixed<F>(); }
  static constexpr void mac(Acc& acc, Coeff c, Scalar v) { acc.mac(c, v); }
  // Rounded once each (issue 16; fixed.hpp "Sums of products rounded ONCE").
  static constexpr void mac_sum(Acc& acc, Coeff c, Scalar v0, Scalar v1) { acc.mac_sum(c, v0, v1); }
  static constexpr Scalar mul_sum2(Coeff c0, Scalar v0, Coeff c1, Scalar v1) {
    return Scalar::mul_sum2(c0, v0, c1, v1);
  }
  static constexpr Acc acc_mul(Acc a, Coeff c) { return a.mul(c); }

  static constexpr SinCos<Scalar> sin_cos(std::uint32_t phase) {
    static_assert(F <= 30);
    return from_q30(sin_cos_q30(phase));
  }
  static constexpr Scalar sin(std::uint32_t phase) { return from_q30(sin_q30(phase)); }
  static constexpr Scalar from_q30(std::int32_t v) {
    static_assert(F <= 30);
    return Scalar::from_raw_in_range(static_cast<std::int32_t>(detail::shift_round(v, 30 - F)));
  }
  static constexpr SinCos<Scalar> from_q30(SinCosQ30 q) { return {from_q30(q.sin), from_q30(q.cos)}; }
};

}  // namespace maglev::numeric
