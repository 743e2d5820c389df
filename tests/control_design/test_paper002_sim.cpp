// Closed loop at 1 kHz (plant + feedback linearization + IMR + LQR gains +
// anti-windup): the 7 mm air-gap step of Fig. 4 against Table III's
// specifications. The measured numbers are printed; docs/PAPER-002.md has them.
#include <cstdio>

#include "maglev/control_design/paper002_sim.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::control_design;

TEST_GROUP(Paper002Sim){};

namespace {
void CheckTableIII(double start_m, double step_m) {
  GapStepScenario s;
  s.gap_start_m = start_m;
  s.gap_step_m = step_m;
  const GapStepResult r = RunGapStep(s, MakePaperConfig());
  std::printf("gap %.0f -> %.0f mm: overshoot %.2f %% (paper 14.3 %%), t_s %.3f s, t_enc %.3f s, peak i_d %.2f A\n",
              start_m * 1e3, (start_m + step_m) * 1e3, 100 * r.overshoot_fraction, r.settling_time_s,
              r.encoder_time_s, r.peak_direct_current_A);
  CHECK(r.overshoot_fraction < 0.30);  // Table III: %OS < 30 %
  CHECK(r.settling_time_s < 3.0);      // t_s < 3 s to 0.1 mm
  CHECK(r.encoder_time_s < 10.0);      // t_enc < 10 s to 10 um
  CHECK_FALSE(r.hit_stop);             // never touched the 18 / 31 mm stops
  CHECK(r.final_error_m < 10e-6);
  // The step drives the amplifiers into their 7 A limit (derivative kick).
  CHECK(r.saturated_ticks > 0);
  DOUBLES_EQUAL(7.0, r.peak_direct_current_A, 1e-9);
}
}  // namespace

TEST(Paper002Sim, SevenMillimetreStepUp) { CheckTableIII(20e-3, 7e-3); }
TEST(Paper002Sim, SevenMillimetreStepDown) { CheckTableIII(30e-3, -7e-3); }

namespace {
GapStepResult ThetaStep(double start_rad, double step_rad) {
  AxisStepScenario s;  // gap held at 25 mm by the y loop, as in Fig. 5
  s.axis = Axis::kTheta;
  s.start = {25e-3, 0, 0, 0, start_rad};
  s.step = step_rad;
  const GapStepResult r = RunAxisStep(s, MakePaperConfig());
  std::printf("theta %.0f -> %.0f mrad: overshoot %.2f %% (paper 22 %% on 10 mrad), t_s %.3f s, t_enc %.3f s\n",
              start_rad * 1e3, (start_rad + step_rad) * 1e3, 100 * r.overshoot_fraction, r.settling_time_s,
              r.encoder_time_s);
  CHECK_FALSE(r.hit_stop);
  CHECK(r.final_error_m < 20e-6);
  return r;
}
}  // namespace

TEST(Paper002Sim, FiveMilliradianThetaStepMeetsTableIII) {
  // Table III, Z-axis rotation, 5 mrad steps: %OS < 30 %, t_s < 3 s, t_enc < 10 s.
  const GapStepResult r = ThetaStep(0.0, 5e-3);
  CHECK(r.overshoot_fraction < 0.30);
  CHECK(r.settling_time_s < 3.0);
  CHECK(r.encoder_time_s < 10.0);
}

TEST(Paper002Sim, TenMilliradianThetaStepMeetsTableIII) {
  // Table III, 10 mrad steps: %OS < 30 %, t_s 3 to 5 s on the rig (here at
  // most 5 s is asserted), t_enc < 10 s.
  const GapStepResult r = ThetaStep(-5e-3, 10e-3);
  CHECK(r.overshoot_fraction < 0.30);
  CHECK(r.settling_time_s < 5.0);
  CHECK(r.encoder_time_s < 10.0);
}

