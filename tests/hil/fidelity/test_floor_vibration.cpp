// Issue 15, the floor under the base (docs/PLANT.md section 12): the bands at
// the class level, the isolator's transmissibility, a time series with that
// spectrum whose displacement, velocity and acceleration agree, seeds, and
// the plant feeling it as the inertial force -m u'' and nothing else.
#include <cmath>
#include <cstdio>
#include <vector>

#include "maglev/plant/floor_vibration.hpp"
#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

namespace hil = maglev::hil;
using hil::FloorVibration;
using hil::FloorVibrationConfig;

TEST_GROUP(FloorVibration){};

namespace {
constexpr double kTick_s = 1.0 / 2500.0;
FloorVibrationConfig Class(const char* name, double isolator_hz = 0.0, double damping = 0.1) {
  FloorVibrationConfig c;
  const int i = hil::find_floor_class(name);
  CHECK(i > 0);
  c.band_velocity_m_per_s = hil::kFloorClasses[i].band_velocity_m_per_s;
  c.isolator_hz = isolator_hz;
  c.isolator_damping = damping;
  return c;
}
}  // namespace

TEST(FloorVibration, EveryBandIsAtTheClassLevelOnARigidBase) {
  const FloorVibration f(Class("vc-c"), kTick_s, 7);
  CHECK(f.active());
  for (int a = 0; a < FloorVibration::kAxes; ++a) {
    for (int b = 0; b < FloorVibration::kBands; ++b) {
      DOUBLES_EQUAL(12.5e-6, f.band_rms_velocity_m_per_s(a, b), 1e-15);
    }
  }
  DOUBLES_EQUAL(1.0, FloorVibration::BandCentre_Hz(0), 1e-15);
  DOUBLES_EQUAL(79.43282347242815, FloorVibration::BandCentre_Hz(19), 1e-9);
}

TEST(FloorVibration, TheIsolatorPassesLowBandsAndCutsHighOnes) {
  // |T| of a 1-DOF base-excited isolator: 1 well below f0, 1/(2 zeta) ~ at f0
  // (zeta small), and -> 2 zeta f0 / f (the damper) above sqrt(2) f0 ... f0 / zeta.
  DOUBLES_EQUAL(1.0, FloorVibration::Transmissibility(40.0, 0.0, 0.1), 0.0);
  DOUBLES_EQUAL(std::sqrt(1.0 + 0.04) / 0.2, FloorVibration::Transmissibility(1.5, 1.5, 0.1), 1e-12);
  const double t40 = FloorVibration::Transmissibility(40.0, 1.5, 0.1);
  const double r = 40.0 / 1.5;
  DOUBLES_EQUAL(std::sqrt((1.0 + 0.04 * r * r) / ((1.0 - r * r) * (1.0 - r * r) + 0.04 * r * r)), t40, 1e-15);
  CHECK(t40 > 0.006 && t40 < 0.009);  // ~ -42 dB at 40 Hz
  const FloorVibration rigid(Class("vc-a"), kTick_s, 3);
  const FloorVibration table(Class("vc-a", 1.5, 0.1), kTick_s, 3);
  for (int b = 0; b < FloorVibration::kBands; ++b) {
    // Same seed, same lines: each band scales by the rms of |T| over its lines,
    // within the |T| of its edges.
    const double fc = FloorVibration::BandCentre_Hz(b);
    const double lo = fc * std::pow(10.0, -0.05), hi = fc * std::pow(10.0, 0.05);
    const double ratio = table.band_rms_velocity_m_per_s(0, b) / rigid.band_rms_velocity_m_per_s(0, b);
    if (lo <= 1.5 && 1.5 <= hi) continue;  // the resonance inside: |T| is not monotonic there
    const double t_lo = FloorVibration::Transmissibility(lo, 1.5, 0.1);
    const double t_hi = FloorVibration::Transmissibility(hi, 1.5, 0.1);
    CHECK(ratio <= std::max(t_lo, t_hi) * (1 + 1e-12));
    CHECK(ratio >= std::min(t_lo, t_hi) * (1 - 1e-12));
  }
}

