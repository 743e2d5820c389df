#include "maglev/control_design/lqr.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <unsupported/Eigen/MatrixFunctions>

namespace maglev::control_design {

const char* ToString(DesignError e) {
  switch (e) {
    case DesignError::kOk: return "ok";
    case DesignError::kBadDimensions: return "bad dimensions";
    case DesignError::kNoStabilizingSolution: return "no stabilizing Riccati solution";
    case DesignError::kNotConverged: return "Newton-Kleinman did not converge";
    case DesignError::kNotSpectralFactorizable: return "poles are not LQR-optimal for any Q >= 0";
  }
  return "unknown";
}

Eigen::MatrixXd SolveLyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& C) {
  const Eigen::Index n = A.rows();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  // vec(A'X + XA) = (I kron A' + A' kron I) vec(X).
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n * n, n * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j) {
      L.block(i * n, j * n, n, n) += I(i, j) * A.transpose();
      L.block(i * n, j * n, n, n) += A(j, i) * I;
    }
  const Eigen::VectorXd c = Eigen::Map<const Eigen::VectorXd>(C.data(), n * n);
  const Eigen::VectorXd x = L.fullPivLu().solve(-c);
  Eigen::MatrixXd X = Eigen::Map<const Eigen::MatrixXd>(x.data(), n, n);
  return 0.5 * (X + X.transpose());
}

static double Residual(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                       const Eigen::MatrixXd& Rinv, const Eigen::MatrixXd& P) {
  const Eigen::MatrixXd res = A.transpose() * P + P * A - P * B * Rinv * B.transpose() * P + Q;
  const double q = Q.norm();
  return res.norm() / (q > 0 ? q : 1.0);
}

LqrResult SolveContinuousLqr(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, const Eigen::MatrixXd& Q,
                             const Eigen::MatrixXd& R) {
  LqrResult out;
  const Eigen::Index n = A.rows();
  if (A.cols() != n || B.rows() != n || Q.rows() != n || Q.cols() != n || R.rows() != B.cols() ||
      R.cols() != B.cols()) {
    out.error = DesignError::kBadDimensions;
    return out;
  }
  const Eigen::MatrixXd Rinv = R.inverse();
  Eigen::MatrixXd H(2 * n, 2 * n);
  H << A, -B * Rinv * B.transpose(), -Q, -A.transpose();
  Eigen::EigenSolver<Eigen::MatrixXd> es(H);
  Eigen::MatrixXcd U(2 * n, n);
  Eigen::Index k = 0;
  const double scale = H.norm();
  for (Eigen::Index i = 0; i < 2 * n; ++i) {
    const std::complex<double> l = es.eigenvalues()(i);
    if (std::abs(l.real()) < 1e-12 * scale) {
      out.error = DesignError::kNoStabilizingSolution;
      return out;
    }
    if (l.real() < 0 && k < n) U.col(k++) = es.eigenvectors().col(i);
  }
  if (k != n) {
    out.error = DesignError::kNoStabilizingSolution;
    return out;
  }
  const Eigen::MatrixXcd U1 = U.topRows(n), U2 = U.bottomRows(n);
  Eigen::MatrixXd P = (U2 * U1.inverse()).real();
  P = 0.5 * (P + P.transpose());
  // Newton-Kleinman polish: K_j = R^-1 B'P_j, (A - B K_j)'P + P(A - B K_j) + Q + K_j'R K_j = 0.
  for (int it = 0; it < 20; ++it) {
    if (Residual(A, B, Q, Rinv, P) < 1e-13) break;
    const Eigen::MatrixXd K = Rinv * B.transpose() * P;
    const Eigen::MatrixXd Ac = A - B * K;
    const Eigen::MatrixXd Pn = SolveLyapunov(Ac, Q + K.transpose() * R * K);
    const double step = (Pn - P).norm() / (P.norm() > 0 ? P.norm() : 1.0);
    P = Pn;
    out.newton_iterations = it + 1;
    if (step < 1e-15) break;
  }
  out.residual = Residual(A, B, Q, Rinv, P);
  if (!(out.residual < 1e-6)) out.error = DesignError::kNotConverged;
  out.P = P;
  out.K = Rinv * B.transpose() * P;
  return out;
}

std::vector<std::complex<double>> ClosedLoopPoles(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B,
                                                  const Eigen::MatrixXd& K) {
  const Eigen::VectorXcd ev = (A - B * K).eigenvalues();
  return {ev.data(), ev.data() + ev.size()};
}

Eigen::MatrixXd MatrixExponential(const Eigen::MatrixXd& M) { return M.exp(); }

Discrete DiscretizeZoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double T_s) {
  const Eigen::Index n = A.rows(), m = B.cols();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = A * T_s;
  M.topRightCorner(n, m) = B * T_s;
  const Eigen::MatrixXd E = MatrixExponential(M);
  return {E.topLeftCorner(n, n), E.topRightCorner(n, m)};
}

