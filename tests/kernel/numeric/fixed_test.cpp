// Fixed<F> / Wide<F>: rounding, saturation at every op boundary, round trips,
// and the wide-accumulator precision claim.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "CppUTest/TestHarness.h"
#include "maglev/numeric/fixed.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"
#include "test_random.hpp"

using maglev::numeric::Fixed;
using maglev::numeric::Q31_32;
using maglev::numeric::Q3_28;
using maglev::numeric::Q7_24;
using maglev::numeric::test::NextRandom;

namespace {
constexpr std::int32_t kMax = INT32_MAX;
constexpr std::int32_t kMin = -INT32_MAX;
Q7_24 R(std::int32_t raw) { return Q7_24::from_raw(raw); }
// A random positive double of any binary exponent from 2^-60 to 2^64 (the
// exponent first, then the 52-bit fraction).
double RandomMagnitude(std::uint64_t* s) {
  const int e = static_cast<int>(NextRandom(s) % 125u) - 60;
  return std::ldexp(1.0 + static_cast<double>(NextRandom(s) >> 11) * 0x1.0p-53, e);
}
}  // namespace

TEST_GROUP(Fixed){};

TEST(Fixed, ConversionRoundsHalfAwayFromZero) {
  const double lsb = Q7_24::kLsb;
  LONGS_EQUAL(1, Q7_24::from_double(0.5 * lsb).raw());
  LONGS_EQUAL(-1, Q7_24::from_double(-0.5 * lsb).raw());
  LONGS_EQUAL(0, Q7_24::from_double(0.49 * lsb).raw());
  LONGS_EQUAL(2, Q7_24::from_double(1.5 * lsb).raw());
  LONGS_EQUAL(-2, Q7_24::from_double(-1.5 * lsb).raw());
  LONGS_EQUAL(3 << 23, Q7_24::from_double(1.5).raw());
  LONGS_EQUAL(0, Q7_24::from_double(std::nan("")).raw());
  LONGS_EQUAL(1 << 24, Q7_24::from_float(1.0f).raw());
}

TEST(Fixed, ConversionSaturates) {
  LONGS_EQUAL(kMax, Q7_24::from_double(128.0).raw());
  LONGS_EQUAL(kMax, Q7_24::from_double(1e30).raw());
  LONGS_EQUAL(kMin, Q7_24::from_double(-128.0).raw());
  LONGS_EQUAL(kMin, Q7_24::from_double(-1e30).raw());
  LONGS_EQUAL(kMax, Q7_24::from_double(INFINITY).raw());
  LONGS_EQUAL(kMin, Q7_24::from_raw(INT32_MIN).raw());  // never INT32_MIN
  LONGS_EQUAL(kMax, Q7_24::from_int(200).raw());
  LONGS_EQUAL(kMin, Q7_24::from_int(-200).raw());
  LONGS_EQUAL(5 << 24, Q7_24::from_int(5).raw());
}

// double_to_raw's sign-split fast path gives the general path's value for
// every input: each limit the kernel uses, the bounds (2^51 - 1, the limit)
// on both sides, signed zeros, infinities, NaN, half-integers, and random
// magnitudes of every binary exponent from 2^-60 to 2^64.
TEST(Fixed, DoubleToRawFastPathEqualsTheGeneralPath) {
  using maglev::numeric::detail::double_to_raw;
  using maglev::numeric::detail::double_to_raw_general;
  const double limits[] = {static_cast<double>(kMax), 4611686018427387904.0, 9223372036854774784.0};
  const double edge[] = {0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994,
                         2251799813685247.0, -2251799813685247.0, 2251799813685246.5, -2251799813685246.5,
                         2251799813685247.5, -2251799813685247.5, 2251799813685248.0, -2251799813685248.0,
                         2147483646.5, -2147483646.5, 2147483646.75, 2147483647.0, -2147483647.0, 2147483647.5,
                         4294967295.5, -4294967295.5, 4611686018427387904.0, -4611686018427387904.0, 1e300,
                         -1e300, INFINITY, -INFINITY, std::nan(""), 5e-324, -5e-324};
  for (double limit : limits) {
    for (double v : edge) CHECK_EQUAL(double_to_raw_general(v, limit), double_to_raw(v, limit));
  }
#if defined(__arm__)
  constexpr int kSamples = 30000;  // under QEMU: a prefix of the host's set
#else
  constexpr int kSamples = 300000;
#endif
  std::uint64_t s = 7;
  for (int i = 0; i < kSamples; ++i) {
    double v = RandomMagnitude(&s);
    if (i % 4 == 1) v = std::floor(v) + 0.5;  // ties
    if (NextRandom(&s) & 1u) v = -v;
    for (double limit : limits) {
      if (double_to_raw_general(v, limit) != double_to_raw(v, limit)) {
        CHECK_EQUAL(double_to_raw_general(v, limit), double_to_raw(v, limit));
      }
    }
  }
}

