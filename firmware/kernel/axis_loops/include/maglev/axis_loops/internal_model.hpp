// Internal-model regulator (servo compensator), paper 002 eqs (14)-(17),
// applied to one paper-000 axis y'' + c' y' + k' y = g u.
//
// Internal model with poles at s = 0 and s = +-j w0 (eqs (14), (15)),
// discretized at the servo period T so that its discrete poles are EXACTLY
// z = 1 and z = exp(+-j w0 T) (the exact ZOH pole map):
//   xi0_{k+1} = xi0_k + T e_k                         (pole z = 1)
//   r1_{k+1}  = r1_k + eps r2_k                        (resonator, "magic
//   r2_{k+1}  = r2_k - eps r1_{k+1} + T e_k             circle" form)
// with eps = 2 sin(w0 T / 2). The resonator matrix [[1, eps], [-eps, 1-eps^2]]
// has determinant exactly 1 and trace 2 - eps^2 = 2 cos(w0 T), so its poles
// sit exactly on exp(+-j w0 T); because det = 1 holds for ANY eps, rounding
// eps to the Q3.28 coefficient format moves the frequency by < 1e-6 relative
// but can never move the poles off the unit circle. It is a similarity
// transform of (15)'s companion form, so the internal-model principle (zero
// steady-state error for constants and w0-sinusoids) is unchanged.
//
// Control law, eq (16), in kernel units (e in um or urad, u in A):
//   v = k_e e + D + k_xi0 xi0 + k_r1 r1 + k_r2 r2 + u_ff,
// where D is k_de times a Tustin-filtered derivative of e (the paper's
// "linear filter" estimate of e-dot). As in Pid2Dof, the inputs are the
// error e = r - y and the explicit reference step of this tick; the step is
// weighted by b (injected into xi0: k_xi0 xi0 -= k_e (1-b) dr, exact
// because xi0 is a pure integrator) and c (derivative kick).
// Anti-windup, eq (17): after the applied effort is known,
//   [xi0 r1 r2] += E (u_applied - v),  E = (T/Tt) K_xi / |K_xi|^2,
// i.e. the internal model's own output contribution is pulled towards the
// applied effort with time constant Tt (back-calculation, generalised).
//
// Default gains: Ackermann's formula (pole placement) on the exact-ZOH
// discretized plant of the axis augmented with the internal model above;
// pole choice in design_internal_model_double().
#pragma once

#include "maglev/io/code_placement.hpp"
#include <cmath>

#include "maglev/axis_loops/design_error.hpp"
#include "maglev/axis_loops/loop_terms.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"
#include "maglev/numeric/elementary.hpp"

