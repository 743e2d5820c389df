// Two-degree-of-freedom PID with filtered derivative and back-calculation
// anti-windup: the paper-000 controllers (27), (28), (32), (33),
//   u = kp (b r - y) + ki/s (r - y) + kd s / (1 + s/wf) (c r - y) + u_ff
// (b, c weighting reference steps only, see below),
// discretized at the servo rate T = 1/fs when the Config is applied:
//   P  : kp e_k
//   I  : Tustin, I_k = I_{k-1} + (ki T / 2)(e_k + e_{k-1}) + (T/Tt)(u_applied - v)
//   D  : Tustin (not prewarped, see design_pid2dof),
//        D_k = a_d D_{k-1} + b_d (e_k - e_{k-1}),
//        a_d = (2 - wf T)/(2 + wf T),  b_d = 2 kd wf / (2 + wf T).
// So, without steps (or b = c = 1), the loop's exact discrete transfer function e -> v is
//   C(z) = kp + (ki T/2)(z+1)/(z-1) + b_d (z-1)/(z-a_d).
//
// Units: Config gains are the paper's SI gains (A/m, A/(m s), A s/m, or per
// rad); the kernel works in um (urad), so every gain is scaled by 1e-6 at
// design time (kp_kernel [A/um] = kp [A/m] * 1e-6).
//
// WHY the inputs are an error and a step, not r and y: positions are 64-bit
// (pm, prad) and only errors fit a Scalar (+-128 um). The textbook form
// kp (b r - y) needs absolute r and y, and applied to a profiled move it
// would also leave a ramp error (1-b) kp/ki v (2.3 mm at 0.26 m/s for x).
// So the setpoint weights act on explicit reference STEPS only: each tick
// the caller passes e = r - y (whole reference: profile + steps) and the
// step the step-reference generator applied THIS tick (0 otherwise). The
// loop injects the step's un-weighted part into its states:
//   I -= kp (1-b) dr,   D-input history += (1-c) dr,
// which is exactly the textbook 2-DOF response to a step of dr (a change of
// state coordinates: the same output at every tick), with states that stay
// bounded however far the stage travels.
//
// Per tick, the caller (kernel::Controller) does:
//   v = pid.update(error_um, reference_step_um, ff_A);  // unsaturated effort
//   u = pid.saturate(v) ... allocator current-limit scaling ... -> u_applied
//   pid.apply_limit(u_applied);         // back-calculation (zero if u == v)
#pragma once

#include "maglev/io/code_placement.hpp"
#include <cmath>

#include "maglev/io/axis.hpp"
#include "maglev/axis_loops/design_error.hpp"
#include "maglev/axis_loops/loop_terms.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

// Plain SI floats: what Modbus and persistence see.
struct Pid2DofConfig {
  float kp = 0.0f;                        // A/m   (A/rad)
  float ki = 0.0f;                        // A/(m s)
  float kd = 0.0f;                        // A s/m
  float derivative_filter_hz = 1000.0f;   // wf/(2 pi); ignored when kd == 0
  float setpoint_weight_p = 1.0f;         // b in [0, 1]
  float setpoint_weight_d = 0.0f;         // c in [0, 1]
  float antiwindup_tracking_time_s = 0.0f;  // Tt (back-calculation); must be >= T
  float effort_limit_A = 4.0f;            // symmetric clamp of saturate()
};

// Discrete coefficients, computed in double at apply time, stored as Coeff.
// The gains that enter only the accumulator's MACs are AccCoeff (the float
// kernel holds its float values as double: ScalarTraits<float>::AccCoeff).
template <typename Scalar>
struct Pid2DofCoefficients {
  using Traits = numeric::ScalarTraits<Scalar>;
  using Coeff = typename Traits::Coeff;
  using AccCoeff = typename Traits::AccCoeff;
  AccCoeff kp{};            // A/um
  AccCoeff one_minus_b_kp{};  // (1 - b) kp, A/um: step weighting
  Coeff c{};                // setpoint weight, D (on steps)
  AccCoeff ki_half_T{};     // ki T / 2, A/(um tick)
  AccCoeff antiwindup{};    // T / Tt
  AccCoeff a_d{};           // derivative filter pole
  AccCoeff b_d{};           // derivative gain, A/um
  Scalar effort_limit{};  // A
};