TEST(Fixed, RoundTripIsExactForEveryRepresentableValue) {
  // Q7.24 -> double -> Q7.24 is the identity, and double -> Q7.24 -> double
  // errs by at most half an LSB.
  std::uint32_t x = 12345u;
  for (int i = 0; i < 100000; ++i) {
    x = x * 1664525u + 1013904223u;
    const auto raw = static_cast<std::int32_t>(x);
    const Q7_24 q = R(raw);
    LONGS_EQUAL(q.raw(), Q7_24::from_double(q.to_double()).raw());
    const double d = static_cast<double>(raw) * 1.1e-8;
    CHECK(std::fabs(Q7_24::from_double(d).to_double() - d) <= 0.5 * Q7_24::kLsb);
  }
  // to_float is the nearest float of the exact value.
  DOUBLES_EQUAL(1.25, static_cast<double>(Q7_24::from_double(1.25).to_float()), 0.0);
}

TEST(Fixed, AddSubSaturateAtBoundaries) {
  LONGS_EQUAL(kMax, (R(kMax) + R(1)).raw());
  LONGS_EQUAL(kMax - 1, (R(kMax) + R(-1)).raw());
  LONGS_EQUAL(kMin, (R(kMin) + R(-1)).raw());
  LONGS_EQUAL(kMin, (R(kMin) - R(1)).raw());
  LONGS_EQUAL(kMax, (R(kMax) - R(kMin)).raw());
  LONGS_EQUAL(kMin, (R(kMin) - R(kMax)).raw());
  LONGS_EQUAL(0, (R(kMax) + R(kMin)).raw());
  LONGS_EQUAL(kMin, (-R(kMax)).raw());
  LONGS_EQUAL(kMax, (-R(kMin)).raw());
  Q7_24 a = R(kMax - 2);
  a += R(10);
  LONGS_EQUAL(kMax, a.raw());
}

// The 32-bit saturating add / subtract (issue 16) against the 64-bit sum
// clamped, the form they replaced: every pair of edge values and 1 million
// pseudo-random pairs (half of them small, no saturation); also run on the
// M7 (kernel-numeric-m7).
TEST(Fixed, SaturatingAddAndSubtractEqualTheWideForms) {
  using maglev::numeric::detail::add_sat32;
  using maglev::numeric::detail::saturate32;
  using maglev::numeric::detail::sub_sat32;
  long mismatches = 0;
  const std::int32_t edges[] = {0, 1, -1, kMax, kMin, kMax - 1, kMin + 1, kMax / 2, kMin / 2, kMax / 2 + 1,
                                kMin / 2 - 1};
  for (std::int32_t a : edges) {
    for (std::int32_t b : edges) {
      mismatches += add_sat32(a, b) != saturate32(std::int64_t{a} + b) ? 1 : 0;
      mismatches += sub_sat32(a, b) != saturate32(std::int64_t{a} - b) ? 1 : 0;
    }
  }
  std::uint64_t x = 16;
  for (int i = 0; i < 1000000; ++i) {
    std::int32_t a = static_cast<std::int32_t>(NextRandom(&x)), b = static_cast<std::int32_t>(NextRandom(&x));
    if (a == INT32_MIN) a = kMin;  // Fixed's raw range is symmetric
    if (b == INT32_MIN) b = kMin;
    if ((i & 1) != 0) b = static_cast<std::int32_t>(b / 65536);
    mismatches += add_sat32(a, b) != saturate32(std::int64_t{a} + b) ? 1 : 0;
    mismatches += sub_sat32(a, b) != saturate32(std::int64_t{a} - b) ? 1 : 0;
  }
  LONGS_EQUAL(0, mismatches);
  LONGS_EQUAL(kMax, (R(kMax) + R(kMax)).raw());
  LONGS_EQUAL(kMin, (R(kMin) + R(kMin)).raw());
  LONGS_EQUAL(kMin, (R(kMin) - R(kMax)).raw());
}

