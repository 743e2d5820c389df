#pragma once
// Host reference implementation of paper 002's controller, to be ported to the
// firmware kernel: input transformation (8), feedback linearization (12) on
// the simplified model (11), five internal-model regulators (14)-(16) with
// LQR gains, anti-windup (17) on X and Z, derivative estimates by first-order
// linear filters, run at a fixed period (1 kHz). Double precision, host only.
#include <array>

#include "maglev/control_design/imr_design.hpp"
#include "maglev/pmlsm_plant/params.hpp"
#include "maglev/pmlsm_plant/plant.hpp"

namespace maglev::control_design {

// Terms of the simplified model (11) at (x1, x7, x9, u_x, u_z), from (6)-(8).
struct NominalTerms {
  double a1, a2, a3, a7;
  double b1, b2, b3;
  double c1, c2, c3;
  double h_x, h_z;
};
NominalTerms EvaluateNominalModel(const pmlsm_plant::StageParams& p, const pmlsm_plant::ForceConstants& k,
                                  double x1_m, double x7_rad, double x9_rad, double u_x_A, double u_z_A);

// (8) + (12): per-motor current commands that make the nominal model (11)
// follow x'' = w. u_x, u_z are clamped at +-horizontal_limit_A (sat_7 of (17));
// the raw values feed the anti-windup. With rotation loops off, v_phi =
// v_theta = 0 and w_phi, w_theta are ignored.
struct FeedbackLinearization {
  pmlsm_plant::MotorCurrents currents{};
  double u_x_A = 0.0, u_z_A = 0.0;
  double u_x_raw_A = 0.0, u_z_raw_A = 0.0;
};
FeedbackLinearization FeedbackLinearize(const pmlsm_plant::StageParams& model, const pmlsm_plant::ForceConstants& k,
                                        const std::array<double, 5>& y, const std::array<double, 5>& w,
                                        double horizontal_limit_A, bool rotation_loops_enabled);

// Set-point range check: Section IV-A (1) and the guides' stops.
enum class ReferenceError : int {
  kOk = 0,
  kGapBelowMinimum = 1,  // x1_ref < 18 mm: the stops; rejected
  kGapAboveMaximum = 2,  // x1_ref > 31 mm: the stops; rejected
  kHorizontalOutOfRange = 3,  // |x3|,|x5| > 50 mm; rejected
  kRotationOutOfRange = 4,    // |phi| > 3 mrad or |theta| > 14 mrad; rejected
};
ReferenceError CheckReference(const std::array<double, 5>& ref);
// True when the reference lies in the operating range (1) of Section IV-A
// (gap 20..30 mm, X/Z +-30 mm, theta +-10 mrad, phi 0), where the paper's
// specifications apply.
bool InPaperOperatingRange(const std::array<double, 5>& ref);

struct Paper002ControllerConfig {
  double period_s = kPaperServoPeriod_s;
  double omega0_rad_per_s = kPaperOmega0_rad_per_s;
  std::array<std::array<double, 5>, kAxes> Ks{};  // per axis, w = Ks [e e' xi] + Gamma xi
  std::array<double, 3> E_x{7e-5, 7e-5, 7e-5};    // [P] anti-windup gains
  std::array<double, 3> E_z{7e-5, 7e-5, 7e-5};    // [P]
  double horizontal_current_limit_A = 7.0;        // sat_7 of (17) [P]
  // First-order derivative filter e'_est = wf s/(s + wf) e. The paper's filter
  // ([11]) is not printed. 2 pi 50 Hz (ours): 1/20 of the servo rate, 50x the
  // slow closed-loop poles, one 10 um count -> 3 mm/s. Chosen after trying
  // 100 / 300 / 1000 rad/s on the step: the sensitivity is in docs/PAPER-002.md.
  double derivative_filter_rad_per_s = 2.0 * 3.14159265358979323846 * 50.0;
  bool rotation_loops_enabled = true;  // the 3-DOF test runs with v_phi = v_theta = 0
  pmlsm_plant::StageParams model;      // the controller's model of the plant
};

// Gains from DesignPaperAxis for every axis.
Paper002ControllerConfig MakePaperConfig();

class Paper002Controller {
 public:
  explicit Paper002Controller(const Paper002ControllerConfig& c);

  // Rejects an invalid reference (keeps the previous one).
  ReferenceError SetReference(const std::array<double, 5>& ref);
  const std::array<double, 5>& reference() const { return ref_; }

  // One servo tick: measured y = [x1 x3 x5 x7 x9] -> per-motor (i_d, i_q).
  pmlsm_plant::MotorCurrents Step(const std::array<double, 5>& y);

  const std::array<double, 5>& w() const { return w_; }
  double u_x_A() const { return u_x_; }
  double u_z_A() const { return u_z_; }

 private:
  Paper002ControllerConfig c_;
  pmlsm_plant::ForceConstants k_;
  Discrete xi_dyn_;  // ZOH of xi' = Phi xi + [N E] [e; sat(u)-u]
  double filter_alpha_;
  std::array<double, 5> ref_{};
  std::array<std::array<double, 3>, kAxes> xi_{};
  std::array<double, kAxes> filt_{};
  std::array<double, kAxes> prev_e_{};
  bool first_ = true;
  std::array<double, 5> w_{};
  double u_x_ = 0.0, u_z_ = 0.0;
};

}  // namespace maglev::control_design
