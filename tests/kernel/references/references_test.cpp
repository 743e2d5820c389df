// Reference generators: exact targets, limits never exceeded (checked on the
// sampled positions by finite differences), analytic durations, circle
// radius, rejected requests.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "CppUTest/TestHarness.h"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/references/references.hpp"

using namespace maglev::kernel;

namespace {

constexpr double kFs = maglev::io::stage::kServoRate_Hz;
constexpr double kT = 1.0 / kFs;
constexpr double kPi = 3.14159265358979323846;
constexpr std::int64_t kMm = 1000000000;  // pm per mm

AxisReferenceLimits stage_limits_x() {
  AxisReferenceLimits l;
  l.max_velocity = 0.3;
  l.max_acceleration = 1.2;
  l.max_jerk = 100.0;
  l.max_step_pico = 100 * 1000000;  // 100 um
  l.travel_min_pico = -28 * kMm;    // 56 mm travel (Sec. V)
  l.travel_max_pico = 28 * kMm;
  return l;
}

struct ProfileStats {
  double max_v = 0, max_a = 0, max_j = 0;         // from finite differences of positions
  double max_v_out = 0, max_a_out = 0;            // reported velocity / acceleration
  double max_v_mismatch = 0;                      // |fd velocity - reported| (mid-point)
  std::int64_t final_pos = 0;
  bool monotone = true;
};

template <typename Gen>
ProfileStats scan(const Gen& g, std::int64_t ticks, double dir) {
  ProfileStats st;
  std::int64_t p_prev2 = 0, p_prev = 0;
  double v_prev = 0;
  for (std::int64_t k = 0; k <= ticks + 5; ++k) {
    const AxisReference r = g.sample(k);
    const std::int64_t p = r.position_pico;
    if (k >= 1) {
      const double v = static_cast<double>(p - p_prev) * 1e-12 / kT;
      st.max_v = std::fmax(st.max_v, std::fabs(v));
      if (dir * v < -1e-9) st.monotone = false;
      if (k >= 2) {
        const double a = static_cast<double>(p - 2 * p_prev + p_prev2) * 1e-12 / (kT * kT);
        st.max_a = std::fmax(st.max_a, std::fabs(a));
        if (k >= 3) st.max_j = std::fmax(st.max_j, std::fabs(a - v_prev) / kT);
        v_prev = a;
      }
      const double v_mid = 0.5 * (static_cast<double>(r.velocity) + static_cast<double>(g.sample(k - 1).velocity));
      st.max_v_mismatch = std::fmax(st.max_v_mismatch, std::fabs(v - v_mid));
    }
    st.max_v_out = std::fmax(st.max_v_out, std::fabs(static_cast<double>(r.velocity)));
    st.max_a_out = std::fmax(st.max_a_out, std::fabs(static_cast<double>(r.acceleration)));
    p_prev2 = p_prev;
    p_prev = p;
    st.final_pos = p;
  }
  return st;
}

}  // namespace

TEST_GROUP(References){};

TEST(References, TrapezoidMovesOfFig10ReachTargetWithinLimits) {
  const AxisReferenceLimits lim = stage_limits_x();
  const double dists_mm[] = {12.0, 24.0, 56.0};
  const double accs[] = {0.6, 1.2};
  for (double dmm : dists_mm) {
    for (double a : accs) {
      const std::int64_t start = -28 * kMm;
      const std::int64_t target = start + static_cast<std::int64_t>(dmm) * kMm;
      const double v = 0.25;
      MoveReference m;
      CHECK(m.plan_trapezoid(start, target, v, a, kFs, lim) == ReferenceError::kOk);
      // Analytic duration: d/v + v/a if vmax is reached, else 2 sqrt(d/a).
      const double d = dmm * 1e-3;
      const double t_exp = d >= v * v / a ? d / v + v / a : 2.0 * std::sqrt(d / a);
      DOUBLES_EQUAL(t_exp, m.duration_s(), 1e-12);
      LONGS_EQUAL(static_cast<long>(std::ceil(t_exp * kFs - 1e-9)), static_cast<long>(m.total_ticks()));
      const ProfileStats st = scan(m, m.total_ticks(), 1.0);
      std::printf("\n[trapezoid %2.0f mm @ %.1f m/s^2] %.4f s, %ld ticks, max fd v %.6f m/s a %.6f m/s^2",
                  dmm, a, m.duration_s(), static_cast<long>(m.total_ticks()), st.max_v, st.max_a);
      CHECK(st.final_pos == target);
      CHECK(m.sample(m.total_ticks()).position_pico == target);
      CHECK(m.sample(m.total_ticks() - 1).position_pico != target);  // really arrives at the last tick
      CHECK(st.monotone);
      // Finite differences of the pm-rounded positions: 1 pm of rounding is
      // 2.5e-9 m/s and 1.25e-5 m/s^2.
      CHECK(st.max_v <= v + 1e-8);
      CHECK(st.max_a <= a + 1e-4);
      CHECK(st.max_v_out <= v * (1 + 1e-6));
      CHECK(st.max_a_out <= a * (1 + 1e-6));
      CHECK(st.max_v_mismatch < a * kT);  // reported velocity is the profile's
    }
  }
  // Backwards and zero-length moves.
  MoveReference back;
  CHECK(back.plan_trapezoid(5 * kMm, -7 * kMm, 0.2, 0.6, kFs, lim) == ReferenceError::kOk);
  const ProfileStats sb = scan(back, back.total_ticks(), -1.0);
  CHECK(sb.final_pos == -7 * kMm);
  CHECK(sb.monotone);
  CHECK(sb.max_v <= 0.2 + 1e-8);
  MoveReference none;
  CHECK(none.plan_trapezoid(kMm, kMm, 0.2, 0.6, kFs, lim) == ReferenceError::kOk);
  LONGS_EQUAL(0, static_cast<long>(none.total_ticks()));
  CHECK(none.sample(0).position_pico == kMm);
}

