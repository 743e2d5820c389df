// Biquad stages: measured response == exact discrete H(e^jwT); notch depth
// at f0, low-pass gain Q at f0, lead-lag dc / high-frequency gains.
#include <cmath>
#include <complex>
#include <cstdio>

#include "CppUTest/TestHarness.h"
#include "freq_response.hpp"
#include "maglev/axis_loops/biquad.hpp"

using namespace maglev::kernel;
using maglev::numeric::Q7_24;
using maglev::numeric::ScalarTraits;
using loops_test::kFs;
using loops_test::kPi;
using loops_test::kT;
using cplx = std::complex<double>;

namespace {

cplx exact(const BiquadDesign& d, double f) {
  const cplx zi = std::polar(1.0, -2.0 * kPi * f * kT);
  return (d.b0 + d.b1 * zi + d.b2 * zi * zi) / (1.0 + d.a1 * zi + d.a2 * zi * zi);
}

template <typename Scalar>
cplx measure(const BiquadConfig& cfg, double f) {
  using Tr = ScalarTraits<Scalar>;
  BiquadCoefficients<Scalar> c;
  CHECK(design_biquad<Scalar>(cfg, kFs, &c) == LoopDesignError::kOk);
  BiquadState<Scalar> s{};
  // 1 s settle (the notch's slowest pole decays as exp(-w0/(2Q) t)), 2 s window.
  return loops_test::measure_gain([&](double x) { return Tr::to_double(biquad_update(c, s, Tr::from_double(x))); },
                                  f, 1.0, 2500, 5000);
}

void check_stage(const BiquadConfig& cfg, const double* freqs, int n, const char* name) {
  BiquadDesign d;
  CHECK(design_biquad_double(cfg, kFs, &d) == LoopDesignError::kOk);
  for (int i = 0; i < n; ++i) {
    const double f = freqs[i];
    const cplx h = exact(d, f);
    const cplx mf = measure<float>(cfg, f);
    const cplx mq = measure<Q7_24>(cfg, f);
    std::printf("\n[biquad %s] %6.1f Hz |H|=%.5f (%.2f dB) ph=%7.2f  meas-exact: float %.1e Q7.24 %.1e", name, f,
                std::abs(h), 20 * std::log10(std::abs(h)), loops_test::phase_deg(h), std::abs(mf - h),
                std::abs(mq - h));
    // Absolute error on a unit-amplitude input: float 1e-5, Q7.24 2e-5
    // (coefficient quantisation 2^-29 and 1-LSB output rounding).
    CHECK(std::abs(mf - h) < 1e-5);
    CHECK(std::abs(mq - h) < 2e-5);
  }
}

}  // namespace

TEST_GROUP(Biquad){};

TEST(Biquad, NotchHasItsDepthAtF0) {
  BiquadConfig cfg;
  cfg.type = BiquadType::kNotch;
  cfg.frequency_Hz = 180.0f;
  cfg.q = 2.0f;
  cfg.depth_dB = 30.0f;
  const double freqs[] = {10.0, 100.0, 180.0, 300.0, 1000.0};
  check_stage(cfg, freqs, 5, "notch");
  BiquadDesign d;
  CHECK(design_biquad_double(cfg, kFs, &d) == LoopDesignError::kOk);
  // Prewarped: exactly -30 dB at f0 and unity at dc and Nyquist.
  DOUBLES_EQUAL(-30.0, 20 * std::log10(std::abs(exact(d, 180.0))), 1e-6);
  DOUBLES_EQUAL(1.0, std::abs(exact(d, 0.0)), 1e-12);
  DOUBLES_EQUAL(1.0, std::abs(exact(d, 1250.0)), 1e-9);
  // Measured depth in Q7.24 too.
  DOUBLES_EQUAL(-30.0, 20 * std::log10(std::abs(measure<Q7_24>(cfg, 180.0))), 0.05);
}

TEST(Biquad, LowPassHasGainQAtCornerAndUnityDc) {
  BiquadConfig cfg;
  cfg.type = BiquadType::kLowPass;
  cfg.frequency_Hz = 400.0f;
  cfg.q = 0.7071f;
  const double freqs[] = {5.0, 100.0, 400.0, 1000.0};
  check_stage(cfg, freqs, 4, "lowpass");
  BiquadDesign d;
  CHECK(design_biquad_double(cfg, kFs, &d) == LoopDesignError::kOk);
  DOUBLES_EQUAL(0.7071, std::abs(exact(d, 400.0)), 1e-6);
  DOUBLES_EQUAL(-90.0, loops_test::phase_deg(exact(d, 400.0)), 1e-6);
  DOUBLES_EQUAL(1.0, std::abs(exact(d, 0.0)), 1e-12);
  DOUBLES_EQUAL(0.0, std::abs(exact(d, 1250.0)), 1e-9);  // Tustin zero at Nyquist
}