namespace maglev::kernel {

struct InternalModelConfig {
  float omega0_rad_s = 4.71238898f;         // paper 002: w0 = 1.5 pi rad/s
  // Plant of this axis: y'' + damping y' + stiffness y = gain u (SI).
  float plant_gain = 2.2716f;               // m/s^2 per A (rad/s^2 per A)
  float plant_damping_per_s = 0.0f;         // c/m
  float plant_stiffness_per_s2 = 0.0f;      // k/m
  float bandwidth_Hz = 20.0f;               // w_c / (2 pi): the plant pole pair
  float internal_model_bandwidth_Hz = 1.5f;  // w_im / (2 pi): the internal model's poles
  float derivative_filter_hz = 1000.0f;
  float setpoint_weight_p = 1.0f;           // b
  float setpoint_weight_d = 0.0f;           // c
  float antiwindup_tracking_time_s = 0.01f; // Tt of eq (17)'s E
  float effort_limit_A = 4.0f;
};

// Stored in a scaled realization so that every coefficient is O(1) (fits
// Q3.28) and the states are in A: s0 = k_xi0 xi0, (s1, s2) = lambda (r1, r2)
// with lambda = |(k_r1, k_r2)| (one common factor: the resonator matrix, and
// so its exact poles, is unchanged).
// Every gain but the setpoint weight c enters only the accumulator's MACs:
// AccCoeff (the float kernel holds the float values as double, exactly).
template <typename Scalar>
struct InternalModelCoefficients {
  using Coeff = typename numeric::ScalarTraits<Scalar>::Coeff;
  using AccCoeff = typename numeric::ScalarTraits<Scalar>::AccCoeff;
  AccCoeff k_e{};          // A/um
  AccCoeff step_gain{};    // k_e (1-b), A/um: step weighting injected into s0
  Coeff c{};               // setpoint weight, D
  AccCoeff a_d{};          // derivative filter pole
  AccCoeff b_d{};          // k_de * Tustin derivative gain, A/um
  AccCoeff in_xi0{};       // k_xi0 T, A/(um tick)
  AccCoeff in_r{};         // lambda T
  AccCoeff out_r[2]{};     // k_r1 / lambda, k_r2 / lambda
  AccCoeff eps{};          // 2 sin(w0 T / 2)
  AccCoeff E[3]{};         // eq (17) gains in the scaled states (A per A)
  Scalar effort_limit{};
};

// Gains in double, also used by tests to build the exact closed loop.
struct InternalModelDesign {
  double T = 0.0, eps = 0.0;
  double k_e = 0.0, k_de = 0.0;  // A/um, A s/um
  double k_xi[3] = {0.0, 0.0, 0.0};
  double E[3] = {0.0, 0.0, 0.0};
  double a_d = 0.0, b_d = 0.0;
};

template <typename Scalar>
struct InternalModelState {
  using Acc = typename numeric::ScalarTraits<Scalar>::Acc;
  Acc xi[3]{};           // scaled internal-model states s0, s1, s2 [A]
  Scalar prev_d_input{};  // derivative input at k-1, um
  Scalar derivative{};    // D at k-1, A
  Scalar last_output{};   // v at k-1, A
};

namespace detail {

// Solves M x = rhs (n <= 5) by Gaussian elimination with partial pivoting.
MAGLEV_CONFIG_CODE inline bool solve5(double M[5][5], double rhs[5], double x[5]) {
  constexpr int n = 5;
  for (int col = 0; col < n; ++col) {
    int piv = col;
    for (int r = col + 1; r < n; ++r) {
      if (std::fabs(M[r][col]) > std::fabs(M[piv][col])) piv = r;
    }
    if (M[piv][col] == 0.0) return false;
    for (int k = 0; k < n; ++k) {
      const double t = M[col][k];
      M[col][k] = M[piv][k];
      M[piv][k] = t;
    }
    const double t = rhs[col];
    rhs[col] = rhs[piv];
    rhs[piv] = t;
    for (int r = col + 1; r < n; ++r) {
      const double f = M[r][col] / M[col][col];
      for (int k = col; k < n; ++k) M[r][k] -= f * M[col][k];
      rhs[r] -= f * rhs[col];
    }
  }
  for (int r = n - 1; r >= 0; --r) {
    double s = rhs[r];
    for (int k = r + 1; k < n; ++k) s -= M[r][k] * x[k];
    x[r] = s / M[r][r];
  }
  return true;
}

MAGLEV_CONFIG_CODE inline void matmul5(const double A[5][5], const double B[5][5], double C[5][5]) {
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      double s = 0.0;
      for (int k = 0; k < 5; ++k) s += A[i][k] * B[k][j];
      C[i][j] = s;
    }
  }
}

