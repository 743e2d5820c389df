// Riccati solver, ZOH discretization and inverse LQR on cases with closed forms.
#include <cmath>

#include "maglev/control_design/lqr.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::control_design;

namespace {
Eigen::MatrixXd DoubleIntegratorA() {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2, 2);
  A(0, 1) = 1.0;
  return A;
}
Eigen::MatrixXd DoubleIntegratorB() {
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(2, 1);
  B(1, 0) = 1.0;
  return B;
}
}  // namespace

TEST_GROUP(Lqr){};

TEST(Lqr, DoubleIntegratorClosedForm) {
  // Q = I, R = 1: P = [[sqrt3, 1], [1, sqrt3]], K = [1, sqrt3].
  const LqrResult r = SolveContinuousLqr(DoubleIntegratorA(), DoubleIntegratorB(), Eigen::MatrixXd::Identity(2, 2),
                                         Eigen::MatrixXd::Identity(1, 1));
  CHECK(r.error == DesignError::kOk);
  DOUBLES_EQUAL(std::sqrt(3.0), r.P(0, 0), 1e-12);
  DOUBLES_EQUAL(1.0, r.P(0, 1), 1e-12);
  DOUBLES_EQUAL(std::sqrt(3.0), r.P(1, 1), 1e-12);
  DOUBLES_EQUAL(1.0, r.K(0, 0), 1e-12);
  DOUBLES_EQUAL(std::sqrt(3.0), r.K(0, 1), 1e-12);
  CHECK(r.residual < 1e-12);
}

TEST(Lqr, ScalarUnstablePlant) {
  // x' = a x + u, Q = q, R = 1: P = a + sqrt(a^2 + q), closed loop -sqrt(a^2 + q).
  Eigen::MatrixXd A(1, 1), B(1, 1), Q(1, 1), R(1, 1);
  A << 2.0;
  B << 1.0;
  Q << 5.0;
  R << 1.0;
  const LqrResult r = SolveContinuousLqr(A, B, Q, R);
  DOUBLES_EQUAL(2.0 + 3.0, r.P(0, 0), 1e-12);
  const auto p = ClosedLoopPoles(A, B, r.K);
  DOUBLES_EQUAL(-3.0, p[0].real(), 1e-12);
}

TEST(Lqr, BadInputsAreReported) {
  const LqrResult r = SolveContinuousLqr(DoubleIntegratorA(), DoubleIntegratorB(), Eigen::MatrixXd::Identity(3, 3),
                                         Eigen::MatrixXd::Identity(1, 1));
  CHECK(r.error == DesignError::kBadDimensions);
  // Uncontrollable, undamped mode with no cost: no stabilizing solution.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2, 2);
  A(0, 1) = 1.0;
  A(1, 0) = -1.0;
  const LqrResult u = SolveContinuousLqr(A, Eigen::MatrixXd::Zero(2, 1), Eigen::MatrixXd::Zero(2, 2),
                                         Eigen::MatrixXd::Identity(1, 1));
  CHECK(u.error != DesignError::kOk);
}

TEST(Lqr, LyapunovSolves) {
  Eigen::MatrixXd A(2, 2);
  A << -1.0, 2.0, 0.0, -3.0;
  const Eigen::MatrixXd C = Eigen::MatrixXd::Identity(2, 2);
  const Eigen::MatrixXd X = SolveLyapunov(A, C);
  CHECK((A.transpose() * X + X * A + C).norm() < 1e-12);
}

TEST(Lqr, ZohOfDoubleIntegrator) {
  const double T = 1e-3;
  const Discrete d = DiscretizeZoh(DoubleIntegratorA(), DoubleIntegratorB(), T);
  DOUBLES_EQUAL(1.0, d.Ad(0, 0), 1e-15);
  DOUBLES_EQUAL(T, d.Ad(0, 1), 1e-15);
  DOUBLES_EQUAL(T * T / 2.0, d.Bd(0, 0), 1e-18);
  DOUBLES_EQUAL(T, d.Bd(1, 0), 1e-15);
}

TEST(Lqr, InverseLqrDoubleIntegrator) {
  // Poles -1 +- 1j (zeta = 0.707, the Kalman-inequality limit is reachable):
  // Q = h'h, LQR gives those poles back.
  const std::vector<std::complex<double>> target{{-2.0, 1.0}, {-2.0, -1.0}};
  const InverseLqrResult w = StateWeightForPoles(DoubleIntegratorA(), DoubleIntegratorB().col(0), target);
  CHECK(w.error == DesignError::kOk);
  const LqrResult r = SolveContinuousLqr(DoubleIntegratorA(), DoubleIntegratorB(), w.h.transpose() * w.h,
                                         Eigen::MatrixXd::Identity(1, 1));
  const auto p = ClosedLoopPoles(DoubleIntegratorA(), DoubleIntegratorB(), r.K);
  // Closed form: K = [b, a] for s^2 + a s + b = s^2 + 4 s + 5.
  DOUBLES_EQUAL(5.0, r.K(0, 0), 1e-9);
  DOUBLES_EQUAL(4.0, r.K(0, 1), 1e-9);
  DOUBLES_EQUAL(-2.0, p[0].real(), 1e-9);
}

TEST(Lqr, PolesBelowKalmanLimitAreRejected) {
  // zeta < 1/sqrt2 on a double integrator is not LQR-optimal for any Q >= 0.
  const std::vector<std::complex<double>> target{{-1.0, 3.0}, {-1.0, -3.0}};
  const InverseLqrResult w = StateWeightForPoles(DoubleIntegratorA(), DoubleIntegratorB().col(0), target);
  CHECK(w.error == DesignError::kNotSpectralFactorizable);
}