TEST(Biquad, LeadLagCorners) {
  BiquadConfig cfg;
  cfg.type = BiquadType::kLeadLag;
  cfg.frequency_Hz = 30.0f;  // zero
  cfg.pole_Hz = 120.0f;
  const double freqs[] = {1.0, 30.0, 60.0, 120.0, 500.0};
  check_stage(cfg, freqs, 5, "leadlag");
  BiquadDesign d;
  CHECK(design_biquad_double(cfg, kFs, &d) == LoopDesignError::kOk);
  DOUBLES_EQUAL(1.0, std::abs(exact(d, 0.0)), 1e-12);
  // Both corners prewarped: the discrete stage is the continuous prototype
  // with corners tan-warped, so its maximum lead is asin((a-1)/(a+1)) with
  // a = tan(pi 120 T)/tan(pi 30 T) = 4.029 (37.03 deg, vs 36.87 for a = 4),
  // reached at the warped geometric mean (~60 Hz).
  const double ratio = std::tan(kPi * 120.0 * kT) / std::tan(kPi * 30.0 * kT);
  const double fm = std::atan(std::sqrt(std::tan(kPi * 30.0 * kT) * std::tan(kPi * 120.0 * kT))) / (kPi * kT);
  DOUBLES_EQUAL(std::asin((ratio - 1) / (ratio + 1)) * 180.0 / kPi, loops_test::phase_deg(exact(d, fm)), 1e-9);
  DOUBLES_EQUAL(ratio, std::abs(exact(d, 1250.0)), 1e-9);  // high-frequency gain wp/wz (warped)
}

TEST(Biquad, DisabledStagePassesThroughAndInvalidConfigsAreRejected) {
  BiquadCoefficients<Q7_24> c;
  CHECK(design_biquad<Q7_24>(BiquadConfig{}, kFs, &c) == LoopDesignError::kOk);
  CHECK(!c.enabled);
  BiquadState<Q7_24> s{};
  DOUBLES_EQUAL(1.25, biquad_update(c, s, Q7_24::from_double(1.25)).to_double(), 0.0);
  BiquadConfig bad;
  bad.type = BiquadType::kNotch;
  bad.frequency_Hz = 1300.0f;
  CHECK(design_biquad<Q7_24>(bad, kFs, &c) == LoopDesignError::kFilterAboveNyquist);
  bad.frequency_Hz = 100.0f;
  bad.q = 0.0f;
  CHECK(design_biquad<Q7_24>(bad, kFs, &c) == LoopDesignError::kBadQuality);
  bad.type = BiquadType::kLeadLag;
  bad.frequency_Hz = 10.0f;
  bad.pole_Hz = 1000.0f;  // high-frequency gain ~ b0 > 8: does not fit Q3.28
  CHECK(design_biquad<Q7_24>(bad, kFs, &c) == LoopDesignError::kCoefficientOutOfRange);
  BiquadCoefficients<float> cf;
  CHECK(design_biquad<float>(bad, kFs, &cf) == LoopDesignError::kOk);
}

