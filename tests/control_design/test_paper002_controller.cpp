// Reference controller: set-point validation, rest at the equilibrium,
// anti-windup on X.
#include <cmath>

#include "maglev/control_design/paper002_controller.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::control_design;

TEST_GROUP(Paper002Controller){};

TEST(Paper002Controller, GapReferenceBelow18mmIsRejectedAndKept) {
  Paper002Controller c(MakePaperConfig());
  CHECK(c.SetReference({22e-3, 0, 0, 0, 0}) == ReferenceError::kOk);
  CHECK(c.SetReference({17.9e-3, 0, 0, 0, 0}) == ReferenceError::kGapBelowMinimum);
  DOUBLES_EQUAL(22e-3, c.reference()[0], 0.0);
  CHECK(c.SetReference({31.5e-3, 0, 0, 0, 0}) == ReferenceError::kGapAboveMaximum);
  CHECK(c.SetReference({25e-3, 0.06, 0, 0, 0}) == ReferenceError::kHorizontalOutOfRange);
  CHECK(c.SetReference({25e-3, 0, 0, 0, 0.02}) == ReferenceError::kRotationOutOfRange);
  CHECK(c.SetReference({NAN, 0, 0, 0, 0}) == ReferenceError::kGapBelowMinimum);
  DOUBLES_EQUAL(22e-3, c.reference()[0], 0.0);
}

TEST(Paper002Controller, OperatingRangeOfSectionIVA) {
  CHECK(InPaperOperatingRange({20e-3, 30e-3, -30e-3, 0, 10e-3}));
  CHECK_FALSE(InPaperOperatingRange({19e-3, 0, 0, 0, 0}));    // valid, outside (1)
  CHECK_FALSE(InPaperOperatingRange({25e-3, 0, 0, 0, 12e-3}));
}

TEST(Paper002Controller, AtEquilibriumCommandsHoverCurrent) {
  Paper002ControllerConfig cfg = MakePaperConfig();
  Paper002Controller c(cfg);
  c.SetReference({25e-3, 0, 0, 0, 0});
  const auto k = maglev::pmlsm_plant::ComputeForceConstants(cfg.model.motor);
  double hover = 0;
  maglev::pmlsm_plant::HoverDirectCurrent_A(cfg.model.motor, k, 25e-3, cfg.model.mass_y_kg * 9.81 / 4.0, &hover);
  const auto cmd = c.Step({25e-3, 0, 0, 0, 0});
  // (11) drops the i_d^2 term, so v_y/2 is the linear estimate: within 10 %.
  for (const auto& m : cmd) {
    DOUBLES_EQUAL(hover, m.d_A, 0.1 * hover);
    DOUBLES_EQUAL(0.0, m.q_A, 0.0);
  }
}

TEST(Paper002Controller, AntiWindupActsOnlyWhenSaturated) {
  // A 30 mm X step saturates u_x; with E_x the internal model integrates less.
  Paper002ControllerConfig with = MakePaperConfig();
  Paper002ControllerConfig without = with;
  without.E_x = {0, 0, 0};
  Paper002Controller a(with), b(without);
  a.Step({25e-3, 0, 0, 0, 0});  // at rest first, so the step is seen by the derivative filter
  b.Step({25e-3, 0, 0, 0, 0});
  a.SetReference({25e-3, 30e-3, 0, 0, 0});
  b.SetReference({25e-3, 30e-3, 0, 0, 0});
  bool saturated = false;
  for (int n = 0; n < 50; ++n) {
    a.Step({25e-3, 0, 0, 0, 0});
    b.Step({25e-3, 0, 0, 0, 0});
    saturated = saturated || std::fabs(a.u_x_A()) >= 7.0;
  }
  CHECK(saturated);
  // The windup (positive feedback through E * (sat(u) - u)) changes w_x.
  CHECK(std::fabs(a.w()[1] - b.w()[1]) > 0.0);
}

TEST(Paper002Controller, AntiWindupIdleBelowTheLimit) {
  // A 0.1 mm X step never reaches 7 A: E_x must change nothing.
  Paper002ControllerConfig with = MakePaperConfig();
  Paper002ControllerConfig without = with;
  without.E_x = {0, 0, 0};
  Paper002Controller a(with), b(without);
  a.Step({25e-3, 0, 0, 0, 0});
  b.Step({25e-3, 0, 0, 0, 0});
  a.SetReference({25e-3, 0.1e-3, 0, 0, 0});
  b.SetReference({25e-3, 0.1e-3, 0, 0, 0});
  for (int n = 0; n < 50; ++n) {
    a.Step({25e-3, 0, 0, 0, 0});
    b.Step({25e-3, 0, 0, 0, 0});
    CHECK(std::fabs(a.u_x_A()) < 7.0);
    DOUBLES_EQUAL(b.w()[1], a.w()[1], 0.0);
  }
}