std::vector<double> PolyFromRoots(const std::vector<std::complex<double>>& roots) {
  std::vector<std::complex<double>> c{1.0};
  for (std::size_t deg = 0; deg < roots.size(); ++deg) {
    c.push_back(0.0);
    for (std::size_t i = deg + 1; i >= 1; --i) c[i] -= roots[deg] * c[i - 1];
  }
  std::vector<double> r(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) r[i] = c[i].real();
  return r;
}

namespace {
// p(-s) from p(s), coefficients highest power first.
std::vector<double> Mirror(std::vector<double> p) {
  const std::size_t d = p.size() - 1;
  for (std::size_t i = 0; i <= d; ++i)
    if ((d - i) % 2 == 1) p[i] = -p[i];
  return p;
}
std::vector<double> Mul(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}
}  // namespace

InverseLqrResult StateWeightForPoles(const Eigen::MatrixXd& A, const Eigen::VectorXd& b,
                                     const std::vector<std::complex<double>>& poles) {
  InverseLqrResult out;
  const Eigen::Index n = A.rows();
  if (A.cols() != n || b.size() != n || static_cast<Eigen::Index>(poles.size()) != n) {
    out.error = DesignError::kBadDimensions;
    return out;
  }
  // Open-loop characteristic polynomial and adj(sI - A) b by Faddeev-LeVerrier:
  // adj(sI - A) = sum_k s^(n-1-k) M_k, M_0 = I, M_k = A M_(k-1) + c_k I.
  std::vector<double> dol{1.0};
  Eigen::MatrixXd N(n, n);  // column k: coefficient of s^(n-1-k) in adj(sI-A) b
  Eigen::MatrixXd Mk = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index k = 1; k <= n; ++k) {
    N.col(k - 1) = Mk * b;
    const Eigen::MatrixXd AM = A * Mk;
    const double ck = -AM.trace() / static_cast<double>(k);
    dol.push_back(ck);
    Mk = AM + ck * Eigen::MatrixXd::Identity(n, n);
  }
  const std::vector<double> dcl = PolyFromRoots(poles);
  const std::vector<double> pc = Mul(dcl, Mirror(dcl)), po = Mul(dol, Mirror(dol));
  std::vector<double> diff(pc.size());  // even, degree <= 2n-2
  double dmax = 0.0;
  for (std::size_t i = 0; i < pc.size(); ++i) {
    diff[i] = pc[i] - po[i];
    dmax = std::max(dmax, std::abs(diff[i]));
  }
  // Even polynomial in sigma = s^2 (coefficients highest first, degree n-1).
  const Eigen::Index m = n - 1;
  Eigen::VectorXd e(m + 1);
  for (Eigen::Index i = 0; i <= m; ++i) e(i) = diff[static_cast<std::size_t>(2 + 2 * i)];  // s^(2(m-i))
  const double tol = 1e-10 * dmax;
  if (std::abs(diff[0]) > tol || std::abs(diff[1]) > tol) {
    out.error = DesignError::kNotSpectralFactorizable;
    return out;
  }
  // Strip vanishing leading coefficients (fewer zeros in n(s)).
  Eigen::Index lead = 0;
  while (lead < m && std::abs(e(lead)) <= tol) ++lead;
  const Eigen::VectorXd ep = e.tail(m + 1 - lead);
  const Eigen::Index deg = ep.size() - 1;  // degree of n(s)
  // n(s) n(-s) = ep(sigma); leading coefficient of n(s)n(-s) is (-1)^deg n0^2.
  const double lead_sign = (deg % 2 == 0) ? 1.0 : -1.0;
  if (ep(0) * lead_sign <= 0.0) {
    out.error = DesignError::kNotSpectralFactorizable;
    return out;
  }
  std::vector<std::complex<double>> zeros;
  if (deg > 0) {
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(deg, deg);  // companion of ep
    for (Eigen::Index j = 0; j < deg; ++j) C(0, j) = -ep(j + 1) / ep(0);
    for (Eigen::Index j = 1; j < deg; ++j) C(j, j - 1) = 1.0;
    const Eigen::VectorXcd sig = C.eigenvalues();
    for (Eigen::Index j = 0; j < deg; ++j) {
      std::complex<double> s = std::sqrt(sig(j));
      if (std::abs(s.real()) < 1e-9 * (1.0 + std::abs(s))) {
        out.error = DesignError::kNotSpectralFactorizable;  // zero on the jw axis
        return out;
      }
      if (s.real() > 0) s = -s;
      zeros.push_back(s);
    }
  }
  const std::vector<double> nmonic = PolyFromRoots(zeros);
  const double n0 = std::sqrt(ep(0) * lead_sign);
  // n(s) coefficients padded to degree n-1, highest first.
  Eigen::VectorXd ncoef = Eigen::VectorXd::Zero(n);
  for (Eigen::Index j = 0; j <= deg; ++j) ncoef(n - 1 - deg + j) = n0 * nmonic[static_cast<std::size_t>(j)];
  // h N = ncoef'  ->  N' h' = ncoef.
  out.h = N.transpose().fullPivLu().solve(ncoef).transpose();
  return out;
}

}  // namespace maglev::control_design
