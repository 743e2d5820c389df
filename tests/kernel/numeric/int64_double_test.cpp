// maglev/numeric/int64_double.hpp: the tick's int64 <-> double forms give
// the same values as the C++ conversions and an exact floor division, over
// the edge cases and 2 million pseudo-random arguments each (200 000 on the M7) (SplitMix64,
// fixed seed: the same arguments on every run and on the M7 build).
#include <cmath>
#include <cstdint>
#include <initializer_list>

#include "maglev/numeric/int64_double.hpp"
#include "test_random.hpp"

#include <CppUTest/TestHarness.h>

namespace {

using maglev::numeric::DivRoundHalfUp;
using maglev::numeric::FloorDiv;
using maglev::numeric::Int64ToDouble;
using maglev::numeric::RoundToInt64;
using maglev::numeric::TruncToInt64;

std::uint64_t next(std::uint64_t* s) { return maglev::numeric::test::NextRandom(s); }

// A value of random magnitude: uniform in its bit length, so small and large
// arguments are both dense.
std::int64_t random_int64(std::uint64_t* s, int max_bits) {
  const int bits = static_cast<int>(next(s) % static_cast<std::uint64_t>(max_bits + 1));
  const std::uint64_t mag = bits == 0 ? 0 : (next(s) >> (64 - bits));
  return (next(s) & 1u) ? -static_cast<std::int64_t>(mag) : static_cast<std::int64_t>(mag);
}

// Fewer on the M7 under QEMU (the same generator: a prefix of the host's set).
#if defined(__arm__)
constexpr int kSamples = 200000;
#else
constexpr int kSamples = 2000000;
#endif

}  // namespace

TEST_GROUP(Int64Double){};

TEST(Int64Double, ToDoubleEqualsTheCastForEveryInt64) {
  const std::int64_t edge[] = {0, 1, -1, INT64_MAX, INT64_MIN, (std::int64_t{1} << 53) + 1, -(std::int64_t{1} << 53) - 1,
                               (std::int64_t{1} << 32) - 1, -(std::int64_t{1} << 32), 0x7FFFFFFFFFFFFC00ll};
  for (std::int64_t v : edge) CHECK_EQUAL(static_cast<double>(v), Int64ToDouble(v));
  std::uint64_t s = 1;
  for (int i = 0; i < kSamples; ++i) {
    const std::int64_t v = random_int64(&s, 63);
    if (static_cast<double>(v) != Int64ToDouble(v)) CHECK_EQUAL(static_cast<double>(v), Int64ToDouble(v));
  }
}

TEST(Int64Double, RoundAndTruncateEqualTheLibraryBelow2To51) {
  const double edge[] = {0.0, -0.0, 0.5, -0.5, 1.5, 2.5, -2.5, 0.49999999999999994, 1e15 + 0.5, -1e15 - 0.5,
                         2251799813685247.0, -2251799813685247.0, 2251799813685246.5,
                         // TruncToInt64 splits at 2^32: both sides of each multiple, and tiny values.
                         4294967296.0, -4294967296.0, 4294967295.75, -4294967295.75, 4294967296.5,
                         -4294967296.5, 8589934591.5, -8589934592.25, 1e-300, -1e-300, 5e-324, -5e-324,
                         0.9999999999999999, -0.9999999999999999};
  for (double v : edge) {
    CHECK_EQUAL(static_cast<std::int64_t>(std::nearbyint(v)), RoundToInt64(v));
    CHECK_EQUAL(static_cast<std::int64_t>(v), TruncToInt64(v));
  }
  std::uint64_t s = 2;
  for (int i = 0; i < kSamples; ++i) {
    // Integers, half-integers and general values, up to 2^51 in magnitude.
    const double base = static_cast<double>(random_int64(&s, 50));
    const double frac = static_cast<double>(next(&s) >> 11) * 0x1.0p-53;
    const double v = (i % 3 == 0) ? base : (i % 3 == 1 ? base + 0.5 : base + frac);
    if (!(std::fabs(v) < 2251799813685248.0)) continue;
    const std::int64_t round = static_cast<std::int64_t>(std::nearbyint(v));  // ties to even
    if (round != RoundToInt64(v)) CHECK_EQUAL(round, RoundToInt64(v));
    if (static_cast<std::int64_t>(v) != TruncToInt64(v)) CHECK_EQUAL(static_cast<std::int64_t>(v), TruncToInt64(v));
  }
}

TEST(Int64Double, FloorDivIsExact) {
  std::uint64_t s = 3;
  long checked = 0;
  for (int i = 0; i < kSamples; ++i) {
    // Divisors up to 2^36 (the commutation pitch bound), dividends up to
    // 2^62 with quotients below 2^50, and exact multiples +- 1.
    std::int64_t d = random_int64(&s, 36);
    d = d < 0 ? -d : d;
    if (d == 0) d = 1;
    std::int64_t a = random_int64(&s, 62);
    // Exact multiples +- 1: a quotient below 2^26 keeps q * d below 2^62.
    if (i % 4 == 0) a = (a % (std::int64_t{1} << 26)) * d + static_cast<std::int64_t>(next(&s) % 3) - 1;
    const double quotient = std::fabs(static_cast<double>(a) / static_cast<double>(d));
    if (!(quotient < 1125899906842624.0)) continue;  // 2^50
    std::int64_t expect = a / d;
    if ((a % d != 0) && (a < 0)) --expect;
    const std::int64_t got = FloorDiv(a, d, 1.0 / static_cast<double>(d));
    if (got != expect) CHECK_EQUAL(expect, got);
    ++checked;
  }
  CHECK(checked > kSamples / 2);
}