TEST(References, SCurveRespectsJerkAndReachesTarget) {
  const AxisReferenceLimits lim = stage_limits_x();
  const double cases[][4] = {// d [m], v, a, j
                             {0.024, 0.25, 1.2, 40.0},
                             {0.002, 0.25, 1.2, 40.0},   // v not reached
                             {0.0001, 0.25, 1.2, 40.0},  // a not reached either
                             {0.056, 0.3, 0.6, 20.0}};
  for (const auto& c : cases) {
    const std::int64_t start = -28 * kMm;
    const std::int64_t target = start + static_cast<std::int64_t>(std::llround(c[0] * 1e12));
    MoveReference m;
    CHECK(m.plan_scurve(start, target, c[1], c[2], c[3], kFs, lim) == ReferenceError::kOk);
    const ProfileStats st = scan(m, m.total_ticks(), 1.0);
    std::printf("\n[s-curve %.4f m] %.4f s, peak v %.4f; max fd v %.5f a %.5f j %.3f", c[0], m.duration_s(),
                m.peak_velocity(), st.max_v, st.max_a, st.max_j);
    CHECK(st.final_pos == target);
    CHECK(st.monotone);
    CHECK(st.max_v <= c[1] + 1e-8);
    CHECK(st.max_a <= c[2] + 1e-4);
    // Third differences of pm positions: rounding contributes up to
    // 4 pm / T^3 = 0.0625 m/s^3.
    CHECK(st.max_j <= c[3] * (1 + 1e-6) + 0.07);
    double s = 0, v = 0, a = 0;
    m.evaluate(m.duration_s(), &s, &v, &a);
    DOUBLES_EQUAL(c[0], s, 1e-12);
    DOUBLES_EQUAL(0.0, v, 1e-9);
    DOUBLES_EQUAL(0.0, a, 1e-9);
  }
  // Analytic duration when v and a are reached: d/v + v/a + a/j.
  MoveReference m;
  CHECK(m.plan_scurve(-25 * kMm, 25 * kMm, 0.2, 1.2, 40.0, kFs, lim) == ReferenceError::kOk);
  DOUBLES_EQUAL(0.05 / 0.2 + 0.2 / 1.2 + 1.2 / 40.0, m.duration_s(), 1e-12);
  DOUBLES_EQUAL(0.2, m.peak_velocity(), 1e-12);
}

