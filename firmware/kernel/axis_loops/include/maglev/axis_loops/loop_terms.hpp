// The per-tick terms Pid2Dof and InternalModelRegulator share -- one
// implementation, so both loops round the same way in float and Q7.24:
//   weight_step()          2-DOF setpoint weighting of an explicit reference
//                          step: -(1-b) k * step into the accumulator that
//                          carries it (PID integrator / regulator s0), and the
//                          derivative's input history moved by (1-c) * step,
//                          so output steps get full P and D, reference steps
//                          only b and c of them;
//   filtered_derivative()  D_k = a_d D_{k-1} + b_d (e_k - e_{k-1}) (Tustin,
//                          first-order filtered), one rounding;
//   finish_output()        v + D + u_ff in the wide accumulator, one rounding.
// The anti-windup (apply_limit) is NOT shared: the PID back-calculates one
// integrator with gain T/Tt, the regulator feeds E (u - v) into all three
// model states (paper 002 eq (17)).
#pragma once

#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

template <typename Scalar>
struct LoopTerms {
  using Traits = numeric::ScalarTraits<Scalar>;
  using Acc = typename Traits::Acc;
  using Coeff = typename Traits::Coeff;

  static void weight_step(Acc& state, Scalar& prev_d_input, Coeff one_minus_b_gain, Coeff c, Scalar step) {
    // Almost every tick has no explicit step: a zero step adds an exact zero
    // to both states (the caller's zero is +0, so no signed zero changes
    // either), so skipping it keeps every bit (issue 16).
    if (step == Traits::zero()) return;
    Traits::mac(state, one_minus_b_gain, -step);
    prev_d_input += step - Traits::mul(c, step);
  }

  static void filtered_derivative(Scalar& derivative, Scalar& prev_d_input, Coeff a_d, Coeff b_d, Scalar e) {
    auto d = Traits::acc_zero();
    Traits::mac(d, a_d, derivative);
    Traits::mac(d, b_d, e - prev_d_input);
    derivative = Traits::acc_to_scalar(d);
    prev_d_input = e;
  }

  static Scalar finish_output(Acc v, Scalar derivative, Scalar feedforward) {
    v += Traits::acc_from_scalar(derivative);
    v += Traits::acc_from_scalar(feedforward);
    return Traits::acc_to_scalar(v);
  }
};

}  // namespace maglev::kernel
