#include "maglev/control_design/imr_design.hpp"

#include <algorithm>
#include <limits>

namespace maglev::control_design {

const char* AxisName(Axis a) {
  switch (a) {
    case Axis::kY: return "y";
    case Axis::kX: return "x";
    case Axis::kZ: return "z";
    case Axis::kPhi: return "phi";
    case Axis::kTheta: return "theta";
  }
  return "?";
}

std::vector<std::complex<double>> PaperPoles(Axis a) {
  using C = std::complex<double>;
  switch (a) {
    case Axis::kY: return {C(-173.2, 0), C(-2.61, 5.48), C(-2.61, -5.48), C(-2.16, 1.77), C(-2.16, -1.77)};
    case Axis::kX:
    case Axis::kZ: return {C(-38.73, 0), C(-3.2, 5.89), C(-3.2, -5.89), C(-2.69, 2.23), C(-2.69, -2.23)};
    case Axis::kPhi:
    case Axis::kTheta: return {C(-200, 0), C(-2.81, 5.58), C(-2.81, -5.58), C(-2.19, 1.82), C(-2.19, -1.82)};
  }
  return {};
}

ImrPlant BuildImrPlant(double w0) {
  ImrPlant p{Eigen::MatrixXd::Zero(5, 5), Eigen::MatrixXd::Zero(5, 1)};
  p.A(0, 1) = 1.0;        // e' = e'
  p.A(1, 2) = 1.0;        // e'' = w = u + Gamma xi
  p.A(2, 3) = 1.0;        // Phi row 1
  p.A(3, 4) = 1.0;        // Phi row 2
  p.A(4, 3) = -w0 * w0;   // Phi row 3
  p.A(4, 0) = 1.0;        // + N e
  p.B(1, 0) = 1.0;
  return p;
}

AxisDesign DesignAxisFromWeights(Axis a, double omega0, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& R) {
  AxisDesign d;
  d.axis = a;
  d.Q = Q;
  d.R = R;
  const ImrPlant p = BuildImrPlant(omega0);
  const LqrResult l = SolveContinuousLqr(p.A, p.B, Q, R);
  d.error = l.error;
  d.riccati_residual = l.residual;
  if (l.error != DesignError::kOk) return d;
  d.K = l.K.row(0);
  for (int i = 0; i < 5; ++i) d.Ks[static_cast<std::size_t>(i)] = -d.K(i);
  d.poles = ClosedLoopPoles(p.A, p.B, l.K);
  return d;
}

AxisDesign DesignPaperAxis(Axis a, double omega0) {
  const ImrPlant p = BuildImrPlant(omega0);
  const InverseLqrResult w = StateWeightForPoles(p.A, p.B.col(0), PaperPoles(a));
  if (w.error != DesignError::kOk) {
    AxisDesign d;
    d.axis = a;
    d.error = w.error;
    return d;
  }
  return DesignAxisFromWeights(a, omega0, w.h.transpose() * w.h, Eigen::MatrixXd::Identity(1, 1));
}

double WorstRelativePoleError(const std::vector<std::complex<double>>& achieved,
                              const std::vector<std::complex<double>>& target) {
  if (achieved.size() != target.size()) return std::numeric_limits<double>::infinity();
  std::vector<bool> used(achieved.size(), false);
  double worst = 0.0;
  for (const auto& t : target) {
    std::size_t best = achieved.size();
    double bd = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < achieved.size(); ++i)
      if (!used[i] && std::abs(achieved[i] - t) < bd) {
        bd = std::abs(achieved[i] - t);
        best = i;
      }
    used[best] = true;
    worst = std::max(worst, bd / std::abs(t));
  }
  return worst;
}

}  // namespace maglev::control_design