TEST(FloorVibration, TheTimeSeriesHasTheSpectrumAndIsConsistent) {
  FloorVibration f(Class("vc-b"), kTick_s, 11);
  const int n = 500000;  // 200 s: the 1 Hz band's lines average out
  double v2 = 0.0, worst_du = 0.0, worst_dv = 0.0, v_scale = 0.0, a_sum = 0.0;
  double u_prev = f.displacement_m(0), v_prev = f.velocity_m_per_s(0), v_block = 0.0;
  double v_mid_before = 0.0;  // the previous tick's midpoint velocity
  for (int k = 0; k < n; ++k) {
    double a[FloorVibration::kAxes];
    const double v_now = f.velocity_m_per_s(0);
    v2 += v_now * v_now;
    // Each tick's midpoint values; the acceleration held over the tick is
    // the midpoint's.
    f.Next(kTick_s, a);
    CHECK(std::isfinite(a[0]) && std::isfinite(a[1]));
    const double u = f.displacement_m(0), v = f.velocity_m_per_s(0);
    // The central difference of u between two midpoints is v at the tick
    // boundary between them, to (w dt)^2 / 24 (2e-3 at 80 Hz).
    worst_du = std::max(worst_du, std::fabs((u - u_prev) / kTick_s - 0.5 * (v + v_prev)));
    v_scale = std::max(v_scale, std::fabs(v));
    // Over blocks of 1 s (from the second: the first has no midpoint before
    // it): the held accelerations integrate to the velocity's change
    // (midpoint rule).
    if (k % 2500 == 0) {
      a_sum = 0.0;
      v_block = 0.5 * (v_mid_before + v_now);
    }
    a_sum += a[0] * kTick_s;
    if (k % 2500 == 2499 && k > 2500) worst_dv = std::max(worst_dv, std::fabs(0.5 * (v_now + v) - v_block - a_sum));
    u_prev = u;
    v_prev = v;
    v_mid_before = v_now;
  }
  const double v_rms = std::sqrt(v2 / n);
  // 20 bands of 25 um/s each: 25 sqrt(20) = 111.8 um/s.
  DOUBLES_EQUAL(25e-6 * std::sqrt(20.0), v_rms, 0.03 * 25e-6 * std::sqrt(20.0));
  std::printf("\n  vc-b: v rms %.4g m/s, max %.4g; worst u' - v %.3g, worst v change - sum a dt %.3g\n", v_rms,
              v_scale, worst_du, worst_dv);
  CHECK(worst_du < 2e-3 * v_scale);
  CHECK(worst_dv < 1e-2 * v_scale);
}

TEST(FloorVibration, ASeedIsARealizationAndNoneIsNothing) {
  FloorVibration a(Class("vc-d"), kTick_s, 5), b(Class("vc-d"), kTick_s, 5), c(Class("vc-d"), kTick_s, 6);
  bool differs = false;
  for (int k = 0; k < 3000; ++k) {
    double xa[FloorVibration::kAxes], xb[FloorVibration::kAxes], xc[FloorVibration::kAxes];
    a.Next(kTick_s, xa);
    b.Next(kTick_s, xb);
    c.Next(kTick_s, xc);
    CHECK(xa[0] == xb[0] && xa[1] == xb[1] && xa[2] == xb[2]);
    differs = differs || xa[0] != xc[0];
  }
  CHECK(differs);
  FloorVibration none;
  CHECK(!none.active());
  CHECK(!FloorVibrationConfig{}.active());
  double z[FloorVibration::kAxes] = {1.0, 1.0, 1.0};
  none.Next(kTick_s, z);
  CHECK(z[0] == 0.0 && z[1] == 0.0 && z[2] == 0.0);
  CHECK_EQUAL(-1, hil::find_floor_class("vc-z"));
  CHECK_EQUAL(0, hil::find_floor_class("none"));
}

TEST(FloorVibration, ThePlantFeelsTheFloorAsMinusMassTimesItsAcceleration) {
  // Two plants, the same state in mid-air, amplifiers off: one tick later
  // their velocities differ by the floor's -a dt, in x, y and z (the floor
  // moves vertically too), and nothing else.
  hil::PlantConfig quiet = hil::PlantConfig::Ideal();
  quiet.sensor_noise_enabled = false;
  quiet.body.gravity_enabled = false;  // it stays in mid-air
  // The z spring-damper acts on the platen's motion relative to the base,
  // which the floor changes: off, so that the floor is the only difference.
  quiet.suspension.enabled = false;
  hil::PlantConfig shaken = quiet;
  shaken.floor = Class("office");
  hil::Plant p0(quiet, 1), p1(shaken, 1);
  hil::BodyState s = p0.body_state();
  // Clear of the surface: the office floor moves it ~30 um in z in the 50
  // ticks once no spring holds it.
  s.position_m.z() = 200e-6;
  p0.set_body_state(s);
  p1.set_body_state(s);
  FloorVibration expected(shaken.floor, p1.tick_s(), 1);
  for (int k = 0; k < 50; ++k) {
    double a[FloorVibration::kAxes];
    expected.Next(p1.tick_s(), a);
    double v0[3], v1[3];
    for (int i = 0; i < 3; ++i) {
      v0[i] = p0.truth().velocity_m_per_s[i];
      v1[i] = p1.truth().velocity_m_per_s[i];
    }
    p0.advance_tick();
    p1.advance_tick();
    for (int i = 0; i < 3; ++i) {
      const double dv = (p1.truth().velocity_m_per_s[i] - v1[i]) - (p0.truth().velocity_m_per_s[i] - v0[i]);
      DOUBLES_EQUAL(-a[i] * p1.tick_s(), dv, 1e-6 * std::fabs(a[i]) * p1.tick_s() + 1e-15);
    }
    CHECK(a[2] != 0.0);
  }
}
