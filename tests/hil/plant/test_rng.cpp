// The plant's normal generator (issue 16 item 5): the ziggurat must draw the
// same distribution as the polar method it replaced (std::normal_distribution
// on the same mt19937_64), judged on what the bench's noise figures depend
// on: mean, variance, a tail probability and quantile, the whole CDF
// (Kolmogorov-Smirnov) and whiteness (lag-1 autocorrelation). Both
// generators are measured, so a failure says which one is off.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <vector>

#include "maglev/plant/rng.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::NormalMethod;
using maglev::hil::Rng;

namespace {
constexpr std::size_t kDraws = 2'000'000;
constexpr double kN = 2'000'000.0;

struct Stats {
  double mean = 0, variance = 0, p_abs_gt_3 = 0, p_abs_gt_4 = 0, q999_abs = 0, lag1 = 0, ks = 0;
};

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

Stats Measure(NormalMethod method, std::uint64_t seed) {
  Rng rng(seed, method);
  std::vector<double> v(kDraws);
  for (double& x : v) x = rng.Normal();
  Stats s;
  double sum = 0;
  for (double x : v) sum += x;
  s.mean = sum / kN;
  double ss = 0, lag = 0;
  int gt3 = 0, gt4 = 0;
  for (std::size_t k = 0; k < kDraws; ++k) {
    const double d = v[k] - s.mean;
    ss += d * d;
    if (k > 0) lag += d * (v[k - 1] - s.mean);
    gt3 += std::fabs(v[k]) > 3.0;
    gt4 += std::fabs(v[k]) > 4.0;
  }
  s.variance = ss / (kN - 1.0);
  s.lag1 = lag / ss;
  s.p_abs_gt_3 = static_cast<double>(gt3) / kN;
  s.p_abs_gt_4 = static_cast<double>(gt4) / kN;
  std::sort(v.begin(), v.end());
  for (std::size_t k = 0; k < kDraws; ++k) {
    const double c = NormalCdf(v[k]);
    s.ks = std::max({s.ks, std::fabs(c - static_cast<double>(k) / kN), std::fabs(static_cast<double>(k + 1) / kN - c)});
  }
  std::vector<double> a(kDraws);
  for (std::size_t k = 0; k < a.size(); ++k) a[k] = std::fabs(v[k]);
  std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(kDraws * 999 / 1000), a.end());
  s.q999_abs = a[kDraws * 999 / 1000];
  return s;
}

void Print(const char* name, const Stats& s) {
  std::printf("\n  %-8s mean %+.5f var %.5f P(|x|>3) %.6f P(|x|>4) %.7f q99.9(|x|) %.4f lag1 %+.5f KS %.5f", name, s.mean,
              s.variance, s.p_abs_gt_3, s.p_abs_gt_4, s.q999_abs, s.lag1, s.ks);
}

// Bounds: 5 standard errors of each estimate for N(0, 1) white noise.
void CheckNormal(const Stats& s) {
  const double n = kN;
  CHECK(std::fabs(s.mean) < 5.0 / std::sqrt(n));
  CHECK(std::fabs(s.variance - 1.0) < 5.0 * std::sqrt(2.0 / n));
  const double p3 = std::erfc(3.0 / std::sqrt(2.0));  // 0.0026998
  CHECK(std::fabs(s.p_abs_gt_3 - p3) < 5.0 * std::sqrt(p3 / n));
  const double p4 = std::erfc(4.0 / std::sqrt(2.0));  // 6.334e-5: beyond R = 3.654, the tail method's draws
  CHECK(std::fabs(s.p_abs_gt_4 - p4) < 5.0 * std::sqrt(p4 / n));
  // q99.9 of |x| = 3.2905; its standard error sqrt(p (1 - p) / n) / (2 phi(q)) = 0.0063.
  CHECK(std::fabs(s.q999_abs - 3.2905267) < 0.032);
  CHECK(std::fabs(s.lag1) < 5.0 / std::sqrt(n));
  CHECK(s.ks < 1.63 / std::sqrt(n));  // Kolmogorov-Smirnov at the 1 % level
}
}  // namespace

TEST_GROUP(PlantRng){};

TEST(PlantRng, ZigguratLayersHaveEqualAreas) {
  const auto& t = maglev::hil::detail::ziggurat_tables();
  const double v = maglev::hil::detail::ZigguratTables::kV;
  const double r = maglev::hil::detail::ZigguratTables::kR;
  // The base: the rectangle R x f(R) plus the tail beyond R.
  const double tail = std::sqrt(std::acos(-1.0) / 2.0) * std::erfc(r / std::sqrt(2.0));
  DOUBLES_EQUAL(v, r * std::exp(-0.5 * r * r) + tail, 1e-9 * v);
  DOUBLES_EQUAL(v, t.x[0] * t.f[1], 1e-12 * v);  // the base as a rectangle of height f(R)
  for (std::size_t i = 1; i < 256; ++i) DOUBLES_EQUAL(v, t.x[i] * (t.f[i + 1] - t.f[i]), 1e-8 * v);
  CHECK(t.x[255] > 0.0 && t.x[256] == 0.0 && t.f[256] == 1.0);
}

TEST(PlantRng, ZigguratDrawsTheDistributionOfThePolarMethod) {
  for (std::uint64_t seed : {1ull, 42ull}) {
    const Stats zig = Measure(NormalMethod::kZiggurat, seed);
    const Stats polar = Measure(NormalMethod::kPolar, seed);
    std::printf("\n  seed %llu:", static_cast<unsigned long long>(seed));
    Print("ziggurat", zig);
    Print("polar", polar);
    CheckNormal(zig);
    CheckNormal(polar);
  }
}

TEST(PlantRng, PolarKeepsTheSequenceOfStdNormalDistribution) {
  std::mt19937_64 engine(7);
  std::normal_distribution<double> normal{0.0, 1.0};
  Rng rng(7, NormalMethod::kPolar);
  for (int k = 0; k < 1000; ++k) CHECK_EQUAL(normal(engine), rng.Normal());
}

TEST(PlantRng, ASeedGivesOneSequence) {
  Rng a(3), b(3);
  for (int k = 0; k < 100000; ++k) CHECK_EQUAL(a.Normal(), b.Normal());
}
