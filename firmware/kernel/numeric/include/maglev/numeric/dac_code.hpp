// A DAC code from a value in codes: the one rounding and saturation every
// stage's kernel uses (the seed stage's force allocation, paper 002's PMLSM
// controller, paper 001's solenoid-magnet stage).
#pragma once

#include <bit>
#include <cstdint>

#include "maglev/numeric/saturation.hpp"

namespace maglev::numeric {

// An int32 saturated to the DAC's int16 range: SSAT on the M7 (GCC made
// two compares and two conditional moves of the clamp).
inline std::int16_t SaturateToInt16(std::int32_t v) {
#if defined(__arm__) && defined(__ARM_FEATURE_SAT)
  return static_cast<std::int16_t>(__builtin_arm_ssat(v, 16));
#else
  return static_cast<std::int16_t>(clamp<std::int32_t>(v, -32768, 32767));
#endif
}

// The AD5764 code of v (in codes): round half away from zero, saturate to
// [-32768, 32767], NaN -> 0 -- defined for every double, so the two forms
// below give the same code by construction (tests DacCode.* in
// tests/kernel/numeric and ForceAllocation.DacCodeRoundsHalfAwayAndSaturates
// run on the host and on the M7: every half code and its neighbours, the
// bounds, infinities, NaN).
// The M7's is its own instructions' definition of exactly that: VRINTA
// rounds half away; VCVT.S32.F64 saturates out-of-range values and turns
// NaN into 0 (ARMv7-M ARM, FPToFixed); SSAT saturates to 16 bits: four
// instructions (the two-branch C++ form was ~19 a coil, eight a tick; issue
// 16). C++ leaves a NaN or out-of-range double -> int conversion undefined,
// so the portable form tests the range first. (round() replaced trunc(v +- 0.5),
// which differs only at v = +-(0.5 - 2^-54), where v +- 0.5 rounds to +-1.)
inline std::int16_t DacCode(double v) {
#if defined(__arm__) && defined(__ARM_FP) && (__ARM_FP & 8) && defined(__ARM_FEATURE_SAT)
  const double r = __builtin_round(v);  // VRINTA
  float bits;                           // the int32, in an S register
  __asm__("vcvt.s32.f64 %0, %P1" : "=t"(bits) : "w"(r));
  return SaturateToInt16(std::bit_cast<std::int32_t>(bits));
#else
  // Without libm (x86-64's round, fmin and fmax are library calls): the
  // range first, then the truncated integer and the exact remainder v - i
  // decide the half away from zero.
  if (!(v == v)) return 0;
  if (!(v < 32767.0)) return 32767;
  if (!(v > -32768.0)) return -32768;
  const auto i = static_cast<std::int32_t>(v);  // |v| < 32768: truncation toward zero
  const double rest = v - static_cast<double>(i);  // exact
  return static_cast<std::int16_t>(i + (rest >= 0.5 ? 1 : 0) - (rest <= -0.5 ? 1 : 0));
#endif
}

// DacCode with a symmetric range, [-32767, 32767]: the stages whose current
// limits are symmetric (paper 001's and paper 002's kernels) never use
// -32768. NaN stays NaN through the clamp (its compares are false): code 0.
inline std::int16_t SymmetricDacCode(double v) { return DacCode(v < -32767.0 ? -32767.0 : v); }

}  // namespace maglev::numeric
