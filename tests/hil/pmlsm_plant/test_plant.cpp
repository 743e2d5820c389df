// Rigid-body model (5)-(7) with guides, RK4, encoders; and the linearization
// of the plant after feedback linearization (12), which must be (13).
#include <cmath>

#include "maglev/control_design/paper002_controller.hpp"
#include "maglev/pmlsm_plant/plant.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::pmlsm_plant;

namespace {
State Hover(double gap_m) {
  State x{};
  x[0] = gap_m;
  return x;
}
MotorCurrents HoverCurrents(const StageParams& p, const ForceConstants& k, double gap_m) {
  double i = 0;
  HoverDirectCurrent_A(p.motor, k, gap_m, p.mass_y_kg * p.gravity_G_m_per_s2 / 4.0, &i);
  return {DqCurrents{i, 0}, DqCurrents{i, 0}, DqCurrents{i, 0}, DqCurrents{i, 0}};
}
}  // namespace

TEST_GROUP(Plant) {
  StageParams p;
  ForceConstants k = ComputeForceConstants(p.motor);
};

TEST(Plant, GapsFollowEquation5) {
  State x = Hover(25e-3);
  x[6] = 2e-3;
  x[8] = -5e-3;
  const auto g = AirGaps_m(p, x);
  DOUBLES_EQUAL(25e-3 - 0.397 * std::sin(2e-3), g[0], 1e-15);
  DOUBLES_EQUAL(25e-3 + 0.397 * std::sin(-5e-3), g[1], 1e-15);
  DOUBLES_EQUAL(25e-3 + 0.397 * std::sin(2e-3), g[2], 1e-15);
  DOUBLES_EQUAL(25e-3 - 0.397 * std::sin(-5e-3), g[3], 1e-15);
}

TEST(Plant, HoverIsAnEquilibrium) {
  const State dx = Derivative(p, k, Hover(25e-3), HoverCurrents(p, k, 25e-3));
  for (double d : dx) DOUBLES_EQUAL(0.0, d, 1e-12);
}

TEST(Plant, VerticalOpenLoopIsUnstableRotationHeldByGuides) {
  // d(gap'')/d(gap) at hover: the PM attraction gives a positive (unstable) pole.
  const double h = 1e-7;
  const auto i = HoverCurrents(p, k, 25e-3);
  const double s = (Derivative(p, k, Hover(25e-3 + h), i)[1] - Derivative(p, k, Hover(25e-3 - h), i)[1]) / (2 * h);
  DOUBLES_EQUAL(37.6, std::sqrt(s), 0.5);  // [D] in the notes: +37.6 rad/s at 25 mm
  // Rotation stiffness: guides beat the magnetic negative stiffness (ours).
  State xr = Hover(25e-3);
  xr[8] = h;
  CHECK(Derivative(p, k, xr, i)[9] / h < 0.0);
  xr[8] = 0;
  xr[6] = h;
  CHECK(Derivative(p, k, xr, i)[7] / h < 0.0);
}

TEST(Plant, Rk4MatchesFreeFallAndHorizontalForce) {
  Plant plant(p);
  plant.Reset(Hover(25e-3));
  // i_q on motors 2, 4 only: pure X force, no vertical change beyond K_v3 i_q^2.
  MotorCurrents cmd = HoverCurrents(p, k, 25e-3);
  cmd[1].q_A = cmd[3].q_A = 1.0;
  plant.Step(cmd, 1e-3);
  const double ax = -2.0 * k.Kh * Lh(p.motor, 25e-3) / p.mass_x_kg;
  DOUBLES_EQUAL(0.5 * ax * 1e-6, plant.state()[2], 1e-3 * std::fabs(0.5 * ax * 1e-6));
  DOUBLES_EQUAL(ax * 1e-3, plant.state()[3], 1e-6 * std::fabs(ax));
}

TEST(Plant, StopsClampTheGap) {
  Plant plant(p);
  plant.Reset(Hover(20e-3));
  MotorCurrents none{};
  for (int n = 0; n < 2000; ++n) plant.Step(none, 1e-3);  // no current: PM pulls it up to the stop
  DOUBLES_EQUAL(18e-3, plant.state()[0], 1e-15);
  DOUBLES_EQUAL(0.0, plant.state()[1], 0.0);
}

TEST(Plant, EncodersQuantize) {
  State x = Hover(25.0049e-3);
  x[2] = -1.23456e-3;
  x[8] = 31e-6;
  const Measurement m = MeasureEncoders({}, x);
  DOUBLES_EQUAL(25.00e-3, m.y[0], 1e-12);
  DOUBLES_EQUAL(-1.23e-3, m.y[1], 1e-12);
  DOUBLES_EQUAL(40e-6, m.y[4], 1e-12);
}