template <typename Scalar>
struct Pid2DofState {
  using Acc = typename numeric::ScalarTraits<Scalar>::Acc;
  Acc integrator{};     // A
  Scalar prev_error{};  // e_{k-1}, um
  Scalar prev_d_input{};  // derivative input at k-1, um
  Scalar derivative{};  // D_{k-1}, A
  Scalar last_output{};  // v_{k-1}, unsaturated, A
};

// Config -> coefficients. On error *out is left untouched.
template <typename Scalar>
MAGLEV_CONFIG_CODE LoopDesignError design_pid2dof(const Pid2DofConfig& config, double servo_rate_Hz, Pid2DofCoefficients<Scalar>* out) {
  using Traits = numeric::ScalarTraits<Scalar>;
  const double kp = static_cast<double>(config.kp);
  const double ki = static_cast<double>(config.ki);
  const double kd = static_cast<double>(config.kd);
  const double wf_hz = static_cast<double>(config.derivative_filter_hz);
  const double bw = static_cast<double>(config.setpoint_weight_p);
  const double cw = static_cast<double>(config.setpoint_weight_d);
  const double tt = static_cast<double>(config.antiwindup_tracking_time_s);
  const double lim = static_cast<double>(config.effort_limit_A);
  const double all[] = {kp, ki, kd, wf_hz, bw, cw, tt, lim, servo_rate_Hz};
  for (double v : all) {
    if (!std::isfinite(v)) return LoopDesignError::kNonFinite;
  }
  if (servo_rate_Hz <= 0.0) return LoopDesignError::kBadServoRate;
  if (kp < 0.0 || ki < 0.0 || kd < 0.0) return LoopDesignError::kNegativeGain;
  if (bw < 0.0 || bw > 1.0 || cw < 0.0 || cw > 1.0) return LoopDesignError::kBadSetpointWeight;
  if (lim <= 0.0 || lim >= Traits::kMaxMagnitude) return LoopDesignError::kBadLimit;
  const double T = 1.0 / servo_rate_Hz;
  double a_d = 0.0;
  double b_d = 0.0;
  if (kd > 0.0) {
    if (wf_hz <= 0.0 || wf_hz >= 0.5 * servo_rate_Hz) return LoopDesignError::kFilterAboveNyquist;
    constexpr double kPi = 3.14159265358979323846;
    // Plain Tustin, NOT prewarped: below crossover the discrete D term then
    // matches kd s/(1+s/wf) to (wT)^2/12 (prewarping a corner this close to
    // Nyquist would shift the low-frequency response by 2 % at 50 Hz). The
    // 1 kHz corner lands at (2/T) atan(wf T/2) = 715 Hz.
    const double wf_d = 2.0 * kPi * wf_hz;
    a_d = (2.0 - wf_d * T) / (2.0 + wf_d * T);
    b_d = 2.0 * kd * 1e-6 * wf_d / (2.0 + wf_d * T);
  }
  double aw = 0.0;
  if (ki > 0.0) {
    if (tt < T) return LoopDesignError::kBadTrackingTime;
    aw = T / tt;
  }
  const double kp_k = kp * 1e-6;
  const double ki_half_T = ki * 1e-6 * T / 2.0;
  const double coeffs[] = {kp_k, ki_half_T, a_d, b_d, aw, bw, cw};
  for (double v : coeffs) {
    if (!Traits::coeff_fits(v)) return LoopDesignError::kCoefficientOutOfRange;
  }
  Pid2DofCoefficients<Scalar> c;
  c.kp = Traits::acc_coeff_from_double(kp_k);
  c.one_minus_b_kp = Traits::acc_coeff_from_double((1.0 - bw) * kp_k);
  c.c = Traits::coeff_from_double(cw);
  c.ki_half_T = Traits::acc_coeff_from_double(ki_half_T);
  c.antiwindup = Traits::acc_coeff_from_double(aw);
  c.a_d = Traits::acc_coeff_from_double(a_d);
  c.b_d = Traits::acc_coeff_from_double(b_d);
  c.effort_limit = Traits::from_double(lim);
  *out = c;
  return LoopDesignError::kOk;
}