TEST(References, CircleOfFig8HasTheRightRadiusAndSmoothStart) {
  const AxisReferenceLimits lx = stage_limits_x();
  AxisReferenceLimits ly = lx;
  ly.travel_min_pico = -17 * kMm;  // 35 mm in y
  ly.travel_max_pico = 17 * kMm;
  CircleReference c;
  CHECK(c.plan(0, 0, 0.006, 0.02, 2.0, 0.1, 20.0, kFs, lx, ly) == ReferenceError::kOk);
  double max_r_err = 0, max_v = 0;
  AxisReference x, y;
  for (std::int64_t k = 0; k <= c.total_ticks(); ++k) {
    c.sample(k, &x, &y);
    const double dx = static_cast<double>(x.position_pico + 3 * kMm / 1) * 1e-12;  // centre at (-3 mm, 0)
    const double dy = static_cast<double>(y.position_pico) * 1e-12;
    max_r_err = std::fmax(max_r_err, std::fabs(std::hypot(dx, dy) - 0.003));
    max_v = std::fmax(max_v, std::hypot(static_cast<double>(x.velocity), static_cast<double>(y.velocity)));
  }
  std::printf("\n[circle 6 mm] %ld ticks, max radius error %.3g m, max speed %.5f m/s",
              static_cast<long>(c.total_ticks()), max_r_err, max_v);
  CHECK(max_r_err < 2e-12);  // pm rounding
  CHECK(max_v <= 0.02 * (1 + 1e-6));
  // Smooth start and stop at the start point, after exactly 2 turns.
  c.sample(0, &x, &y);
  CHECK(x.position_pico == 0 && y.position_pico == 0);
  DOUBLES_EQUAL(0.0, static_cast<double>(x.velocity), 0.0);
  DOUBLES_EQUAL(0.0, static_cast<double>(y.acceleration), 0.0);
  c.sample(c.total_ticks(), &x, &y);
  CHECK(std::llabs(x.position_pico) <= 1 && std::llabs(y.position_pico) <= 1);
  // Half-way through the first turn at constant speed, the acceleration is
  // centripetal: v^2/r towards the centre.
  // Rejections: too fast, too much centripetal acceleration, outside travel.
  CHECK(c.plan(0, 0, 0.006, 0.5, 1.0, 0.1, 20.0, kFs, lx, ly) == ReferenceError::kVelocityLimit);
  CHECK(c.plan(0, 0, 0.006, 0.1, 1.0, 0.1, 20.0, kFs, lx, ly) == ReferenceError::kAccelerationLimit);
  CHECK(c.plan(0, 16 * kMm, 0.006, 0.02, 1.0, 0.1, 20.0, kFs, lx, ly) == ReferenceError::kOutsideTravel);
  CHECK(c.plan(0, 0, -0.006, 0.02, 1.0, 0.1, 20.0, kFs, lx, ly) == ReferenceError::kBadParameter);
}

TEST(References, SinusoidOfPaper002) {
  AxisReferenceLimits lim = stage_limits_x();
  SinusoidReference s;
  // w0 = 1.5 pi rad/s, 30 um amplitude, 3 cycles, starting at rest.
  const double f = 0.75;
  CHECK(s.plan(kMm, 30e-6, f, 3.0, kFs, lim) == ReferenceError::kOk);
  const ProfileStats st = scan(s, 4 * 2500, 0.0);
  const double w = 2 * kPi * f;
  CHECK(st.max_v <= 30e-6 * w * (1 + 1e-6) + 1e-8);
  CHECK(st.max_a <= 30e-6 * w * w * (1 + 1e-3) + 1e-4);
  CHECK(s.sample(0).position_pico == kMm);
  DOUBLES_EQUAL(0.0, static_cast<double>(s.sample(0).velocity), 1e-12);
  // p0 + A (1 - cos w t) at every tick, to the pm.
  for (std::int64_t k = 0; k < 3 * 3333; k += 7) {
    const double exact = 1e9 + 30e6 * (1.0 - std::cos(w * static_cast<double>(k) * kT));  // pm
    CHECK(std::fabs(static_cast<double>(s.sample(k).position_pico) - exact) <= 1.0);
  }
  CHECK(s.done(4 * 2500));
  CHECK(s.sample(4 * 2500).position_pico == kMm);
  // Rejections.
  CHECK(s.plan(kMm, 1e-3, 100.0, 1.0, kFs, lim) == ReferenceError::kVelocityLimit);
  lim.max_velocity = 10.0;
  CHECK(s.plan(kMm, 1e-3, 100.0, 1.0, kFs, lim) == ReferenceError::kAccelerationLimit);
  CHECK(s.plan(27 * kMm + 999 * 1000000, 30e-6, f, 1.0, kFs, stage_limits_x()) == ReferenceError::kOutsideTravel);
  CHECK(s.plan(kMm, 30e-6, 2000.0, 1.0, kFs, stage_limits_x()) == ReferenceError::kBadParameter);
  // A finite sinusoid ends at rest: whole half cycles only (the reference
  // holds its last sample, so a moving end would be a velocity step).
  CHECK(s.plan(kMm, 30e-6, f, 0.25, kFs, stage_limits_x()) == ReferenceError::kBadParameter);
  CHECK(s.plan(kMm, 30e-6, f, 1.2, kFs, stage_limits_x()) == ReferenceError::kBadParameter);
  CHECK(s.plan(kMm, 30e-6, f, 0.5, kFs, stage_limits_x()) == ReferenceError::kOk);
  const std::int64_t half = 1667;  // ceil(0.5 / 0.75 Hz x 2500 Hz)
  CHECK(!s.done(half - 1));
  CHECK(s.done(half));
  // p0 + 2 A, at rest (the last tick lies 0.13 ms past the half cycle: 6 pm short of it)
  CHECK(std::llabs(s.sample(half).position_pico - (kMm + 60000000)) <= 100);
  DOUBLES_EQUAL(0.0, static_cast<double>(s.sample(half).velocity), 1e-12);
  // The shortest: half a cycle just below fs / 2 lasts two ticks, never 0 ("until kHold").
  CHECK(s.plan(kMm, 1e-9, 1249.0, 0.5, kFs, stage_limits_x()) == ReferenceError::kOk);
  CHECK(!s.done(1));
  CHECK(s.done(2));
}