// Exact ZOH of x' = [[0,1],[-k,-c]] x + [0,g] u over T: the 3x3 augmented
// exponential expm([[A, B], [0, 0]] T) by scaling-and-squaring + Taylor.
MAGLEV_CONFIG_CODE inline void zoh2(double k, double c, double g, double T, double Ad[2][2], double Bd[2]) {
  double M[3][3] = {{0.0, T, 0.0}, {-k * T, -c * T, g * T}, {0.0, 0.0, 0.0}};
  int squarings = 0;
  double norm = std::fabs(k * T) + std::fabs(c * T) + std::fabs(g * T) + T;
  while (norm > 0.5) {
    norm *= 0.5;
    ++squarings;
  }
  const double scale = std::ldexp(1.0, -squarings);
  for (auto& row : M) {
    for (double& v : row) v *= scale;
  }
  double E[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  double term[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int n = 1; n < 20; ++n) {
    double nt[3][3] = {};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        for (int q = 0; q < 3; ++q) nt[i][j] += term[i][q] * M[q][j];
        nt[i][j] /= n;
      }
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        term[i][j] = nt[i][j];
        E[i][j] += nt[i][j];
      }
    }
  }
  for (int s = 0; s < squarings; ++s) {
    double sq[3][3] = {};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        for (int q = 0; q < 3; ++q) sq[i][j] += E[i][q] * E[q][j];
      }
    }
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) E[i][j] = sq[i][j];
    }
  }
  Ad[0][0] = E[0][0];
  Ad[0][1] = E[0][1];
  Ad[1][0] = E[1][0];
  Ad[1][1] = E[1][1];
  Bd[0] = E[0][2];
  Bd[1] = E[1][2];
}

}  // namespace detail

// Normalised 5th-order Bessel poles (real, then pairs re +- j im).
inline constexpr double kBessel5Real = -0.9264;
inline constexpr double kBessel5Pairs[2][2] = {{-0.8516, 0.4427}, {-0.5906, 0.9072}};
inline constexpr double kBessel3Real = -0.9416;
inline constexpr double kBessel3Pair[2] = {-0.7456, 0.7114};

