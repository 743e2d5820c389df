// The kernel's float feedback linearization (12) and its force-law tables
// against the host's double reference (host-tools/control_design).
#include <cmath>
#include <cstdio>

#include "maglev/control_design/paper002_controller.hpp"
#include "maglev/control_design/pmlsm_kernel_config.hpp"
#include "maglev/pmlsm_plant/force_law.hpp"
#include "maglev/pmlsm_stage/feedback_linearization.hpp"
#include "maglev/profile/profile_text.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

namespace cd = maglev::control_design;
namespace ps = maglev::pmlsm_stage;
namespace pp = maglev::pmlsm_plant;

namespace {
cd::PmlsmDesign Design(bool* ok) {
  const auto parsed = maglev::profile::find_profile("fmp2009-pmlsm", MAGLEV_PROFILE_DIR);
  cd::PmlsmDesign d;
  std::string why;
  *ok = parsed.ok() && cd::BuildPmlsmKernelConfig(parsed.profile, &d, &why);
  return d;
}
}  // namespace

TEST_GROUP(FeedbackLinearization) {
  bool ok = false;
  cd::PmlsmDesign d = Design(&ok);
  pp::StageParams p;  // paper 002's values: the profile must give the same stage
  pp::ForceConstants k = pp::ComputeForceConstants(p.motor);
};

TEST(FeedbackLinearization, TheProfileGivesThePlantsPaperParameters) {
  const auto parsed = maglev::profile::find_profile("fmp2009-pmlsm", MAGLEV_PROFILE_DIR);
  CHECK_TRUE(parsed.ok());
  cd::PmlsmStage s;
  std::string why;
  CHECK_TRUE(cd::PmlsmStageFromProfile(parsed.profile, &s, &why));
  const pp::ForceConstants kp = pp::ComputeForceConstants(s.stage.motor);
  DOUBLES_EQUAL(k.Kv1, kp.Kv1, 1e-9 * k.Kv1);
  DOUBLES_EQUAL(k.Kv2, kp.Kv2, 1e-9 * k.Kv2);
  DOUBLES_EQUAL(k.Kv3, kp.Kv3, 1e-9 * k.Kv3);
  DOUBLES_EQUAL(k.Kh, kp.Kh, 1e-9 * k.Kh);
  DOUBLES_EQUAL(p.mass_x_kg, s.stage.mass_x_kg, 0.0);
  DOUBLES_EQUAL(p.mass_z_kg, s.stage.mass_z_kg, 0.0);
  DOUBLES_EQUAL(p.mass_y_kg, s.stage.mass_y_kg, 0.0);
  DOUBLES_EQUAL(p.guide_torsion_phi_per_s2, s.stage.guide_torsion_phi_per_s2, 0.0);
}

// Linear interpolation at 0.09 mm spacing: below 1e-5 relative (plus float).
TEST(FeedbackLinearization, TheGapTablesInterpolateTheForceLawWithin1e5) {
  CHECK_TRUE(ok);
  double worst = 0.0;
  for (double g = 18e-3; g <= 31e-3; g += 0.0137e-3) {
    const ps::GapTerms t = ps::LookUpGapTerms(d.config.force, static_cast<float>(g));
    const double exact[4] = {k.Kv1 * pp::Lv1(p.motor, g), k.Kv2 * pp::Lv2(p.motor, g),
                             k.Kv3 * pp::Lv3(p.motor, g), k.Kh * pp::Lh(p.motor, g)};
    const double got[4] = {static_cast<double>(t.attraction_N), static_cast<double>(t.direct_N_per_A),
                           static_cast<double>(t.quadratic_N_per_A2), static_cast<double>(t.thrust_N_per_A)};
    for (int i = 0; i < 4; ++i) worst = std::fmax(worst, std::fabs(got[i] - exact[i]) / std::fabs(exact[i]));
  }
  CHECK_TRUE(worst < 1e-5);
  CHECK_TRUE(worst > 0.0);  // the tables are not the functions themselves
}

// The float kernel's (12) + (8) equals the host's double reference.
TEST(FeedbackLinearization, MatchesTheHostReferenceOverTheOperatingRange) {
  CHECK_TRUE(ok);
  double worst = 0.0;
  int cases = 0;
  for (double gap : {20e-3, 23.3e-3, 27e-3, 30e-3}) {
    for (double tilt : {-2e-3, 0.0, 2.5e-3}) {
      for (double wy : {-3.0, 0.0, 2.0}) {
        const std::array<double, 5> y{gap, 10e-3, -5e-3, tilt * 0.5, tilt * 3.0};
        const std::array<double, 5> w{wy, 0.7, -0.4, 5.0 * wy, -3.0};
        const cd::FeedbackLinearization ref = cd::FeedbackLinearize(p, k, y, w, 7.0, true);
        float yf[5], wf[5];
        for (int a = 0; a < 5; ++a) {
          yf[a] = static_cast<float>(y[static_cast<std::size_t>(a)]);
          wf[a] = static_cast<float>(w[static_cast<std::size_t>(a)]);
        }
        const ps::LinearizedCurrents got = ps::FeedbackLinearize(d.config, yf, wf, true);
        for (int m = 0; m < 4; ++m) {
          const auto& r = ref.currents[static_cast<std::size_t>(m)];
          worst = std::fmax(worst, std::fabs(static_cast<double>(got.i_d_A[m]) - r.d_A) / (std::fabs(r.d_A) + 0.1));
          worst = std::fmax(worst, std::fabs(static_cast<double>(got.i_q_A[m]) - r.q_A) / (std::fabs(r.q_A) + 0.1));
        }
        ++cases;
      }
    }
  }
  LONGS_EQUAL(36, cases);
  std::printf("\nfloat (12) vs double reference: worst %.3g\n", worst);
  CHECK_TRUE(worst < 1e-4);
}

// Ours: with the i_d^2 term inverted, each motor's full vertical force (2)
// is the force (11)'s linear model asked for.
TEST(FeedbackLinearization, TheExactInverseDeliversTheLinearModelsForce) {
  CHECK_TRUE(ok);
  ps::PmlsmKernelConfig c = d.config;
  const float y[5] = {22e-3f, 0.0f, 0.0f, 1e-3f, -4e-3f};
  const float w[5] = {1.5f, 0.2f, 0.1f, 2.0f, -1.0f};
  c.exact_vertical_inverse = false;
  const ps::LinearizedCurrents lin = ps::FeedbackLinearize(c, y, w, true);
  c.exact_vertical_inverse = true;
  const ps::LinearizedCurrents ex = ps::FeedbackLinearize(c, y, w, true);
  float g[4];
  ps::AirGaps(c, y, g);
  for (int m = 0; m < 4; ++m) {
    const double gm = static_cast<double>(g[m]);
    const double id = static_cast<double>(ex.i_d_A[m]), iq = static_cast<double>(ex.i_q_A[m]);
    const double full = pp::ComputeMotorForce(p.motor, k, gm, id, iq).vertical_N;
    const double wanted = pp::ComputeMotorForce(p.motor, k, gm, 0.0, iq).vertical_N +
                          k.Kv2 * pp::Lv2(p.motor, gm) * static_cast<double>(lin.i_d_A[m]);
    DOUBLES_EQUAL(wanted, full, 1e-3 * (1.0 + std::fabs(wanted)));
    CHECK_TRUE(std::fabs(id - static_cast<double>(lin.i_d_A[m])) > 1e-4);  // it did change the current
  }
}