TEST(References, StepAndRejectedMoves) {
  const AxisReferenceLimits lim = stage_limits_x();
  StepReference st;
  CHECK(st.plan(kMm, 8000000, lim) == ReferenceError::kOk);  // +8 um
  CHECK(st.sample(0).position_pico == kMm + 8000000);
  CHECK(st.sample(0).step_pico == 8000000);
  CHECK(st.sample(1).step_pico == 0);
  CHECK(st.sample(-1).position_pico == kMm);
  CHECK(st.plan(kMm, 200000000, lim) == ReferenceError::kStepTooLarge);
  CHECK(st.plan(28 * kMm, 1000000, lim) == ReferenceError::kOutsideTravel);
  CHECK(st.plan(kMm, INT64_MIN, lim) == ReferenceError::kStepTooLarge);
  MoveReference m;
  CHECK(m.plan_trapezoid(0, 30 * kMm, 0.2, 0.6, kFs, lim) == ReferenceError::kOutsideTravel);
  CHECK(m.plan_trapezoid(0, 10 * kMm, 0.5, 0.6, kFs, lim) == ReferenceError::kVelocityLimit);
  CHECK(m.plan_trapezoid(0, 10 * kMm, 0.2, 2.0, kFs, lim) == ReferenceError::kAccelerationLimit);
  CHECK(m.plan_trapezoid(0, 10 * kMm, NAN, 0.6, kFs, lim) == ReferenceError::kNonFinite);
  CHECK(m.plan_trapezoid(0, 10 * kMm, 0.0, 0.6, kFs, lim) == ReferenceError::kBadParameter);
  CHECK(m.plan_scurve(0, 10 * kMm, 0.2, 0.6, 500.0, kFs, lim) == ReferenceError::kJerkLimit);
  CHECK(m.plan_trapezoid(-29 * kMm, 0, 0.2, 0.6, kFs, lim) == ReferenceError::kOutsideTravel);
}

// kHold's stop never ends beyond where the profile it stops could have
// stopped: a move to the travel's end at the axis' max acceleration
// (trapezoid and S-curve), held on any tick of its deceleration, stays at or
// before its target (and so inside travel), and within the axis' max
// acceleration. The stop used to take whole ticks at a deceleration rounded
// down to fit them, which covers up to half a tick of motion more: 8.7 um
// beyond travel for the trapezoid here.
TEST(References, AStopNeverEndsBeyondTheTargetOfTheMoveItStops) {
  const AxisReferenceLimits l = stage_limits_x();
  for (int shape = 0; shape < 2; ++shape) {
    MoveReference m;
    const ReferenceError e =
        shape == 0 ? m.plan_trapezoid(0, l.travel_max_pico, l.max_velocity, l.max_acceleration, kFs, l)
                   : m.plan_scurve(0, l.travel_max_pico, l.max_velocity, l.max_acceleration, l.max_jerk, kFs, l);
    CHECK(e == ReferenceError::kOk);
    std::int64_t worst_pm = INT64_MIN;
    double worst_a = 0.0;
    int held = 0;
    for (std::int64_t k = 1; k < m.total_ticks(); ++k) {
      const AxisReference r = m.sample(k);
      if (!(r.acceleration < 0.0f)) continue;  // held while decelerating
      StopReference s;
      CHECK(s.plan(r.position_pico, static_cast<double>(r.velocity), kFs, l) == ReferenceError::kOk);
      std::int64_t prev = r.position_pico, prev2 = m.sample(k - 1).position_pico;
      for (std::int64_t t = 1; t <= s.total_ticks() + 2; ++t) {
        const std::int64_t p = s.sample(t).position_pico;
        worst_pm = p > worst_pm ? p : worst_pm;
        if (t >= 2) worst_a = std::fmax(worst_a, std::fabs(static_cast<double>(p - 2 * prev + prev2)) * 1e-12 / (kT * kT));
        prev2 = prev;
        prev = p;
      }
      ++held;
    }
    CHECK(held > 100);
    std::printf("\n  %s: stop from %d decelerating ticks: furthest %.3f um past the target, max |a| %.4f m/s^2\n",
                shape == 0 ? "trapezoid" : "S-curve", held, static_cast<double>(worst_pm - l.travel_max_pico) * 1e-6,
                worst_a);
    CHECK(worst_pm <= l.travel_max_pico);
    CHECK(worst_a <= l.max_acceleration * 1.0001);
  }
}