// Builds the augmented discrete model z = [y, y', xi0, r1, r2] (kernel units,
// e = -y for r = 0) and returns the state-feedback gains in double.
MAGLEV_CONFIG_CODE inline LoopDesignError design_internal_model_double(const InternalModelConfig& cfg, double servo_rate_Hz,
                                                    InternalModelDesign* out) {
  constexpr double kPi = 3.14159265358979323846;
  const double w0 = static_cast<double>(cfg.omega0_rad_s);
  const double g = static_cast<double>(cfg.plant_gain) * 1e6;  // um/s^2 per A
  const double cp = static_cast<double>(cfg.plant_damping_per_s);
  const double kp = static_cast<double>(cfg.plant_stiffness_per_s2);
  const double wc = 2.0 * kPi * static_cast<double>(cfg.bandwidth_Hz);
  const double wim = 2.0 * kPi * static_cast<double>(cfg.internal_model_bandwidth_Hz);
  const double wf_hz = static_cast<double>(cfg.derivative_filter_hz);
  const double tt = static_cast<double>(cfg.antiwindup_tracking_time_s);
  const double vals[] = {w0, g, cp, kp, wc, wim, wf_hz, tt, servo_rate_Hz};
  for (double v : vals) {
    if (!std::isfinite(v)) return LoopDesignError::kNonFinite;
  }
  if (servo_rate_Hz <= 0.0) return LoopDesignError::kBadServoRate;
  const double T = 1.0 / servo_rate_Hz;
  if (w0 <= 0.0 || w0 * T >= kPi) return LoopDesignError::kFilterAboveNyquist;
  if (wf_hz <= 0.0 || wf_hz >= 0.5 * servo_rate_Hz) return LoopDesignError::kFilterAboveNyquist;
  if (wc <= 0.0 || wim <= 0.0 || wc * T >= 1.0 || wim * T >= 1.0 || g == 0.0) return LoopDesignError::kUnstableDesign;
  if (tt < T) return LoopDesignError::kBadTrackingTime;

  double Ap[2][2];
  double Bp[2];
  detail::zoh2(kp, cp, g, T, Ap, Bp);
  const double eps = 2.0 * numeric::dsin(0.5 * w0 * T);
  // Augmented A, B (e = -y).
  double A[5][5] = {
      {Ap[0][0], Ap[0][1], 0, 0, 0},
      {Ap[1][0], Ap[1][1], 0, 0, 0},
      {-T, 0, 1, 0, 0},
      {0, 0, 0, 1, eps},
      {-T, 0, 0, -eps, 1 - eps * eps},
  };
  const double B[5] = {Bp[0], Bp[1], 0, 0, 0};
  // Controllability matrix columns A^i B.
  double Ctrl[5][5];
  double col[5] = {B[0], B[1], B[2], B[3], B[4]};
  for (int i = 0; i < 5; ++i) {
    for (int r = 0; r < 5; ++r) Ctrl[r][i] = col[r];
    double next[5] = {};
    for (int r = 0; r < 5; ++r) {
      for (int q = 0; q < 5; ++q) next[r] += A[r][q] * col[q];
    }
    for (int r = 0; r < 5; ++r) col[r] = next[r];
  }
  // Desired closed-loop poles (continuous), then z = exp(s T), in two
  // groups, as paper 002's LQR result also has them (one fast group, slow
  // poles near w0):
  //  * the plant pair: a stable, damped plant (z, theta_x/y with the
  //    identified suspension, eqs (29)-(31)) keeps its own two poles, so the
  //    regulator adds no stiffness of its own (a placement below the 56 Hz
  //    suspension mode would need NEGATIVE stiffness); a double integrator
  //    (x, y, theta_z) gets w_c (-0.866 +- 0.5 j) (zeta = 0.87);
  //  * the internal model's three poles: 3rd-order Bessel set scaled by
  //    w_im. Keeping them slow (near w0) puts them next to the slow zeros the
  //    internal model brings into the reference response, so their residues
  //    are small: placing all five poles at w_c gives 60-80 % step overshoot.
  double real_poles[5];
  double pairs[2][2];  // re, im (continuous)
  int n_real = 0, n_pairs = 0;
  const double disc = cp * cp - 4.0 * kp;
  if (kp > 0.0 && cp > 0.0) {
    if (disc >= 0.0) {
      real_poles[n_real++] = 0.5 * (-cp + std::sqrt(disc));
      real_poles[n_real++] = 0.5 * (-cp - std::sqrt(disc));
    } else {
      pairs[n_pairs][0] = -0.5 * cp;
      pairs[n_pairs][1] = 0.5 * std::sqrt(-disc);
      ++n_pairs;
    }
  } else {
    pairs[n_pairs][0] = -0.8660 * wc;
    pairs[n_pairs][1] = 0.5 * wc;
    ++n_pairs;
  }
  real_poles[n_real++] = kBessel3Real * wim;
  pairs[n_pairs][0] = kBessel3Pair[0] * wim;
  pairs[n_pairs][1] = kBessel3Pair[1] * wim;
  ++n_pairs;
  double phi[5][5] = {{1, 0, 0, 0, 0}, {0, 1, 0, 0, 0}, {0, 0, 1, 0, 0}, {0, 0, 0, 1, 0}, {0, 0, 0, 0, 1}};
  for (int p = 0; p < n_real; ++p) {
    const double z = numeric::dexp(real_poles[p] * T);
    double F[5][5];
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) F[i][j] = A[i][j] - (i == j ? z : 0.0);
    }
    double tmp[5][5];
    detail::matmul5(phi, F, tmp);
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) phi[i][j] = tmp[i][j];
    }
  }
  for (int p = 0; p < n_pairs; ++p) {
    const double mag = numeric::dexp(pairs[p][0] * T);
    const double re = mag * numeric::dcos(pairs[p][1] * T);
    double A2[5][5];
    detail::matmul5(A, A, A2);
    double F[5][5];
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) F[i][j] = A2[i][j] - 2.0 * re * A[i][j] + (i == j ? mag * mag : 0.0);
    }
    double tmp[5][5];
    detail::matmul5(phi, F, tmp);
    for (int i = 0; i < 5; ++i) {
      for (int j = 0; j < 5; ++j) phi[i][j] = tmp[i][j];
    }
  }
  // w^T = e5^T Ctrl^-1  <=>  Ctrl^T w = e5.
  double CtT[5][5];
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) CtT[i][j] = Ctrl[j][i];
  }
  double rhs[5] = {0, 0, 0, 0, 1};
  double w[5];
  if (!detail::solve5(CtT, rhs, w)) return LoopDesignError::kUnstableDesign;
  double K[5];  // u = -K z
  for (int j = 0; j < 5; ++j) {
    double s = 0.0;
    for (int i = 0; i < 5; ++i) s += w[i] * phi[i][j];
    K[j] = s;
  }
  for (double v : K) {
    if (!std::isfinite(v)) return LoopDesignError::kUnstableDesign;
  }
  InternalModelDesign d;
  d.T = T;
  d.eps = eps;
  d.k_e = K[0];     // u = -K0 y = K0 e
  d.k_de = K[1];    // u = -K1 y'
  d.k_xi[0] = -K[2];
  d.k_xi[1] = -K[3];
  d.k_xi[2] = -K[4];
  const double n2 = d.k_xi[0] * d.k_xi[0] + d.k_xi[1] * d.k_xi[1] + d.k_xi[2] * d.k_xi[2];
  for (int i = 0; i < 3; ++i) d.E[i] = n2 > 0.0 ? (T / tt) * d.k_xi[i] / n2 : 0.0;
  // Plain Tustin (no prewarp): matches the continuous filter below crossover.
  const double wf_d = 2.0 * kPi * wf_hz;
  d.a_d = (2.0 - wf_d * T) / (2.0 + wf_d * T);
  d.b_d = d.k_de * 2.0 * wf_d / (2.0 + wf_d * T);
  *out = d;
  return LoopDesignError::kOk;
}