TEST(Plant, FeedbackLinearizationInvertsNominalModel) {
  // (12) on (11): the nominal accelerations a1 + a3 v_y + a2 v_phi + a7 v_theta, ...
  // equal w exactly (13).
  using namespace maglev::control_design;
  State x = Hover(22e-3);
  x[6] = 1e-3;
  x[8] = -5e-3;
  const std::array<double, 5> y{x[0], x[2], x[4], x[6], x[8]};
  const std::array<double, 5> w{0.7, -0.3, 0.2, -0.4, 0.9};
  const FeedbackLinearization f = FeedbackLinearize(p, k, y, w, 7.0, true);
  const double vy = f.currents[0].d_A + f.currents[2].d_A;
  const double vphi = f.currents[0].d_A - f.currents[2].d_A;
  const double vth = f.currents[3].d_A - f.currents[1].d_A;
  const NominalTerms t = EvaluateNominalModel(p, k, y[0], y[3], y[4], f.u_x_A, f.u_z_A);
  DOUBLES_EQUAL(w[0], t.a1 + t.a3 * vy + t.a2 * vphi + t.a7 * vth, 1e-9);
  DOUBLES_EQUAL(w[1], t.h_x * f.u_x_A, 1e-12);
  DOUBLES_EQUAL(w[2], t.h_z * f.u_z_A, 1e-12);
  DOUBLES_EQUAL(w[3], t.b1 + t.b3 * vy + t.b2 * vphi, 1e-9);
  DOUBLES_EQUAL(w[4], t.c1 + t.c3 * vy + t.c2 * vth, 1e-9);
}

TEST(Plant, FullPlantDiffersFromThirteenOnlyByNeglectedTerms) {
  // On the full plant (6)-(7) the residual x'' - w is exactly the quadratic
  // i_d^2 terms that (11) drops (a4..a9, b4..b6, c4..c6), computed here
  // independently; the horizontal axes are exact.
  using namespace maglev::control_design;
  for (double gap : {20e-3, 25e-3, 30e-3}) {
    State x = Hover(gap);
    x[6] = 1e-3;
    x[8] = -5e-3;
    const std::array<double, 5> y{x[0], x[2], x[4], x[6], x[8]};
    const std::array<double, 5> w{0.5, 0.2, -0.1, 0.3, -0.2};
    const FeedbackLinearization f = FeedbackLinearize(p, k, y, w, 7.0, true);
    const State d = Derivative(p, k, x, f.currents);
    const auto g = AirGaps_m(p, x);
    std::array<double, 4> q{};
    for (std::size_t m = 0; m < 4; ++m)
      q[m] = k.Kv3 * Lv3(p.motor, g[m]) * f.currents[m].d_A * f.currents[m].d_A;
    const double r = p.radius_to_movers_r_m;
    DOUBLES_EQUAL(w[0] - (q[0] + q[1] + q[2] + q[3]) / p.mass_y_kg, d[1], 1e-9);
    DOUBLES_EQUAL(w[1], d[3], 1e-9);
    DOUBLES_EQUAL(w[2], d[5], 1e-9);
    DOUBLES_EQUAL(w[3] + r * (q[0] - q[2]) / p.inertia_x_kg_m2, d[7], 1e-9);
    DOUBLES_EQUAL(w[4] + r * (q[3] - q[1]) / p.inertia_z_kg_m2, d[9], 1e-9);
  }
}

TEST(Plant, LinearizationAtNominalGapIsThirteen) {
  // Jacobian dx''/dw of the full plant under (12), level at the nominal 25 mm
  // gap: decoupled, unit gain up to the neglected 2 a6 v_y / a3 (< 10 %).
  using namespace maglev::control_design;
  const State x = Hover(25e-3);
  const std::array<double, 5> y{x[0], x[2], x[4], x[6], x[8]};
  const std::array<std::size_t, 5> acc{1, 3, 5, 7, 9};
  for (std::size_t j = 0; j < 5; ++j) {
    std::array<double, 5> wp{}, wm{};
    wp[j] = 1e-3;
    wm[j] = -1e-3;
    const State dp = Derivative(p, k, x, FeedbackLinearize(p, k, y, wp, 7.0, true).currents);
    const State dm = Derivative(p, k, x, FeedbackLinearize(p, k, y, wm, 7.0, true).currents);
    for (std::size_t a = 0; a < 5; ++a) {
      const double gain = (dp[acc[a]] - dm[acc[a]]) / 2e-3;
      DOUBLES_EQUAL(a == j ? 1.0 : 0.0, gain, a == j ? 0.1 : 1e-6);
    }
  }
}