namespace {
GapStepResult HorizontalStep(Axis axis, double E) {
  AxisStepScenario s;  // -15 -> +15 mm: the 30 mm step of Section IV-A (1)
  s.axis = axis;
  s.start = {25e-3, 0, 0, 0, 0};
  s.start[static_cast<std::size_t>(axis)] = -15e-3;
  s.step = 30e-3;
  s.rotation_loops_enabled = false;
  Paper002ControllerConfig c = MakePaperConfig();
  c.E_x = {E, E, E};
  c.E_z = {E, E, E};
  const GapStepResult r = RunAxisStep(s, c);
  std::printf("%s -15 -> 15 mm, E = %.0e: overshoot %.2f %%, t_s %.3f s, t_enc %.3f s\n", AxisName(axis), E,
              100 * r.overshoot_fraction, r.settling_time_s, r.encoder_time_s);
  return r;
}
}  // namespace

TEST(Paper002Sim, ThirtyMillimetreHorizontalStepsMeetTableIIIWithAntiWindup) {
  for (Axis a : {Axis::kX, Axis::kZ}) {
    const GapStepResult with = HorizontalStep(a, 7e-5);  // the paper's E_x = E_z
    const GapStepResult without = HorizontalStep(a, 0.0);
    CHECK(with.overshoot_fraction < 0.30);
    CHECK(with.settling_time_s < 3.0);
    CHECK(with.encoder_time_s < 10.0);
    CHECK(with.final_error_m < 10e-6);
    // u_x / u_z do hit sat_7, and (17) does not make the transient worse.
    CHECK(with.saturated_ticks > 0);
    CHECK(with.overshoot_fraction <= without.overshoot_fraction);
    CHECK(with.settling_time_s <= without.settling_time_s);
  }
}

TEST(Paper002Sim, SinusoidalTrackingExactWhenTheModelIsExact) {
  // Internal model principle: with the i_d^2 terms that (11) drops removed
  // from the plant (K_v3 = 0 in plant and controller), the 3-DOF ellipse at
  // omega_0 is tracked to well below one encoder count.
  Paper002ControllerConfig c = MakePaperConfig();
  c.model.motor.kv3_scale = 0.0;
  for (bool four : {false, true}) {
    TrackingScenario s;
    s.four_dof = four;
    s.quantize_encoders = false;
    const TrackingResult r = RunTracking(s, c);
    std::printf("%s ellipse, exact model: mean |e| y %.3f um, x %.3f um, z %.3f um, theta %.2f urad\n",
                four ? "4-DOF" : "3-DOF", r.mean_abs_error[0] * 1e6, r.mean_abs_error[1] * 1e6,
                r.mean_abs_error[2] * 1e6, r.mean_abs_error[4] * 1e6);
    for (std::size_t a = 0; a < 3; ++a) CHECK(r.mean_abs_error[a] < 2e-6);
    CHECK(r.mean_abs_error[4] < 20e-6);  // below one 20 urad count
    CHECK_FALSE(r.hit_stop);
  }
}

TEST(Paper002Sim, SinusoidalTrackingOnTheBench) {
  // The bench plant (with the dropped terms, quantized encoders). Paper:
  // 3-DOF y 33.04, x 78.33, z 68.25 um; 4-DOF y 47.03, x 77.98, z 76.85 um,
  // theta 123.9 urad. Measured numbers go to docs/PAPER-002.md; asserted here:
  // the horizontal axes (exact in (11)) stay within one encoder count, and
  // nothing touches a stop.
  for (bool four : {false, true}) {
    TrackingScenario s;
    s.four_dof = four;
    const TrackingResult r = RunTracking(s, MakePaperConfig());
    std::printf("%s ellipse, bench: mean |e| y %.2f um, x %.2f um, z %.2f um, theta %.1f urad\n",
                four ? "4-DOF" : "3-DOF", r.mean_abs_error[0] * 1e6, r.mean_abs_error[1] * 1e6,
                r.mean_abs_error[2] * 1e6, r.mean_abs_error[4] * 1e6);
    CHECK(r.mean_abs_error[1] < 10e-6);
    CHECK(r.mean_abs_error[2] < 10e-6);
    CHECK(r.mean_abs_error[0] < 0.5e-3);  // y: bounded by the dropped terms, far below the 5 mm amplitude
    CHECK_FALSE(r.hit_stop);
  }
}