template <typename Scalar>
MAGLEV_CONFIG_CODE LoopDesignError design_internal_model(const InternalModelConfig& cfg, double servo_rate_Hz,
                                      InternalModelCoefficients<Scalar>* out) {
  using Traits = numeric::ScalarTraits<Scalar>;
  const double bw = static_cast<double>(cfg.setpoint_weight_p);
  const double cw = static_cast<double>(cfg.setpoint_weight_d);
  const double lim = static_cast<double>(cfg.effort_limit_A);
  if (!std::isfinite(bw) || !std::isfinite(cw) || !std::isfinite(lim)) return LoopDesignError::kNonFinite;
  if (bw < 0.0 || bw > 1.0 || cw < 0.0 || cw > 1.0) return LoopDesignError::kBadSetpointWeight;
  if (lim <= 0.0 || lim >= Traits::kMaxMagnitude) return LoopDesignError::kBadLimit;
  InternalModelDesign d;
  const LoopDesignError err = design_internal_model_double(cfg, servo_rate_Hz, &d);
  if (err != LoopDesignError::kOk) return err;
  const double lambda = std::sqrt(d.k_xi[1] * d.k_xi[1] + d.k_xi[2] * d.k_xi[2]);
  const double in_xi0 = d.k_xi[0] * d.T;
  const double in_r = lambda * d.T;
  const double out1 = lambda > 0.0 ? d.k_xi[1] / lambda : 0.0;
  const double out2 = lambda > 0.0 ? d.k_xi[2] / lambda : 0.0;
  const double E0 = d.k_xi[0] * d.E[0], E1 = lambda * d.E[1], E2 = lambda * d.E[2];
  const double step_gain = d.k_e * (1.0 - bw);
  const double all[] = {d.k_e, step_gain, d.a_d, d.b_d, in_xi0, in_r, out1, out2, d.eps, E0, E1, E2};
  for (double v : all) {
    if (!Traits::coeff_fits(v)) return LoopDesignError::kCoefficientOutOfRange;
  }
  InternalModelCoefficients<Scalar> c;
  c.k_e = Traits::acc_coeff_from_double(d.k_e);
  c.step_gain = Traits::acc_coeff_from_double(step_gain);
  c.c = Traits::coeff_from_double(cw);
  c.a_d = Traits::acc_coeff_from_double(d.a_d);
  c.b_d = Traits::acc_coeff_from_double(d.b_d);
  c.in_xi0 = Traits::acc_coeff_from_double(in_xi0);
  c.in_r = Traits::acc_coeff_from_double(in_r);
  c.out_r[0] = Traits::acc_coeff_from_double(out1);
  c.out_r[1] = Traits::acc_coeff_from_double(out2);
  c.eps = Traits::acc_coeff_from_double(d.eps);
  c.E[0] = Traits::acc_coeff_from_double(E0);
  c.E[1] = Traits::acc_coeff_from_double(E1);
  c.E[2] = Traits::acc_coeff_from_double(E2);
  c.effort_limit = Traits::from_double(lim);
  *out = c;
  return LoopDesignError::kOk;
}

