#pragma once
// LQR design of paper 002's five internal-model regulators (14)-(16).
//
// Each feedback-linearized axis (13) is a double integrator e'' = w. With the
// internal model xi' = Phi xi + N e (poles 0, +-j w0) and
// w = K_s [e e' xi]' + Gamma xi, the design plant in z = [e e' xi1 xi2 xi3] is
//   z' = A z + B u,  u = -K z  (so K_s = -K),
// with A containing Gamma xi in the e'' row. The paper prints the closed-loop
// poles, not the LQR weights. We derive the weights: with R = 1, the rank-one
// state weight Q = h'h whose LQR closed loop has exactly the printed poles
// (inverse LQR by spectral factorization, lqr.hpp). They are derived from the
// paper's poles; the paper's own (unprinted) weights may differ.
#include <Eigen/Dense>
#include <array>
#include <complex>
#include <vector>

#include "maglev/control_design/lqr.hpp"

namespace maglev::control_design {

// Axis order of (13): y, x, z, phi, theta.
enum class Axis : int { kY = 0, kX = 1, kZ = 2, kPhi = 3, kTheta = 4 };
inline constexpr int kAxes = 5;
const char* AxisName(Axis a);

inline constexpr double kPaperOmega0_rad_per_s = 1.5 * 3.14159265358979323846;  // omega_0 = 1.5 pi
inline constexpr double kPaperServoPeriod_s = 1e-3;                             // 1 kHz

// The printed closed-loop poles (Section IV-A). phi: not printed, the paper
// only regulates phi to 0; we reuse theta's poles (ours).
std::vector<std::complex<double>> PaperPoles(Axis a);

struct ImrPlant {
  Eigen::MatrixXd A;  // 5x5
  Eigen::MatrixXd B;  // 5x1
};
ImrPlant BuildImrPlant(double omega0_rad_per_s);

struct AxisDesign {
  Axis axis = Axis::kY;
  DesignError error = DesignError::kOk;
  Eigen::MatrixXd Q;               // state weight used (derived, rank one)
  Eigen::MatrixXd R;               // 1x1, = 1
  Eigen::RowVectorXd K;            // LQR gain, u = -K z
  std::array<double, 5> Ks{};      // paper's K_s = -K: w = Ks [e e' xi] + Gamma xi
  std::vector<std::complex<double>> poles;  // eig(A - B K)
  double riccati_residual = 0.0;
};

// LQR from explicit weights (the general tool).
AxisDesign DesignAxisFromWeights(Axis a, double omega0, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R);
// Weights derived from the paper's poles, then LQR.
AxisDesign DesignPaperAxis(Axis a, double omega0 = kPaperOmega0_rad_per_s);

// Worst relative pole error: for each target pole, |achieved - target| / |target|
// against the nearest achieved pole (each achieved pole used once).
double WorstRelativePoleError(const std::vector<std::complex<double>>& achieved,
                              const std::vector<std::complex<double>>& target);

}  // namespace maglev::control_design