TEST(Fixed, MultiplyRoundsHalfAwayFromZeroAndSaturates) {
  // 0.5 LSB products: raw 1 * raw (1<<23) = 2^23 -> exactly half an LSB.
  const Q7_24 half = Q7_24::from_double(0.5);
  LONGS_EQUAL(1, (R(1) * half).raw());
  LONGS_EQUAL(-1, (R(-1) * half).raw());
  LONGS_EQUAL(2, (R(3) * half).raw());   // 1.5 -> 2
  LONGS_EQUAL(-2, (R(-3) * half).raw());  // -1.5 -> -2
  LONGS_EQUAL(0, (R(1) * Q7_24::from_double(0.25)).raw());  // 0.25 -> 0
  DOUBLES_EQUAL(-6.0, (Q7_24::from_double(2.0) * Q7_24::from_double(-3.0)).to_double(), 0.0);
  LONGS_EQUAL(kMax, (Q7_24::from_double(100.0) * Q7_24::from_double(2.0)).raw());
  LONGS_EQUAL(kMin, (Q7_24::from_double(100.0) * Q7_24::from_double(-2.0)).raw());
  LONGS_EQUAL(kMax, (R(kMin) * R(kMin)).raw());
  LONGS_EQUAL(kMin, (R(kMax) * R(kMin)).raw());
  // Mixed formats: coefficient Q3.28 * signal Q7.24 -> Q7.24.
  DOUBLES_EQUAL(0.036 * 8.0, Q7_24::mul(Q3_28::from_double(0.036), Q7_24::from_double(8.0)).to_double(),
                2 * Q7_24::kLsb);
}

TEST(Fixed, DivideRoundsAndSaturates) {
  DOUBLES_EQUAL(0.75, (Q7_24::from_double(3.0) / Q7_24::from_double(4.0)).to_double(), 0.0);
  // 1 LSB / 2 = 0.5 LSB -> 1 (away from zero); -1/2 -> -1.
  LONGS_EQUAL(1, (R(1) / Q7_24::from_double(2.0)).raw());
  LONGS_EQUAL(-1, (R(-1) / Q7_24::from_double(2.0)).raw());
  LONGS_EQUAL(0, (R(1) / Q7_24::from_double(3.0)).raw());  // 1/3 LSB -> 0
  LONGS_EQUAL(kMax, (Q7_24::from_double(100.0) / Q7_24::from_double(0.5)).raw());
  LONGS_EQUAL(kMin, (Q7_24::from_double(-100.0) / Q7_24::from_double(0.5)).raw());
  LONGS_EQUAL(kMax, (Q7_24::one() / Q7_24::zero()).raw());
  LONGS_EQUAL(kMin, (-Q7_24::one() / Q7_24::zero()).raw());
  LONGS_EQUAL(0, (Q7_24::zero() / Q7_24::zero()).raw());
  LONGS_EQUAL(kMax, (R(kMin) / R(-1)).raw());
}