// Same per-tick API as Pid2Dof, so the controller can hold either.
template <typename Scalar>
class InternalModelRegulator {
 public:
  using Traits = numeric::ScalarTraits<Scalar>;
  using Terms = LoopTerms<Scalar>;
  using Config = InternalModelConfig;
  using Coefficients = InternalModelCoefficients<Scalar>;
  using State = InternalModelState<Scalar>;

  InternalModelRegulator(const Coefficients* coefficients, State* state) : c_(coefficients), s_(state) {}

  // Same contract as Pid2Dof::update: e = r - y, explicit step of this tick.
  Scalar update(Scalar error_um, Scalar reference_step_um, Scalar feedforward_A) {
    const Coefficients& c = *c_;
    State& s = *s_;
    const Scalar e = error_um;
    Terms::weight_step(s.xi[0], s.prev_d_input, c.step_gain, c.c, reference_step_um);
    // Output from the current internal-model state (eq (16)).
    auto v = s.xi[0];
    v += Traits::acc_mul(s.xi[1], c.out_r[0]);
    v += Traits::acc_mul(s.xi[2], c.out_r[1]);
    Terms::filtered_derivative(s.derivative, s.prev_d_input, c.a_d, c.b_d, e);
    s.last_output = Terms::output(v, c.k_e, e, s.derivative, feedforward_A);  // + k_e e, one rounding
    // Advance the internal model (eq (14), exact discrete poles).
    Traits::mac(s.xi[0], c.in_xi0, e);
    s.xi[1] += Traits::acc_mul(s.xi[2], c.eps);
    s.xi[2] -= Traits::acc_mul(s.xi[1], c.eps);
    Traits::mac(s.xi[2], c.in_r, e);
    return s.last_output;
  }

  Scalar saturate(Scalar v) const { return numeric::clamp_abs(v, c_->effort_limit); }

  // Eq (17): xi += E (u_applied - v).
  void apply_limit(Scalar applied_effort_A) {
    const Scalar diff = applied_effort_A - s_->last_output;
    for (int i = 0; i < 3; ++i) Traits::mac(s_->xi[i], c_->E[i], diff);
  }

  void reset(Scalar error_um = Traits::zero()) {
    State& s = *s_;
    for (auto& x : s.xi) x = Traits::acc_zero();
    s.prev_d_input = error_um;
    s.derivative = Traits::zero();
    s.last_output = Traits::zero();
  }

  const Coefficients& coefficients() const { return *c_; }
  const State& state() const { return *s_; }

 private:
  const Coefficients* c_;
  State* s_;
};

}  // namespace maglev::kernel