template <typename Scalar>
class Pid2Dof {
 public:
  using Traits = numeric::ScalarTraits<Scalar>;
  using Terms = LoopTerms<Scalar>;
  using Config = Pid2DofConfig;
  using Coefficients = Pid2DofCoefficients<Scalar>;
  using State = Pid2DofState<Scalar>;

  // The loop is a view: coefficients and state are caller-owned (static).
  Pid2Dof(const Coefficients* coefficients, State* state) : c_(coefficients), s_(state) {}

  // One servo tick. error_um = r - y (um or urad); reference_step_um = the
  // explicit step applied to the reference this tick (0 for profiled moves),
  // weighted by b and c. Returns the unsaturated effort v (A) incl. u_ff.
  Scalar update(Scalar error_um, Scalar reference_step_um, Scalar feedforward_A) {
    const Coefficients& c = *c_;
    State& s = *s_;
    const Scalar e = error_um;
    // Setpoint weighting of the step (see header comment).
    Terms::weight_step(s.integrator, s.prev_d_input, c.one_minus_b_kp, c.c, reference_step_um);
    // Integral: Tustin, held while the error is at the Scalar's limit
    // (+-128 um / urad, pico_to_micro): there the error no longer grows with
    // the position, the proportional term is stuck and the derivative sees no
    // motion, and an integrator fed the clipped error only ramps -- a loop
    // the supervisor's following-error limits (above 128) let run; a 0.1 A
    // theta_z excitation's fault landing oscillated with growing amplitude
    // until the currents went off (2026-11-29, docs/PERFORMANCE.md "Lab tools").
    // Below the limit (every tick of a normal run) the same MAC as before.
    if (Traits::inside_limit(e)) Traits::mac_sum(s.integrator, c.ki_half_T, e, s.prev_error);
    s.prev_error = e;
    // Derivative, first-order filtered, on e minus the (1-c) part of steps.
    Terms::filtered_derivative(s.derivative, s.prev_d_input, c.a_d, c.b_d, e);
    // I + kp e + D + u_ff, one rounding (LoopTerms::output).
    s.last_output = Terms::output(s.integrator, c.kp, e, s.derivative, feedforward_A);
    return s.last_output;
  }

  // Symmetric clamp at the configured effort limit.
  Scalar saturate(Scalar v) const { return numeric::clamp_abs(v, c_->effort_limit); }

  // Back-calculation: tell the loop what was really applied this tick.
  // The integrator is also bounded to half the Scalar range (64 A), a pure
  // overflow guard; the anti-windup proper is the back-calculation.
  void apply_limit(Scalar applied_effort_A) {
    State& s = *s_;
    // Nothing cut (most ticks): the correction is an exact zero, and adding
    // it would leave the integrator as it is (it is never -0: it starts at a
    // +0 or a preset and only nonzero terms reach it), so it is skipped.
    const Scalar cut = applied_effort_A - s.last_output;
    if (!(cut == Traits::zero())) Traits::mac(s.integrator, c_->antiwindup, cut);
    const auto lim = Traits::acc_from_double(0.5 * Traits::kMaxMagnitude);
    if constexpr (!Traits::kIsFixed) {
      // VMAXNM + VMINNM (the two compares and selects were ~12 M7
      // instructions an axis): the same value for every integrator that is a
      // number. A NaN one would become -64 A instead of staying NaN; none can
      // arise (e is an int64 difference, every other term is bounded).
      s.integrator = __builtin_fmin(__builtin_fmax(s.integrator, -lim), lim);
    } else {
      if (lim < s.integrator) s.integrator = lim;
      if (s.integrator < -lim) s.integrator = -lim;
    }
  }

  // (Re)start: zero history, integrator preset (e.g. a dc lift in A), and
  // the current error so the first tick has no derivative or Tustin kick.
  void reset(Scalar integrator_A = Traits::zero(), Scalar error_um = Traits::zero()) {
    State& s = *s_;
    s.integrator = Traits::acc_from_scalar(integrator_A);
    s.prev_error = error_um;
    s.prev_d_input = error_um;
    s.derivative = Traits::zero();
    s.last_output = integrator_A;
  }

  const Coefficients& coefficients() const { return *c_; }
  const State& state() const { return *s_; }

 private:
  const Coefficients* c_;
  State* s_;
};

}  // namespace maglev::kernel