// Rounded once: raw is the nearest integer to sum / 2^shift with ties away
// from zero, i.e. the exact int64 residual sum - raw 2^shift lies in
// [-half, half], and is -half only for a positive sum (ties up) and +half
// only for a negative one (ties down); or raw saturated and beyond.
static void CheckRoundedOnce(std::int64_t sum, int shift, std::int32_t raw) {
  const std::int64_t half = std::int64_t{1} << (shift - 1);
  const std::int64_t limit = std::int64_t{kMax} << shift;  // |sum| / 2^shift beyond kMax + 1/2 saturates
  if (sum >= limit + half) {
    LONGS_EQUAL(kMax, raw);
    return;
  }
  if (sum <= -limit - half) {
    LONGS_EQUAL(kMin, raw);
    return;
  }
  const std::int64_t r = sum - std::int64_t{raw} * (std::int64_t{1} << shift);
  CHECK(r >= -half && r <= half);
  if (r == -half) CHECK(sum > 0);
  if (r == half) CHECK(sum < 0);
}

TEST(Fixed, SumsOfProductsRoundOnce) {
  std::uint64_t rng = 0x51u;
  auto raw_below = [&rng](int bits) {
    const auto v = static_cast<std::int64_t>(NextRandom(&rng) >> (64 - bits)) - (std::int64_t{1} << (bits - 1));
    return static_cast<std::int32_t>(v < -kMax ? -kMax : v);
  };
  for (int n = 0; n < 20000; ++n) {
    // Magnitudes from tiny to near the range, so sums of three stay below 2^63.
    const int bits = 2 + n % 29;
    const Q7_24 a0 = Q7_24::from_raw(raw_below(bits)), b0 = Q7_24::from_raw(raw_below(31));
    const Q7_24 a1 = Q7_24::from_raw(raw_below(bits)), b1 = Q7_24::from_raw(raw_below(31));
    const Q7_24 a2 = Q7_24::from_raw(raw_below(bits)), b2 = Q7_24::from_raw(raw_below(31));
    const std::int64_t p0 = std::int64_t{a0.raw()} * b0.raw(), p1 = std::int64_t{a1.raw()} * b1.raw(),
                       p2 = std::int64_t{a2.raw()} * b2.raw();
    CheckRoundedOnce(p0 + p1, 24, Q7_24::dot2(a0, b0, a1, b1).raw());
    CheckRoundedOnce(p0 + p1 + p2, 24, Q7_24::dot3(a0, b0, a1, b1, a2, b2).raw());
    const Q3_28 c0 = Q3_28::from_raw(raw_below(bits)), c1 = Q3_28::from_raw(raw_below(bits));
    const std::int64_t q = std::int64_t{c0.raw()} * b0.raw() + std::int64_t{c1.raw()} * b1.raw();
    CheckRoundedOnce(q, 28, Q7_24::mul_sum2(c0, b0, c1, b1).raw());
    // The float kernel's forms are its two macs, unchanged.
    using Tf = maglev::numeric::ScalarTraits<float>;
    const float fc0 = static_cast<float>(c0.to_double()), fv0 = b0.to_float();
    const float fc1 = static_cast<float>(c1.to_double()), fv1 = b1.to_float();
    double two_macs = 0.0;
    Tf::mac(two_macs, fc0, fv0);
    Tf::mac(two_macs, fc1, fv1);
    const float fsum = Tf::mul_sum2(fc0, fv0, fc1, fv1);
    const float fref = Tf::acc_to_scalar(two_macs);
    CHECK(std::memcmp(&fsum, &fref, sizeof(float)) == 0);
  }
  // Products at full scale: exact sums beyond the range saturate on their side,
  // cancelling ones do not.
  const Q7_24 mx = Q7_24::max(), mn = Q7_24::min();
  LONGS_EQUAL(kMax, Q7_24::dot3(mx, mx, mx, mx, mx, mx).raw());
  LONGS_EQUAL(kMin, Q7_24::dot3(mx, mn, mx, mn, mn, mx).raw());
  LONGS_EQUAL(kMax, Q7_24::dot2(mn, mn, mx, mx).raw());
  LONGS_EQUAL(kMax, Q7_24::dot3(mx, mx, mx, mx, mn, mx).raw());  // int64 overflow on the way, still beyond
  LONGS_EQUAL(Q7_24::from_double(3.0).raw(),
              Q7_24::dot3(mx, mx, mn, mx, Q7_24::from_double(1.5), Q7_24::from_double(2.0)).raw());
}

