#include "maglev/control_design/paper002_controller.hpp"

#include <algorithm>
#include <cmath>

namespace maglev::control_design {

using pmlsm_plant::ForceConstants;
using pmlsm_plant::StageParams;

NominalTerms EvaluateNominalModel(const StageParams& p, const ForceConstants& k, double x1, double x7, double x9,
                                  double u_x, double u_z) {
  pmlsm_plant::State x{};
  x[0] = x1;
  x[6] = x7;
  x[8] = x9;
  const auto g = pmlsm_plant::AirGaps_m(p, x);
  std::array<double, 4> F0{}, L2{}, Lh{};
  const std::array<double, 4> iq{u_z, u_x, u_z, u_x};  // motors 1, 3 carry u_z; 2, 4 carry u_x
  for (std::size_t m = 0; m < 4; ++m) {
    F0[m] = pmlsm_plant::ComputeMotorForce(p.motor, k, g[m], 0.0, iq[m]).vertical_N;
    L2[m] = k.Kv2 * pmlsm_plant::Lv2(p.motor, g[m]);
    Lh[m] = pmlsm_plant::Lh(p.motor, g[m]);
  }
  const double My = p.mass_y_kg, r = p.radius_to_movers_r_m;
  const double Ix = p.inertia_x_kg_m2, Iz = p.inertia_z_kg_m2;
  NominalTerms t{};
  // (8): u_y1 = (vy + vphi)/2, u_y2 = (vy - vth)/2, u_y3 = (vy - vphi)/2, u_y4 = (vy + vth)/2.
  t.a1 = p.gravity_G_m_per_s2 + (F0[0] + F0[1] + F0[2] + F0[3]) / My;
  t.a3 = (L2[0] + L2[1] + L2[2] + L2[3]) / (2.0 * My);
  t.a2 = (L2[0] - L2[2]) / (2.0 * My);
  t.a7 = (L2[3] - L2[1]) / (2.0 * My);
  t.b1 = r * (F0[2] - F0[0]) / Ix - p.guide_torsion_phi_per_s2 * x7;
  t.b3 = r * (L2[2] - L2[0]) / (2.0 * Ix);
  t.b2 = -r * (L2[2] + L2[0]) / (2.0 * Ix);
  t.c1 = r * (F0[1] - F0[3]) / Iz - p.guide_torsion_theta_per_s2 * x9;
  t.c3 = r * (L2[1] - L2[3]) / (2.0 * Iz);
  t.c2 = -r * (L2[1] + L2[3]) / (2.0 * Iz);
  t.h_x = -k.Kh * (Lh[1] + Lh[3]) / p.mass_x_kg;
  t.h_z = -k.Kh * (Lh[0] + Lh[2]) / p.mass_z_kg;
  return t;
}

FeedbackLinearization FeedbackLinearize(const StageParams& model, const ForceConstants& k,
                                        const std::array<double, 5>& y, const std::array<double, 5>& w,
                                        double horizontal_limit_A, bool rotation_loops_enabled) {
  FeedbackLinearization f{};
  // (12), horizontal part first: a1, b1, c1 depend on u_x, u_z.
  const NominalTerms t0 = EvaluateNominalModel(model, k, y[0], y[3], y[4], 0.0, 0.0);
  f.u_x_raw_A = w[1] / t0.h_x;
  f.u_z_raw_A = w[2] / t0.h_z;
  f.u_x_A = std::clamp(f.u_x_raw_A, -horizontal_limit_A, horizontal_limit_A);
  f.u_z_A = std::clamp(f.u_z_raw_A, -horizontal_limit_A, horizontal_limit_A);
  const NominalTerms t = EvaluateNominalModel(model, k, y[0], y[3], y[4], f.u_x_A, f.u_z_A);
  double vy = 0, vphi = 0, vth = 0;
  if (rotation_loops_enabled) {
    Eigen::Matrix3d M;
    M << t.a3, t.a2, t.a7, t.b3, t.b2, 0.0, t.c3, 0.0, t.c2;
    const Eigen::Vector3d v = M.partialPivLu().solve(Eigen::Vector3d(w[0] - t.a1, w[3] - t.b1, w[4] - t.c1));
    vy = v(0);
    vphi = v(1);
    vth = v(2);
  } else {
    vy = (w[0] - t.a1) / t.a3;
  }
  // (8), with i_q = u_z on motors 1, 3 and u_x on motors 2, 4.
  f.currents[0] = {(vy + vphi) / 2.0, f.u_z_A};
  f.currents[1] = {(vy - vth) / 2.0, f.u_x_A};
  f.currents[2] = {(vy - vphi) / 2.0, f.u_z_A};
  f.currents[3] = {(vy + vth) / 2.0, f.u_x_A};
  return f;
}

ReferenceError CheckReference(const std::array<double, 5>& ref) {
  if (!(ref[0] >= 18e-3)) return ReferenceError::kGapBelowMinimum;
  if (!(ref[0] <= 31e-3)) return ReferenceError::kGapAboveMaximum;
  if (!(std::abs(ref[1]) <= 50e-3) || !(std::abs(ref[2]) <= 50e-3)) return ReferenceError::kHorizontalOutOfRange;
  if (!(std::abs(ref[3]) <= 3e-3) || !(std::abs(ref[4]) <= 14e-3)) return ReferenceError::kRotationOutOfRange;
  return ReferenceError::kOk;
}

bool InPaperOperatingRange(const std::array<double, 5>& ref) {
  return CheckReference(ref) == ReferenceError::kOk && ref[0] >= 20e-3 && ref[0] <= 30e-3 &&
         std::abs(ref[1]) <= 30e-3 && std::abs(ref[2]) <= 30e-3 && ref[3] == 0.0 && std::abs(ref[4]) <= 10e-3;
}

Paper002ControllerConfig MakePaperConfig() {
  Paper002ControllerConfig c;
  for (int a = 0; a < kAxes; ++a) c.Ks[static_cast<std::size_t>(a)] = DesignPaperAxis(static_cast<Axis>(a)).Ks;
  return c;
}

Paper002Controller::Paper002Controller(const Paper002ControllerConfig& c)
    : c_(c), k_(pmlsm_plant::ComputeForceConstants(c.model.motor)) {
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(3, 3);
  Phi(0, 1) = 1.0;
  Phi(1, 2) = 1.0;
  Phi(2, 1) = -c.omega0_rad_per_s * c.omega0_rad_per_s;
  // Input matrix I: the input vector N e + E (sat(u) - u) is formed per axis.
  xi_dyn_ = DiscretizeZoh(Phi, Eigen::MatrixXd::Identity(3, 3), c.period_s);
  filter_alpha_ = 1.0 - std::exp(-c.derivative_filter_rad_per_s * c.period_s);
  ref_ = {25e-3, 0, 0, 0, 0};
}

ReferenceError Paper002Controller::SetReference(const std::array<double, 5>& ref) {
  const ReferenceError e = CheckReference(ref);
  if (e == ReferenceError::kOk) ref_ = ref;
  return e;
}

pmlsm_plant::MotorCurrents Paper002Controller::Step(const std::array<double, 5>& y) {
  std::array<double, kAxes> e{}, edot{};
  for (std::size_t a = 0; a < kAxes; ++a) {
    e[a] = y[a] - ref_[a];
    if (first_) filt_[a] = e[a];
    // e'_est = wf (e - f), f' = wf (e - f), exact for e held over the period.
    edot[a] = c_.derivative_filter_rad_per_s * (e[a] - filt_[a]);
  }
  first_ = false;
  // Regulator outputs (16): w = Ks [e e' xi] + Gamma xi.
  for (std::size_t a = 0; a < kAxes; ++a) {
    const auto& K = c_.Ks[a];
    const auto& xi = xi_[a];
    w_[a] = K[0] * e[a] + K[1] * edot[a] + K[2] * xi[0] + K[3] * xi[1] + K[4] * xi[2] + xi[0];
  }
  if (!c_.rotation_loops_enabled) w_[3] = w_[4] = 0.0;
  const FeedbackLinearization f = FeedbackLinearize(c_.model, k_, y, w_, c_.horizontal_current_limit_A,
                                                    c_.rotation_loops_enabled);
  u_x_ = f.u_x_A;
  u_z_ = f.u_z_A;
  const double ux_raw = f.u_x_raw_A, uz_raw = f.u_z_raw_A;
  // Internal models (14) with anti-windup (17) on X and Z, advanced by ZOH.
  const std::array<double, kAxes> aw{0.0, u_x_ - ux_raw, u_z_ - uz_raw, 0.0, 0.0};
  for (std::size_t a = 0; a < kAxes; ++a) {
    Eigen::Vector3d in(0.0, 0.0, e[a]);
    if (a == 1 || a == 2) {
      const auto& E = (a == 1) ? c_.E_x : c_.E_z;
      in += aw[a] * Eigen::Vector3d(E[0], E[1], E[2]);
    }
    const Eigen::Vector3d xi(xi_[a][0], xi_[a][1], xi_[a][2]);
    const Eigen::Vector3d xn = xi_dyn_.Ad * xi + xi_dyn_.Bd * in;
    xi_[a] = {xn(0), xn(1), xn(2)};
    filt_[a] += filter_alpha_ * (e[a] - filt_[a]);
  }
  return f.currents;
}

}  // namespace maglev::control_design
