// Table sin/cos against std::sin/std::cos: dense sweep and every knot.
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>

#include "CppUTest/TestHarness.h"
#include "maglev/numeric/scalar_traits.hpp"

using maglev::numeric::Q7_24;
using maglev::numeric::ScalarTraits;

namespace {
constexpr double kTwoPi = 6.283185307179586476925;
double angle(std::uint32_t phase) { return kTwoPi * static_cast<double>(phase) / 4294967296.0; }
}  // namespace

TEST_GROUP(SinCos){};

TEST(SinCos, TableKnotsAreCorrectlyRoundedQ30) {
  for (int k = 0; k <= maglev::numeric::kSinTableSize; ++k) {
    const double exact = std::sin(1.5707963267948966 * k / maglev::numeric::kSinTableSize) * 1073741824.0;
    CHECK(std::fabs(maglev::numeric::kQuarterSineTable[static_cast<std::size_t>(k)] - exact) <= 0.5 + 1e-6);
  }
}

TEST(SinCos, ErrorBoundOverDenseSweepAndAllKnots) {
  double max_f = 0.0, max_q = 0.0;
  auto check = [&](std::uint32_t phase) {
    const double a = angle(phase);
    const double s = std::sin(a), c = std::cos(a);
    const auto f = ScalarTraits<float>::sin_cos(phase);
    const auto q = ScalarTraits<Q7_24>::sin_cos(phase);
    max_f = std::fmax(max_f, std::fmax(std::fabs(static_cast<double>(f.sin) - s), std::fabs(static_cast<double>(f.cos) - c)));
    max_q = std::fmax(max_q, std::fmax(std::fabs(q.sin.to_double() - s), std::fabs(q.cos.to_double() - c)));
  };
  // Every knot of every quadrant (phase multiples of 2^20), and the
  // midpoints, where linear interpolation is worst.
  for (std::uint32_t k = 0; k < 4096u; ++k) {
    check(k << 20);
    check((k << 20) + (1u << 19));
  }
  // Dense pseudo-random sweep.
  std::uint32_t x = 1u;
  for (int i = 0; i < 2000000; ++i) {
    x = x * 1664525u + 1013904223u;
    check(x);
  }
  std::printf("\n[sin_cos] max |error|: float %.3g, Q7.24 %.3g (= %.2f LSB)\n", max_f, max_q, max_q / Q7_24::kLsb);
  // Stated bounds (sin_cos.hpp): 4.0e-7 float, 7 LSB Q7.24.
  CHECK(max_f <= 4.0e-7);
  CHECK(max_q <= 7.0 * Q7_24::kLsb);
  // And the bound is not vacuous: the interpolation error is really there.
  CHECK(max_f > 1.0e-7);
  // Exact values at the cardinal points.
  DOUBLES_EQUAL(1.0, static_cast<double>(ScalarTraits<float>::sin_cos(0x40000000u).sin), 0.0);
  DOUBLES_EQUAL(-1.0, static_cast<double>(ScalarTraits<float>::sin_cos(0x80000000u).cos), 0.0);
  LONGS_EQUAL(-(1 << 24), ScalarTraits<Q7_24>::sin_cos(0xC0000000u).sin.raw());
  LONGS_EQUAL(0, ScalarTraits<Q7_24>::sin_cos(0x80000000u).sin.raw());
}

// Every knot and midpoint of every quadrant, the knots +-1, then `random`
// pseudo-random phases (an LCG from `seed`): the phases the bit-for-bit
// tests below sweep.
template <typename F>
void for_each_test_phase(std::uint32_t seed, int random, F&& check) {
  for (std::uint32_t k = 0; k < 4096u; ++k) {
    check(k << 20);
    check((k << 20) + (1u << 19));
    check((k << 20) - 1u);
    check((k << 20) + 1u);
  }
  std::uint32_t x = seed;
  for (int i = 0; i < random; ++i) {
    x = x * 1664525u + 1013904223u;
    check(x);
  }
}

TEST(SinCos, PairIsSinQ30AndCosQ30BitForBit) {
  // sin_cos_q30 decodes the quadrant once; it must give exactly the two
  // single lookups.
  using maglev::numeric::cos_q30;
  using maglev::numeric::sin_cos_q30;
  using maglev::numeric::sin_q30;
  long mismatches = 0;
  for_each_test_phase(7u, 2000000, [&](std::uint32_t phase) {
    const auto p = sin_cos_q30(phase);
    if (p.sin != sin_q30(phase) || p.cos != cos_q30(phase)) ++mismatches;
  });
  LONGS_EQUAL(0, mismatches);
}

TEST(SinCos, QuarterTurnRotationIsTheTableAtThePhasePlusQuarters) {
  // rotate_quarters(sin_cos_q30(p), n) == sin_cos_q30(p + n 2^30) bit for
  // bit: AllocateCurrents relies on it for forcers whose phases are whole
  // quarter turns apart.
  using maglev::numeric::rotate_quarters;
  using maglev::numeric::sin_cos_q30;
  long mismatches = 0;
  for_each_test_phase(11u, 500000, [&](std::uint32_t phase) {
    const auto base = sin_cos_q30(phase);
    for (unsigned n = 0; n < 8u; ++n) {
      const auto want = sin_cos_q30(phase + n * 0x40000000u);
      const auto got = rotate_quarters(base, n);
      if (got.sin != want.sin || got.cos != want.cos) ++mismatches;
    }
  });
  LONGS_EQUAL(0, mismatches);
}

TEST(SinCos, SineAloneIsThePairsSine) {
  // excite() reads only the sine: ScalarTraits::sin (one quarter-wave read)
  // must be the pair's .sin bit for bit, float and Q7.24.
  long mismatches = 0;
  for_each_test_phase(5u, 500000, [&](std::uint32_t phase) {
    const float f = ScalarTraits<float>::sin(phase), fp = ScalarTraits<float>::sin_cos(phase).sin;
    if (std::memcmp(&f, &fp, sizeof f) != 0) ++mismatches;
    if (ScalarTraits<Q7_24>::sin(phase).raw() != ScalarTraits<Q7_24>::sin_cos(phase).sin.raw()) ++mismatches;
  });
  LONGS_EQUAL(0, mismatches);
}