TEST(Fixed, ToFloatEqualsRoundingTheExactDouble) {
  std::uint64_t rng = 0x54u;
  auto check = [](std::int32_t raw) {
    const Q7_24 v = Q7_24::from_raw(raw);
    const float a = v.to_float();
    const float b = static_cast<float>(v.to_double());
    CHECK(std::memcmp(&a, &b, sizeof a) == 0);
    const Q3_28 c = Q3_28::from_raw(raw);
    const float ca = c.to_float(), cb = static_cast<float>(c.to_double());
    CHECK(std::memcmp(&ca, &cb, sizeof ca) == 0);
  };
  const std::int32_t edges[] = {0, 1, -1, kMax, kMin, (1 << 24) + 1, -(1 << 24) - 1, (1 << 25) + 3, 16777217, -16777217};
  for (std::int32_t raw : edges) check(raw);
  for (std::int32_t raw = -200000; raw <= 200000; ++raw) check(raw);
  for (int n = 0; n < 200000; ++n) check(static_cast<std::int32_t>(NextRandom(&rng) >> 33) * ((n & 1) ? 1 : -1));
  // Float's ties: above 2^e a float's ulp is 2^(e-23), so 2^e + k 2^(e-24) for
  // odd k lies halfway between two floats (ties to even on both sides).
  for (int e = 25; e <= 30; ++e) {
    for (std::int32_t k = 1; k < 2000; k += 2) {
      const std::int32_t tie = (std::int32_t{1} << e) + k * (std::int32_t{1} << (e - 24));
      check(tie);
      check(-tie);
    }
  }
}

TEST(Fixed, Comparisons) {
  CHECK(Q7_24::from_double(-1.0) < Q7_24::from_double(0.5));
  CHECK(Q7_24::from_double(0.5) == Q7_24::from_double(0.5));
  CHECK(Q7_24::from_double(0.5) != Q7_24::from_double(0.5000001));
  CHECK(Q7_24::max() > Q7_24::from_double(127.0));
  CHECK(Q7_24::min() <= Q7_24::from_double(-127.0));
}

TEST_GROUP(Wide){};

TEST(Wide, MacIsExactAndNarrowingRounds) {
  Q31_32 acc;
  acc.mac(Q3_28::from_raw(1), Q7_24::from_raw(1));  // 2^-52: below half an LSB (2^-33)
  LONGS_EQUAL(0, static_cast<long>(acc.raw()));
  acc.mac(Q3_28::from_raw(1 << 19), Q7_24::from_raw(1));  // 2^-33 = half LSB -> 1 (away)
  LONGS_EQUAL(1, static_cast<long>(acc.raw()));
  Q31_32 b = Q31_32::from_raw(std::int64_t{1} << 7);  // half LSB of Q7.24
  LONGS_EQUAL(1, b.to_fixed<24>().raw());
  LONGS_EQUAL(-1, (-b).to_fixed<24>().raw());
  LONGS_EQUAL(kMax, Q31_32::from_double(1000.0).to_fixed<24>().raw());
  LONGS_EQUAL(kMin, Q31_32::from_double(-1000.0).to_fixed<24>().raw());
  DOUBLES_EQUAL(1.5, Q31_32::from_fixed(Q7_24::from_double(1.5)).to_double(), 0.0);
}

