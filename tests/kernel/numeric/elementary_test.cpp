// The kernel's own elementary functions against <cmath>, over dense sweeps:
// the error bounds stated in elementary.hpp.
#include <cmath>
#include <cstdio>
#include <cstring>

#include "maglev/numeric/elementary.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

namespace n = maglev::numeric;

TEST_GROUP(Elementary) {};

TEST(Elementary, SineAndCosineWithinTheirBound) {
  double worst = 0.0;
  int count = 0;
  for (double x = -1e6; x <= 1e6; x += 997.13) {
    const double bound = 4e-16 + std::fabs(x) * 2e-22;
    worst = std::fmax(worst, std::fabs(n::dsin(x) - std::sin(x)) / bound);
    worst = std::fmax(worst, std::fabs(n::dcos(x) - std::cos(x)) / bound);
    ++count;
  }
  for (double x = -20.0; x <= 20.0; x += 1.37e-4) {
    worst = std::fmax(worst, std::fabs(n::dsin(x) - std::sin(x)) / 4e-16);
    worst = std::fmax(worst, std::fabs(n::dcos(x) - std::cos(x)) / 4e-16);
    ++count;
  }
  std::printf("\nsin/cos: %d points, worst error / bound %.3f\n", count, worst);
  CHECK_TRUE(count > 290000);
  CHECK_TRUE(worst <= 1.0);
  // Exact where it must be.
  DOUBLES_EQUAL(0.0, n::dsin(0.0), 0.0);
  DOUBLES_EQUAL(1.0, n::dcos(0.0), 0.0);
  CHECK_TRUE(std::isnan(n::dsin(INFINITY)) && std::isnan(n::dcos(NAN)));
}

TEST(Elementary, SinCosIsDsinAndDcosBitForBit) {
  // The references take both from one reduction: the same bits as the two calls.
  int count = 0;
  const auto same = [&count](double x) {
    double s = 1.0, c = 1.0;
    n::dsincos(x, &s, &c);
    const double es = n::dsin(x), ec = n::dcos(x);
    const bool ok = (std::isnan(es) ? std::isnan(s) : std::memcmp(&s, &es, sizeof s) == 0) &&
                    (std::isnan(ec) ? std::isnan(c) : std::memcmp(&c, &ec, sizeof c) == 0);
    if (!ok) std::printf("\ndsincos(%.17g) = %.17g, %.17g; dsin, dcos = %.17g, %.17g\n", x, s, c, es, ec);
    ++count;
    return ok;
  };
  for (double x = -1e6; x <= 1e6; x += 997.13) CHECK_TRUE(same(x));
  for (double x = -20.0; x <= 20.0; x += 1.37e-3) CHECK_TRUE(same(x));
  for (int k = -8; k <= 8; ++k) CHECK_TRUE(same(k * 1.5707963267948966));  // quadrant edges
  CHECK_TRUE(same(0.0) && same(-0.0) && same(INFINITY) && same(NAN) && same(1e300));
  CHECK_TRUE(count > 30000);
}

TEST(Elementary, TangentWithinItsBound) {
  double worst = 0.0;
  for (double x = -1.5707; x <= 1.5707; x += 1.1e-5) {
    const double t = std::tan(x);
    worst = std::fmax(worst, std::fabs(n::dtan(x) - t) / std::fabs(t) / 1e-15);
  }
  std::printf("\ntan: worst rel. error / 1e-15 %.3f\n", worst);
  CHECK_TRUE(worst <= 1.0);
}

TEST(Elementary, ArctangentEverywhereWithinItsBound) {
  double worst = 0.0;
  for (double a = -3.2; a <= 3.2; a += 7.3e-5) {
    for (double r : {1e-3, 0.7, 1.0, 3e4}) {
      const double y = r * std::sin(a), x = r * std::cos(a);
      worst = std::fmax(worst, std::fabs(n::datan2(y, x) - std::atan2(y, x)) / 5e-16);
    }
  }
  for (double t = -50.0; t <= 50.0; t += 3.1e-4) worst = std::fmax(worst, std::fabs(n::datan(t) - std::atan(t)) / 5e-16);
  std::printf("\natan2/atan: worst error / 5e-16 %.3f\n", worst);
  CHECK_TRUE(worst <= 1.0);
  // The quadrants and signed zeros as atan2 defines them.
  const double cases[][2] = {{0.0, 1.0}, {-0.0, 1.0}, {0.0, -1.0}, {-0.0, -1.0}, {1.0, 0.0}, {-1.0, 0.0},
                             {0.0, 0.0}, {0.0, -0.0}, {-0.0, -0.0}, {INFINITY, 1.0}, {1.0, -INFINITY},
                             {-INFINITY, -INFINITY}, {2.0, INFINITY}};
  for (const auto& c : cases) {
    const double want = std::atan2(c[0], c[1]), got = n::datan2(c[0], c[1]);
    DOUBLES_EQUAL(want, got, 1e-15);
    CHECK_EQUAL(std::signbit(want), std::signbit(got));
  }
}

TEST(Elementary, ExponentialLogarithmAndPowerWithinTheirBounds) {
  double worst_exp = 0.0, worst_log = 0.0, worst_pow = 0.0;
  for (double x = -700.0; x <= 700.0; x += 0.01731) {
    worst_exp = std::fmax(worst_exp, std::fabs(n::dexp(x) / std::exp(x) - 1.0) / 1e-15);
  }
  for (double x = 1e-300; x < 1e300; x *= 1.0173) {
    const double l = std::log(x);
    worst_log = std::fmax(worst_log, std::fabs(n::dlog(x) - l) / (4e-16 + 3e-16 * std::fabs(l)));
  }
  for (double a = 1e-3; a < 1e3; a *= 1.037) {
    for (double b : {-2.5, -1.0, 0.05, 0.5, 1.0 / 3.0, 2.0, 7.3}) {
      const double want = std::pow(a, b);
      worst_pow = std::fmax(worst_pow, std::fabs(n::dpow(a, b) / want - 1.0) /
                                           (1e-15 * (1.0 + std::fabs(b * std::log(a)))));
    }
  }
  std::printf("\nexp %.3f, log %.3f, pow %.3f (worst error / bound)\n", worst_exp, worst_log, worst_pow);
  CHECK_TRUE(worst_exp <= 1.0 && worst_log <= 1.0 && worst_pow <= 1.0);
  DOUBLES_EQUAL(1.0, n::dexp(0.0), 0.0);
  DOUBLES_EQUAL(0.0, n::dlog(1.0), 0.0);
  DOUBLES_EQUAL(1.0, n::dpow(5.0, 0.0), 0.0);
  CHECK_TRUE(std::isnan(n::dlog(-1.0)) && std::isinf(n::dlog(0.0)) && std::isnan(n::dpow(-2.0, 0.5)));
}
