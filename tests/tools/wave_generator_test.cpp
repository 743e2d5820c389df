// lab::WaveGenerator: the shapes (sine frequency and amplitude, multisine
// peak / period / tone lines, log sweep end, noise bounds), the refusals
// (axis limit, Nyquist, ...; nothing started), abort outside Ready, and the
// kernel side: Controller::set_injection clamps to the kernel's own limits.
#include <cmath>
#include <cstring>
#include <complex>
#include <memory>
#include <numbers>
#include <vector>

#include "maglev/controller/controller.hpp"
#include "maglev/lab_tools/lab_tick.hpp"
#include "maglev/lab_tools/wave_generator.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::lab;

namespace {

float g_table[kWaveTableLen];

std::vector<float> generate(WaveGenerator& w, int n) {
  std::vector<float> v;
  for (int i = 0; i < n; ++i) {
    const kernel::Injection in = w.step(true);
    v.push_back(in.active ? in.value : NAN);
  }
  return v;
}

double dft_mag(const std::vector<float>& v, std::size_t from, std::size_t n, double f, double fs) {
  std::complex<double> x{0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const double ph = 2 * std::numbers::pi * f * static_cast<double>(i) / fs;
    x += static_cast<double>(v[from + i]) * std::complex<double>{std::cos(ph), -std::sin(ph)};
  }
  return 2.0 * std::abs(x) / static_cast<double>(n);
}

}  // namespace

TEST_GROUP(Wave) {
  kernel::KernelConfig k = kernel::default_kernel_config();
  std::unique_ptr<WaveGenerator> w;
  void setup() override { w = std::make_unique<WaveGenerator>(g_table, kWaveTableLen); }
};

TEST(Wave, SineHasItsAmplitudeAndFrequency) {
  WaveConfig c{};
  c.shape = WaveShape::kSine;
  c.amplitude = 0.2f;
  c.f_start_Hz = 50.0f;
  CHECK(w->start(c, k) == WaveError::kOk);
  const auto v = generate(*w, 2500);
  double peak = 0;
  for (float x : v) peak = std::max(peak, std::fabs(static_cast<double>(x)));
  CHECK(peak <= 0.2 && peak > 0.2 * 0.998);  // 50 samples per period: the samples miss the crest by pi/50
  DOUBLES_EQUAL(0.2, dft_mag(v, 0, 2500, 50.0, 2500.0), 1e-4);
  DOUBLES_EQUAL(0.0, dft_mag(v, 0, 2500, 51.0, 2500.0), 1e-4);
}

TEST(Wave, MultisineIsPeriodicWithItsPeakAndItsTones) {
  CHECK(w->start(LoopResponseMultisine(), k) == WaveError::kOk);
  CHECK_EQUAL(2500u, w->period());
  CHECK_EQUAL(28, w->tones_generated());  // 5..400 Hz log-spaced: 28 distinct 1 Hz lines
  DOUBLES_EQUAL(5.0, w->tone_Hz(0), 1e-6);
  DOUBLES_EQUAL(400.0, w->tone_Hz(27), 1e-6);
  const auto v = generate(*w, 5000);
  double peak = 0;
  for (float x : v) peak = std::max(peak, std::fabs(static_cast<double>(x)));
  DOUBLES_EQUAL(0.1, peak, 1e-6);
  for (int i = 0; i < 2500; ++i) DOUBLES_EQUAL(v[static_cast<std::size_t>(i)], v[static_cast<std::size_t>(i + 2500)], 0.0);
  // Equal amplitude on every tone, nothing between tones.
  const double a0 = dft_mag(v, 0, 2500, w->tone_Hz(0), 2500.0);
  CHECK(a0 > 0.1 / 28);  // peak / tones: a crest factor below the tone count
  for (int t = 0; t < w->tones_generated(); ++t) DOUBLES_EQUAL(a0, dft_mag(v, 0, 2500, w->tone_Hz(static_cast<std::uint16_t>(t)), 2500.0), 1e-5);
  DOUBLES_EQUAL(0.0, dft_mag(v, 0, 2500, 100.0, 2500.0), 1e-5);  // not a tone (93, 109 are)
}

