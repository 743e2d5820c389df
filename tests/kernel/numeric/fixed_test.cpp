// Fixed<F> / Wide<F>: rounding, saturation at every op boundary, round trips,
// and the wide-accumulator precision claim.
#include <cmath>
#include <cstdint>
#include <cstring>
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