TEST(Wide, MacSumRoundsTheExactSumOnce) {
  std::uint64_t rng = 0x52u;
  for (int n = 0; n < 20000; ++n) {
    const auto c = Q3_28::from_raw(static_cast<std::int32_t>(NextRandom(&rng) >> 33) - (1 << 30));
    const auto v0 = Q7_24::from_raw(static_cast<std::int32_t>(NextRandom(&rng) >> 33) - (1 << 30));
    const auto v1 = Q7_24::from_raw(static_cast<std::int32_t>(NextRandom(&rng) >> 33) - (1 << 30));
    Q31_32 acc{};
    acc.mac_sum(c, v0, v1);
    // The exact product has 52 fraction bits; Q31.32 keeps 32: shift by 20.
    const std::int64_t p = std::int64_t{c.raw()} * (std::int64_t{v0.raw()} + v1.raw());
    const std::int64_t half = std::int64_t{1} << 19;
    const std::int64_t r = p - acc.raw() * (std::int64_t{1} << 20);
    CHECK(r >= -half && r <= half);
    if (r == -half) CHECK(p > 0);
    if (r == half) CHECK(p < 0);
  }
  // At full scale the sum of the two signals is exact (no 32-bit saturation).
  Q31_32 full{};
  full.mac_sum(Q3_28::one(), Q7_24::max(), Q7_24::max());
  CHECK(full.raw() == std::int64_t{kMax} * 2 * 256);
}

TEST(Wide, SaturatesInsteadOfWrapping) {
  const Q31_32 big = Q31_32::from_raw(INT64_MAX - 5);
  CHECK((big + Q31_32::from_raw(100)).raw() == INT64_MAX);
  CHECK((-big - Q31_32::from_raw(100)).raw() == -INT64_MAX);
  Q31_32 m = big;
  m.mac(Q3_28::max(), Q7_24::max());
  CHECK(m.raw() == INT64_MAX);
  CHECK(big.mul(Q3_28::from_double(2.0)).raw() == INT64_MAX);
  CHECK(big.mul(Q3_28::from_double(-2.0)).raw() == -INT64_MAX);
}

TEST(Wide, MulByCoefficientMatchesDouble) {
  std::uint32_t x = 777u;
  for (int i = 0; i < 20000; ++i) {
    x = x * 1664525u + 1013904223u;
    const double a = (static_cast<double>(static_cast<std::int32_t>(x)) / 2147483648.0) * 3.0e5;
    x = x * 1664525u + 1013904223u;
    const double c = (static_cast<double>(static_cast<std::int32_t>(x)) / 2147483648.0) * 7.9;
    const Q31_32 wa = Q31_32::from_double(a);
    const Q3_28 qc = Q3_28::from_double(c);
    const double exact = wa.to_double() * qc.to_double();
    CHECK(std::fabs(wa.mul(qc).to_double() - exact) <= 0.5 * Q31_32::kLsb + 1e-12 * std::fabs(exact));
  }
}

TEST(Wide, OneNanometreIntegratesWithinOnePercent) {
  // Ki*T of x/y: 2.4e6 A/(m s) * 1e-6 m/um / 2500 Hz = 9.6e-4; the brief's
  // smallest case 2.4e-4 A/(um tick); 1 nm = 1e-3 um. After 10000 ticks the
  // exact integral is 2.4e-3 A.
  using Tr = maglev::numeric::ScalarTraits<Q7_24>;
  using Trf = maglev::numeric::ScalarTraits<float>;
  const double kiT = 2.4e-4;
  auto acc = Tr::acc_zero();
  auto accf = Trf::acc_zero();
  const Q7_24 e = Q7_24::from_double(1e-3);
  for (int k = 0; k < 10000; ++k) {
    Tr::mac(acc, Tr::coeff_from_double(kiT), e);
    Trf::mac(accf, Trf::coeff_from_double(kiT), 1e-3f);
  }
  const double exact = 10000 * kiT * 1e-3;
  const double err_fixed = std::fabs(Tr::acc_to_double(acc) - exact) / exact;
  const double err_float = std::fabs(accf - exact) / exact;
  CHECK(err_fixed < 0.01);
  CHECK(err_float < 0.01);
  // For contrast: a plain Q7.24 integrator loses it (increment = 4 LSB, the
  // product 2.4e-7 A rounds to 4 LSB = 2.38e-7: -0.7 %, and 0.1 nm would be 0).
  Q7_24 narrow = Q7_24::zero();
  for (int k = 0; k < 10000; ++k) narrow += Q7_24::mul(Q3_28::from_double(kiT), Q7_24::from_double(1e-4));
  const double narrow_exact = 10000 * kiT * 1e-4;
  CHECK(std::fabs(narrow.to_double() - narrow_exact) / narrow_exact > 0.05);
  auto acc01 = Tr::acc_zero();
  for (int k = 0; k < 10000; ++k) Tr::mac(acc01, Tr::coeff_from_double(kiT), Q7_24::from_double(1e-4));
  CHECK(std::fabs(Tr::acc_to_double(acc01) - narrow_exact) / narrow_exact < 0.01);
}