namespace {

// The chains as the kernel ran them before it skipped pass-through stages:
// every stage's biquad_update() on every tick (disabled ones track their input).
template <typename Scalar>
Scalar tracking_chain(const BiquadCoefficients<Scalar> (&c)[kMaxBiquadStages], BiquadState<Scalar> (&s)[kMaxBiquadStages],
                      Scalar x) {
  for (int f = 0; f < kMaxBiquadStages; ++f) x = biquad_update(c[f], s[f], x);
  return x;
}

// The stage kinds a configuration may hold: off, a notch, a low-pass, a lead-lag.
void stage_kinds(BiquadConfig (&kinds)[4]) {
  kinds[0] = BiquadConfig{};
  kinds[1].type = BiquadType::kNotch;
  kinds[1].frequency_Hz = 120.0f;
  kinds[1].q = 2.0f;
  kinds[1].depth_dB = 20.0f;
  kinds[2].type = BiquadType::kLowPass;
  kinds[2].frequency_Hz = 400.0f;
  kinds[3].type = BiquadType::kLeadLag;
  kinds[3].frequency_Hz = 60.0f;
  kinds[3].pole_Hz = 240.0f;
}

template <typename Scalar>
void check_bank_equals_tracking() {
  using Tr = ScalarTraits<Scalar>;
  constexpr std::size_t kChains = 3;
  BiquadConfig kinds[4];
  stage_kinds(kinds);
  BiquadCoefficients<Scalar> designed[4];
  for (int k = 0; k < 4; ++k) CHECK(design_biquad<Scalar>(kinds[k], kFs, &designed[k]) == LoopDesignError::kOk);

  BiquadCoefficients<Scalar> c[kChains][kMaxBiquadStages];  // all off, as a controller starts
  bool enabled[kChains] = {};
  BiquadBank<Scalar, kChains> bank;
  BiquadState<Scalar> ref[kChains][kMaxBiquadStages]{};
  std::uint32_t rng = 12345u;
  auto next = [&rng]() { return rng = rng * 1664525u + 1013904223u; };
  int switches_on = 0, switches_off = 0, quick_returns = 0;
  int last_off[kChains] = {};
  for (int tick = 0; tick < 200000; ++tick) {
    // A new configuration every ~16 ticks, sometimes two or three between
    // two ticks; each changes one chain or all of them; stages off in half
    // the draws.
    if ((next() >> 28) == 0) {
      const int reconfigurations = 1 + static_cast<int>(next() >> 31) + static_cast<int>(next() >> 31);
      for (int r = 0; r < reconfigurations; ++r) {
        const bool all = (next() >> 31) != 0;
        const std::size_t one = (next() >> 16) % kChains;
        bool was[kChains], now[kChains];
        for (std::size_t k = 0; k < kChains; ++k) {
          was[k] = enabled[k];
          if (all || k == one) {
            for (int f = 0; f < kMaxBiquadStages; ++f) {
              const std::uint32_t pick = next() >> 29;  // 0..7
              c[k][f] = designed[pick < 4 ? 0 : pick - 4];
            }
          }
          now[k] = biquad_chain_enabled(c[k]);
          if (!was[k] && now[k]) {
            ++switches_on;
            quick_returns += tick - last_off[k] < 2 ? 1 : 0;
          }
          if (was[k] && !now[k]) {
            ++switches_off;
            last_off[k] = tick;
          }
          enabled[k] = now[k];
        }
        bank.reconfigure(was, now);
      }
    }
    for (std::size_t k = 0; k < kChains; ++k) {
      const Scalar x = Tr::from_double(static_cast<double>(static_cast<std::int32_t>(next())) * 0x1.0p-33);
      const Scalar y_ref = tracking_chain(c[k], ref[k], x);
      const Scalar y = bank.update(static_cast<int>(k), c[k], enabled[k], x);
      if (!(Tr::to_double(y) == Tr::to_double(y_ref))) {
        std::printf("\n[biquad bank] tick %d chain %d: %.17g vs tracking %.17g", tick, static_cast<int>(k), Tr::to_double(y),
                    Tr::to_double(y_ref));
        FAIL("the bank's output differs from tracking every stage");
      }
    }
    bank.end_tick();
  }
  // The sequence exercised both hand-overs many times, re-enabling within
  // two ticks of disabling included.
  std::printf("\n[biquad bank] %d enabled, %d disabled, %d re-enabled within two ticks", switches_on, switches_off,
              quick_returns);
  CHECK(switches_on > 1000);
  CHECK(switches_off > 1000);
  CHECK(quick_returns > 50);
}

}  // namespace

// Skipping the pass-through stages of chains with none enabled, and seeding
// them when one is enabled, gives the output of running every stage every
// tick, bit for bit, over random inputs and random configurations (float
// and Q7.24).
TEST(Biquad, BankSkippingPassThroughStagesEqualsTrackingEveryStage) {
  check_bank_equals_tracking<float>();
  check_bank_equals_tracking<Q7_24>();
}

// The float kernel's taps are held as double for its MACs (AccCoeff): each
// exactly the float the tap rounds to, for every stage type at every
// offered servo rate (Pid2Dof.TheAccumulatorGainsAreFloatValuesExactly has
// the compiler bug this guards against).
TEST(Biquad, TheFloatKernelsTapsAreFloatValuesExactly) {
  const double rates[] = {2500.0, 5000.0, 10000.0, 20000.0};
  BiquadConfig kinds[4];
  stage_kinds(kinds);
  for (int k = 1; k < 4; ++k) {
    const BiquadConfig& cfg = kinds[k];
    for (double fs : rates) {
      BiquadCoefficients<float> c;
      CHECK(design_biquad<float>(cfg, fs, &c) == LoopDesignError::kOk);
      CHECK(c.enabled);
      const double v[] = {c.b0, c.b1, c.b2, c.a1, c.a2};
      for (double x : v) CHECK_EQUAL(static_cast<double>(static_cast<float>(x)), x);
    }
  }
}
