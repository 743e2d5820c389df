#pragma once
// Continuous-time LQR with Eigen: the algebraic Riccati equation
//   A'P + PA - P B R^-1 B' P + Q = 0
// solved by the Hamiltonian eigenvector method (stable invariant subspace),
// then polished by Newton-Kleinman iterations (each a Lyapunov solve).
// Plus zero-order-hold discretization and the inverse problem for one input:
// the state weight that makes LQR place given closed-loop poles.
#include <Eigen/Dense>
#include <complex>
#include <vector>

namespace maglev::control_design {

enum class DesignError : int {
  kOk = 0,
  kBadDimensions = 1,
  kNoStabilizingSolution = 2,  // Hamiltonian has eigenvalues on the imaginary axis
  kNotConverged = 3,
  kNotSpectralFactorizable = 4,  // requested poles are not LQR-optimal for any Q >= 0
};
const char* ToString(DesignError e);

struct LqrResult {
  DesignError error = DesignError::kOk;
  Eigen::MatrixXd P;  // Riccati solution
  Eigen::MatrixXd K;  // u = -K x
  double residual = 0.0;  // ||A'P + PA - PBR^-1B'P + Q||_F / ||Q||_F
  int newton_iterations = 0;
};

LqrResult SolveContinuousLqr(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                             const Eigen::MatrixXd& R);

// Solves A'X + XA + C = 0 (Kronecker form; fine for the small n used here).
Eigen::MatrixXd SolveLyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C);

// Closed-loop eigenvalues of A - B K.
std::vector<std::complex<double>> ClosedLoopPoles(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B,
                                                  const Eigen::MatrixXd& K);

// Zero-order hold: [Ad Bd; 0 I] = expm([A B; 0 0] T).
struct Discrete {
  Eigen::MatrixXd Ad;
  Eigen::MatrixXd Bd;
};
Discrete DiscretizeZoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double T_s);
Eigen::MatrixXd MatrixExponential(const Eigen::MatrixXd& M);

// Inverse LQR for a controllable single-input pair (A, b) and R = 1: returns
// the row h such that Q = h' h makes the LQR closed loop have exactly the
// given poles. By the return-difference identity
//   Dcl(s) Dcl(-s) = Dol(s) Dol(-s) + n(s) n(-s),  n(s) = h adj(sI - A) b,
// n is the Hurwitz spectral factor of the even polynomial on the left minus
// Dol(s)Dol(-s); it exists iff that polynomial is >= 0 on the jw axis.
struct InverseLqrResult {
  DesignError error = DesignError::kOk;
  Eigen::RowVectorXd h;
};
InverseLqrResult StateWeightForPoles(const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                     const std::vector<std::complex<double>>& poles);

// Monic polynomial coefficients (highest power first) of prod (s - p_i).
std::vector<double> PolyFromRoots(const std::vector<std::complex<double>>& roots);

}  // namespace maglev::control_design