TEST_GROUP(Saturation){};

TEST(Saturation, PicoToMicroIsExactAndSaturates) {
  using maglev::numeric::pico_to_micro;
  DOUBLES_EQUAL(1.0, pico_to_micro<Q7_24>(1000000).to_double(), 0.0);
  DOUBLES_EQUAL(-8.0, pico_to_micro<Q7_24>(-8000000).to_double(), 0.0);
  // 1 pm = 1e-6 um = 16.78 LSB -> 17 LSB.
  LONGS_EQUAL(17, pico_to_micro<Q7_24>(1).raw());
  LONGS_EQUAL(-17, pico_to_micro<Q7_24>(-1).raw());
  LONGS_EQUAL(kMax, pico_to_micro<Q7_24>(INT64_MAX).raw());
  LONGS_EQUAL(kMin, pico_to_micro<Q7_24>(INT64_MIN).raw());
  LONGS_EQUAL(kMax, pico_to_micro<Q7_24>(200000000).raw());
  DOUBLES_EQUAL(127.999999, static_cast<double>(pico_to_micro<float>(INT64_MAX)), 1e-4);
  DOUBLES_EQUAL(-127.999999, static_cast<double>(pico_to_micro<float>(INT64_MIN)), 1e-4);
  DOUBLES_EQUAL(0.010, static_cast<double>(pico_to_micro<float>(10000)), 1e-9);
  // The double form equals the exact integer form: every difference within
  // 4e6 pm (2e5 on the M7) of 0 and of both saturation edges, the differences whose quotient
  // lies closest to a half-integer (d 2^18 mod 15625 = 7812 or 7813), the
  // extremes, and a random sweep over the whole int64 range and over +-2e8 pm.
  using maglev::numeric::pico_to_micro_exact;
  auto same = [](std::int64_t d) { return pico_to_micro<Q7_24>(d).raw() == pico_to_micro_exact<Q7_24>(d).raw(); };
  const std::int64_t edge = 128000000;  // 128 um
#if defined(__arm__)
  constexpr std::int64_t kWindow = 200000;  // under QEMU: a part of the host's windows
  constexpr int kRandom = 20000;
#else
  constexpr std::int64_t kWindow = 4000000;
  constexpr int kRandom = 200000;
#endif
  for (std::int64_t centre : {std::int64_t{0}, edge, -edge}) {
    for (std::int64_t d = centre - kWindow; d <= centre + kWindow; ++d) {
      if (!same(d)) FAIL(("pico_to_micro differs from the exact form at " + std::to_string(d)).c_str());
    }
  }
  int near_ties = 0;
  for (std::int64_t target : {std::int64_t{7812}, std::int64_t{7813}}) {
    std::int64_t first = 0;  // d 2^18 = target (mod 15625)
    while (first * 262144 % 15625 != target) ++first;
    for (std::int64_t d = first - 130000000 / 15625 * 15625; d <= 130000000; d += 15625) {
      ++near_ties;
      if (!same(d)) FAIL(("pico_to_micro differs near a tie at " + std::to_string(d)).c_str());
    }
  }
  CHECK(near_ties > 30000);
  for (std::int64_t d : {INT64_MAX, INT64_MIN, INT64_MIN + 1, std::int64_t{1} << 53, -(std::int64_t{1} << 53),
                         (std::int64_t{1} << 53) + 1, std::int64_t{130000000}, std::int64_t{-130000000}}) {
    CHECK(same(d));
  }
  std::uint64_t rng = 0x53u;
  for (int n = 0; n < kRandom; ++n) {
    const auto wide = static_cast<std::int64_t>(NextRandom(&rng));
    const auto narrow = static_cast<std::int64_t>(NextRandom(&rng) % 400000001u) - 200000000;
    CHECK(same(wide));
    CHECK(same(narrow));
  }
  CHECK(maglev::numeric::micro_to_pico(8.0) == 8000000);
  CHECK(maglev::numeric::si_to_pico(0.056) == 56000000000LL);
}