// Above 4096 Hz one period of the 1 Hz grid no longer fits the table sample
// by sample: the table is played with each sample held (issue 16: until
// 2026-11-29 the multisine, and so `stagectl frf`, was refused at 5, 10 and
// 20 kHz with kTable). Same tones, same peak; each tone scaled by the hold's
// Dirichlet kernel sin(pi f h / fs) / (h sin(pi f / fs)); nothing between
// the tones below the held table's Nyquist.
TEST(Wave, MultisineAboveTheTableHoldsItsSamplesAndKeepsItsTones) {
  struct Case {
    float rate_Hz;
    std::uint32_t hold, period;
  };
  for (const Case rc : {Case{5000.0f, 2u, 2500u}, Case{10000.0f, 4u, 2500u}, Case{20000.0f, 5u, 4000u}}) {
    k.servo_rate_Hz = rc.rate_Hz;
    w = std::make_unique<WaveGenerator>(g_table, kWaveTableLen);
    CHECK(w->start(LoopResponseMultisine(), k) == WaveError::kOk);
    CHECK_EQUAL(rc.hold, w->hold_ticks());
    CHECK_EQUAL(rc.period, w->period());
    CHECK_EQUAL(28, w->tones_generated());
    const auto n = static_cast<std::size_t>(rc.rate_Hz);  // one period: 1 s
    const auto v = generate(*w, static_cast<int>(2 * n));
    double peak = 0;
    for (float x : v) peak = std::max(peak, std::fabs(static_cast<double>(x)));
    DOUBLES_EQUAL(0.1, peak, 1e-6);
    for (std::size_t i = 0; i < n; ++i) {
      DOUBLES_EQUAL(v[i], v[i + n], 0.0);                  // periodic in 1 s
      DOUBLES_EQUAL(v[i], v[i - i % rc.hold], 0.0);        // held for `hold` ticks
    }
    const double fs = rc.rate_Hz, h = rc.hold;
    const auto held = [&](double f) { return std::sin(std::numbers::pi * f * h / fs) / (h * std::sin(std::numbers::pi * f / fs)); };
    const double a0 = dft_mag(v, 0, n, w->tone_Hz(0), fs) / held(w->tone_Hz(0));
    CHECK(a0 > 0.1 / 28);
    for (int t = 0; t < w->tones_generated(); ++t) {
      const double f = w->tone_Hz(static_cast<std::uint16_t>(t));
      DOUBLES_EQUAL(a0, dft_mag(v, 0, n, f, fs) / held(f), 1e-5);
    }
    for (double f : {100.0, 500.0, 1000.0}) DOUBLES_EQUAL(0.0, dft_mag(v, 0, n, f, fs), 1e-5);  // not tones
  }
}

TEST(Wave, SweepEndsAfterItsDurationAtItsEndFrequency) {
  WaveConfig c{};
  c.shape = WaveShape::kSweep;
  c.amplitude = 0.1f;
  c.f_start_Hz = 10.0f;
  c.f_end_Hz = 200.0f;
  c.duration_s = 2.0f;
  CHECK(w->start(c, k) == WaveError::kOk);
  const auto v = generate(*w, 5001);
  CHECK(w->state() == WaveState::kFinished);
  CHECK(std::isnan(v[5000]));
  // Zero crossings in the first / last 0.1 s: ~10 Hz / ~190 Hz (2 per period).
  auto crossings = [&](std::size_t from, std::size_t n) {
    int z = 0;
    for (std::size_t i = from + 1; i < from + n; ++i) z += (v[i - 1] < 0) != (v[i] < 0) ? 1 : 0;
    return z;
  };
  CHECK(crossings(0, 250) <= 3);
  CHECK(crossings(4750, 250) >= 35);
}

// A positive duration shorter than a tick lasts one tick: it used to round to
// 0 ticks, "until stopped", and the sweep's per-tick ratio (here 100) took
// its frequency past Nyquist within two ticks and on to inf.
TEST(Wave, ShortestSweepLastsOneTick) {
  WaveConfig c{};
  c.shape = WaveShape::kSweep;
  c.amplitude = 0.1f;
  c.f_start_Hz = 10.0f;
  c.f_end_Hz = 1000.0f;
  c.duration_s = 1e-4f;
  CHECK(w->start(c, k) == WaveError::kOk);
  const auto v = generate(*w, 3);
  CHECK(w->state() == WaveState::kFinished);
  CHECK(std::isfinite(v[0]));
  CHECK(std::isnan(v[1]));
  CHECK(std::isnan(v[2]));
}

TEST(Wave, NoiseStaysInsideItsAmplitude) {
  WaveConfig c{};
  c.shape = WaveShape::kNoise;
  c.amplitude = 0.05f;
  c.duration_s = 1.0f;
  CHECK(w->start(c, k) == WaveError::kOk);
  const auto v = generate(*w, 2500);
  double mean = 0, peak = 0;
  for (float x : v) {
    mean += static_cast<double>(x) / 2500.0;
    peak = std::max(peak, std::fabs(static_cast<double>(x)));
  }
  CHECK(peak <= 0.05);
  CHECK(peak > 0.045);
  DOUBLES_EQUAL(0.0, mean, 0.005);
}

