// The five internal-model regulators designed by LQR reproduce the paper's
// printed closed-loop poles (within the 2 % band).
#include <cstdio>

#include "maglev/control_design/imr_design.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::control_design;

TEST_GROUP(ImrDesign){};

TEST(ImrDesign, ImrPlantHasInternalModelPoles) {
  const ImrPlant p = BuildImrPlant(kPaperOmega0_rad_per_s);
  // Phi block: eigenvalues 0, +-j w0.
  const Eigen::MatrixXd Phi = p.A.bottomRightCorner(3, 3);
  const Eigen::VectorXcd ev = Phi.eigenvalues();
  double max_imag = 0;
  for (Eigen::Index i = 0; i < 3; ++i) {
    DOUBLES_EQUAL(0.0, ev(i).real(), 1e-12);
    max_imag = std::max(max_imag, std::abs(ev(i).imag()));
  }
  DOUBLES_EQUAL(1.5 * M_PI, max_imag, 1e-12);
}

TEST(ImrDesign, EveryAxisMatchesPaperPolesWithinTwoPercent) {
  for (int i = 0; i < kAxes; ++i) {
    const Axis a = static_cast<Axis>(i);
    const AxisDesign d = DesignPaperAxis(a);
    CHECK_TEXT(d.error == DesignError::kOk, AxisName(a));
    const double err = WorstRelativePoleError(d.poles, PaperPoles(a));
    std::printf("axis %-5s worst |p - p_paper| / |p_paper| = %.2e  K_s = [%.5g %.5g %.5g %.5g %.5g]\n", AxisName(a),
                err, d.Ks[0], d.Ks[1], d.Ks[2], d.Ks[3], d.Ks[4]);
    CHECK_TEXT(err < 0.02, AxisName(a));
    CHECK(d.riccati_residual < 1e-9);
    // Q is a weight: symmetric positive semidefinite.
    const Eigen::VectorXd qe = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(d.Q).eigenvalues();
    CHECK(qe.minCoeff() > -1e-6 * qe.maxCoeff());
  }
}

TEST(ImrDesign, GainsFromWeightsAreLqrOptimal) {
  // Perturbing the derived gain raises the LQR cost: the gain is the optimum
  // for its weights, not merely a pole placement.
  const AxisDesign d = DesignPaperAxis(Axis::kY);
  const ImrPlant p = BuildImrPlant(kPaperOmega0_rad_per_s);
  auto cost = [&](const Eigen::RowVectorXd& K) {
    const Eigen::MatrixXd Ac = p.A - p.B * K;
    const Eigen::MatrixXd X = SolveLyapunov(Ac, d.Q + K.transpose() * d.R * K);
    return X.trace();
  };
  const double c0 = cost(d.K);
  for (int j = 0; j < 5; ++j) {
    Eigen::RowVectorXd K = d.K;
    K(j) *= 1.01;
    CHECK(cost(K) > c0);
  }
}

TEST(ImrDesign, DiscreteLoopAtOneKilohertzIsStableAndClose) {
  // Continuous gains at 1 kHz ZOH: discrete poles near exp(p T).
  for (int i = 0; i < kAxes; ++i) {
    const Axis a = static_cast<Axis>(i);
    const AxisDesign d = DesignPaperAxis(a);
    const ImrPlant p = BuildImrPlant(kPaperOmega0_rad_per_s);
    const Discrete z = DiscretizeZoh(p.A, p.B, kPaperServoPeriod_s);
    const Eigen::VectorXcd zp = (z.Ad - z.Bd * d.K).eigenvalues();
    std::vector<std::complex<double>> s;
    for (Eigen::Index j = 0; j < zp.size(); ++j) {
      CHECK(std::abs(zp(j)) < 1.0);
      s.push_back(std::log(zp(j)) / kPaperServoPeriod_s);
    }
    // Sampling moves the fast real pole most (-200 rad/s at 1 kHz): 15 % band.
    CHECK_TEXT(WorstRelativePoleError(s, PaperPoles(a)) < 0.15, AxisName(a));
  }
}