TEST(Saturation, Clamp) {
  using maglev::numeric::clamp_abs;
  DOUBLES_EQUAL(4.0, clamp_abs(Q7_24::from_double(5.0), Q7_24::from_double(4.0)).to_double(), 0.0);
  DOUBLES_EQUAL(-4.0, static_cast<double>(clamp_abs(-5.0f, 4.0f)), 0.0);
  DOUBLES_EQUAL(1.0, static_cast<double>(clamp_abs(1.0f, 4.0f)), 0.0);
}

// The float kernel's one-test saturations (issue 16) against the two-sided
// forms they replaced, bit for bit: ScalarTraits<float>::from_double against
// clamp-then-convert, clamp_abs<float> against clamp(v, -limit, limit).
// Values around both bounds and their neighbours, signed zeros, infinities,
// NaN, and random values over every binary exponent from 2^-60 to 2^64.
TEST(Saturation, OneTestSaturationsEqualTheTwoSidedForms) {
  using Tr = maglev::numeric::ScalarTraits<float>;
  using maglev::numeric::clamp;
  using maglev::numeric::clamp_abs;
  const auto same_bits = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  const double m = Tr::kMaxMagnitude;
  const auto two_sided = [m](double v) { return static_cast<float>(v > m ? m : (v < -m ? -m : v)); };
  const float limits[] = {4.0f, 0.5f, 1e-30f, 127.99999f, 0.0f};
  std::vector<double> values = {0.0, -0.0, m, -m, std::nextafter(m, 0.0), std::nextafter(m, 1e300),
                                -std::nextafter(m, 0.0), -std::nextafter(m, 1e300), 1e300, -1e300,
                                INFINITY, -INFINITY, std::nan(""), -std::nan(""), 5e-324, -5e-324};
  // from_double rounds to float first and compares that with 128.0f, the
  // float nearest to m = 128 - 2^-24: the doubles between m and the floats
  // either side of 128, which round onto 128.0f from both sides.
  for (double v : {128.0, std::nextafter(128.0, 0.0), std::nextafter(128.0, 1e300), 128.0 - 0x1.0p-18,
                   128.0 - 0x1.0p-17, 128.0 - 0x1.0p-16, 128.0 + 0x1.0p-18, 128.0 + 0x1.0p-17, 128.0 + 0x1.0p-16,
                   m + 0x1.0p-30, m - 0x1.0p-30, static_cast<double>(std::nextafter(128.0f, 0.0f)),
                   static_cast<double>(std::nextafter(128.0f, 1e30f))}) {
    values.push_back(v);
    values.push_back(-v);
  }
  for (float l : limits) {
    for (float v : {l, -l, std::nextafter(l, 0.0f), std::nextafter(l, 1e30f)}) {
      values.push_back(v);
      values.push_back(-static_cast<double>(v));
    }
  }
#if defined(__arm__)
  constexpr int kSamples = 30000;
#else
  constexpr int kSamples = 300000;
#endif
  std::uint64_t s = 11;
  for (int i = 0; i < kSamples; ++i) {
    const double v = RandomMagnitude(&s);
    values.push_back((NextRandom(&s) & 1u) ? -v : v);
  }
  int checked = 0;
  for (double v : values) {
    if (!same_bits(two_sided(v), Tr::from_double(v))) {
      CHECK_EQUAL(two_sided(v), Tr::from_double(v));
    }
    const float f = static_cast<float>(v);
    for (float l : limits) {
      if (!same_bits(clamp(f, -l, l), clamp_abs(f, l))) {
        CHECK_EQUAL(clamp(f, -l, l), clamp_abs(f, l));
      }
      ++checked;
    }
  }
  CHECK(checked > 5 * kSamples);
}
