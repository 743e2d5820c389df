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