TEST(Wave, RefusesWhatItCannotHonourAndStartsNothing) {
  WaveConfig c{};
  c.shape = WaveShape::kSine;
  c.f_start_Hz = 10.0f;
  c.amplitude = 0.51f;  // kernel excitation limit 0.5 A
  CHECK(w->start(c, k) == WaveError::kAmplitude);
  c.point = InjectionPoint::kReference;
  c.amplitude = 101e-6f;  // x max_step 100 um
  CHECK(w->start(c, k) == WaveError::kAmplitude);
  c.amplitude = 10e-6f;
  c.f_start_Hz = 1250.0f;  // Nyquist at 2.5 kHz
  CHECK(w->start(c, k) == WaveError::kNyquist);
  c.shape = WaveShape::kSweep;
  c.f_start_Hz = 10.0f;
  c.f_end_Hz = 1300.0f;
  c.duration_s = 1.0f;
  CHECK(w->start(c, k) == WaveError::kNyquist);
  c.f_end_Hz = 5.0f;
  CHECK(w->start(c, k) == WaveError::kFrequency);
  c.f_end_Hz = 100.0f;
  c.duration_s = 0.0f;
  CHECK(w->start(c, k) == WaveError::kDuration);
  c.shape = WaveShape::kMultisine;
  c.tones = 0;
  CHECK(w->start(c, k) == WaveError::kTones);
  c.tones = 10;
  c.axis = 6;
  CHECK(w->start(c, k) == WaveError::kAxis);
  CHECK(w->state() == WaveState::kOff);
  CHECK_FALSE(w->step(true).active);
}

TEST(Wave, AbortsWhenMotionIsNoLongerAllowed) {
  WaveConfig c{};
  c.amplitude = 0.1f;
  c.f_start_Hz = 10.0f;
  CHECK(w->start(c, k) == WaveError::kOk);
  CHECK(w->step(true).active);
  CHECK(w->start(c, k) == WaveError::kBusy);
  CHECK_FALSE(w->step(false).active);
  CHECK(w->state() == WaveState::kAborted);
  CHECK_FALSE(w->step(true).active);
}

TEST(Wave, KernelIgnoresInjectionOutsideReady) {
  auto ctl = std::make_unique<kernel::Controller<float>>();
  kernel::Injection in{};
  in.active = true;
  in.axis = 0;
  in.value = 5.0f;  // far above the limit
  ctl->set_injection(in);
  CHECK(ctl->motion_active());
  (void)ctl->step(io::SensorSample{}, false);  // idle: motion not allowed
  DOUBLES_EQUAL(0.0, ctl->status().excitation_A[0], 0.0);
  CHECK_FALSE(ctl->status().injection_active);
}

namespace {
bool same_injection(const kernel::Injection& a, const kernel::Injection& b) {
  return a.active == b.active && a.at_reference == b.at_reference && a.axis == b.axis &&
         std::memcmp(&a.value, &b.value, sizeof a.value) == 0;
}
}  // namespace

TEST(Wave, LabTickGivesTheIdleInjectionOnceAndStillRunsAStartedWave) {
  // LabTick::before_step skips the ticks of a generator that is not running,
  // once the controller holds the idle generator's injection (Injection{}).
  // The controller must hold exactly what set_injection(wave.step(ready))
  // would have given it on every tick.
  auto ctl = std::make_unique<kernel::Controller<float>>();
  kernel::Injection stale{};
  stale.active = true;
  stale.axis = 2;
  stale.value = 0.01f;
  ctl->set_injection(stale);  // what a bind() may find
  LabTick<float>::bind(ctl.get(), nullptr, w.get());
  LabTick<float>::before_step();
  CHECK(same_injection(kernel::Injection{}, ctl->injection()));
  for (int i = 0; i < 5; ++i) {
    LabTick<float>::before_step();
    CHECK(same_injection(kernel::Injection{}, ctl->injection()));
  }
  // A started wave is stepped again: the controller is not Ready (a fresh
  // controller is Idle), so the generator's step() aborts it.
  WaveConfig c{};
  c.amplitude = 0.1f;
  c.f_start_Hz = 10.0f;
  CHECK(w->start(c, k) == WaveError::kOk);
  LabTick<float>::before_step();
  CHECK(w->state() == WaveState::kAborted);
  CHECK(same_injection(kernel::Injection{}, ctl->injection()));
  // Rebinding forgets what the controller holds.
  ctl->set_injection(stale);
  LabTick<float>::bind(ctl.get(), nullptr, w.get());
  LabTick<float>::before_step();
  CHECK(same_injection(kernel::Injection{}, ctl->injection()));
}