TEST(Int64Double, DivRoundHalfUpEqualsTheIntegerDivision) {
  std::uint64_t s = 5;
  // Edges: both paths' bounds, ties, and the tick's uses (the pico -> Q7.24
  // error: n = |e| 2^24, d = 10^6; Fixed division: n = a 2^24, d = |b|).
  const std::uint64_t edge_n[] = {0, 1, 499999, 500000, 500001, (1ull << 50) - 1, 1ull << 50, (1ull << 62) - 1,
                                  1ull << 62, 1ull << 63, 130000000ull << 24, (1ull << 55) - 1};
  const std::uint64_t edge_d[] = {1, 2, 3, 4095, 4096, 1000000, 1ull << 25, (1ull << 31) - 1, (1ull << 40) - 1,
                                  1ull << 40, 1ull << 62, 1ull << 63};
  for (std::uint64_t n : edge_n) {
    for (std::uint64_t d : edge_d) {
      const std::uint64_t expect = (n + d / 2) / d;
      if (DivRoundHalfUp(n, d) != expect) CHECK_EQUAL(expect, DivRoundHalfUp(n, d));
    }
  }
  for (int i = 0; i < kSamples; ++i) {
    std::int64_t dn = random_int64(&s, 62), dd = random_int64(&s, 41);
    const std::uint64_t n = static_cast<std::uint64_t>(dn < 0 ? -dn : dn);
    std::uint64_t d = static_cast<std::uint64_t>(dd < 0 ? -dd : dd);
    if (d == 0) d = 1;
    // Every fourth: exact ties and their neighbours (n = k d + d/2 +- 1).
    const std::uint64_t k = n % (1ull << 20);
    const std::uint64_t nn = i % 4 == 0 ? k * d + d / 2 + next(&s) % 3 - 1 : n;
    const std::uint64_t expect = (nn + d / 2) / d;
    const std::uint64_t got = DivRoundHalfUp(nn, d);
    if (got != expect) CHECK_EQUAL(expect, got);
  }
}

// PicoToSi is odd, and the integer thresholds give the float comparison's
// outcome: at the threshold and its neighbours for limits of every size and
// sign, and at random values near and far from random limits.
TEST(Int64Double, PicoThresholdsGiveTheFloatComparisonsOutcome) {
  using maglev::numeric::kPicoDomain;
  using maglev::numeric::PicoFirstAbove;
  using maglev::numeric::PicoFirstAtOrAbove;
  using maglev::numeric::PicoToSi;
  std::uint64_t s = 11;
  for (int i = 0; i < kSamples / 10; ++i) {
    const std::int64_t v = random_int64(&s, 62);
    if (PicoToSi(-v) != -PicoToSi(v)) CHECK_EQUAL(-PicoToSi(v), PicoToSi(-v));
  }
  constexpr int kFixed = 20, kRandom = 200;
  float limits[kFixed + kRandom] = {0.0f,   -0.0f,  1e-12f,  5e-13f,  -1e-12f, 200e-6f, 15e-6f,
                                    -5e-6f, 40e-6f, 3e-4f,   5e-3f,   0.029f,  -0.029f, 0.0185f,
                                    -0.0185f, 0.1f, 1e6f,    -1e6f,   1e7f,    -1e7f};
  for (int i = kFixed; i < kFixed + kRandom; ++i) {
    const double mag = std::ldexp(static_cast<double>(next(&s) >> 11) * 0x1.0p-53, -static_cast<int>(next(&s) % 40));
    limits[i] = static_cast<float>((next(&s) & 1u) ? -mag : mag);
  }
  for (float lim : limits) {
    const std::int64_t above = PicoFirstAbove(lim), at_or_above = PicoFirstAtOrAbove(lim);
    CHECK(above >= -kPicoDomain && above <= kPicoDomain + 1);
    CHECK(at_or_above >= -kPicoDomain && at_or_above <= kPicoDomain + 1);
    const auto in_domain = [](std::int64_t v) { return v >= -kPicoDomain && v <= kPicoDomain; };
    for (std::int64_t d = -3; d <= 3; ++d) {
      for (std::int64_t v : {above + d, at_or_above + d}) {
        if (!in_domain(v)) continue;  // the stated domain, |v| <= 2^62
        if ((v >= above) != (PicoToSi(v) > lim)) CHECK_EQUAL(PicoToSi(v) > lim, v >= above);
        if ((v < at_or_above) != (PicoToSi(v) < lim)) CHECK_EQUAL(PicoToSi(v) < lim, v < at_or_above);
      }
    }
    for (int k = 0; k < 200; ++k) {
      const std::int64_t v = (k % 2 == 0 ? above : 0) + random_int64(&s, k % 2 == 0 ? 16 : 61);
      if (!in_domain(v)) continue;
      if ((v >= above) != (PicoToSi(v) > lim)) CHECK_EQUAL(PicoToSi(v) > lim, v >= above);
      if ((v < at_or_above) != (PicoToSi(v) < lim)) CHECK_EQUAL(PicoToSi(v) < lim, v < at_or_above);
    }
  }
  // Beyond the domain: a limit no v reaches, and one every v passes.
  CHECK_EQUAL(kPicoDomain + 1, PicoFirstAbove(1e30f));
  CHECK_EQUAL(-kPicoDomain, PicoFirstAbove(-1e30f));
}
