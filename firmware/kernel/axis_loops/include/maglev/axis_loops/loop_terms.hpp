// The per-tick terms Pid2Dof and InternalModelRegulator share -- one
// implementation, so both loops round the same way in float and Q7.24:
//   weight_step()          2-DOF setpoint weighting of an explicit reference
//                          step: -(1-b) k * step into the accumulator that
//                          carries it (PID integrator / regulator s0), and the
//                          derivative's input history moved by (1-c) * step,
//                          so output steps get full P and D, reference steps
//                          only b and c of them;
//   filtered_derivative()  D_k = a_d D_{k-1} + b_d (e_k - e_{k-1}) (Tustin,
//                          first-order filtered), one rounding of the exact
//                          sum in fixed point (Fixed::mul_sum2);
//   finish_output()        v + D + u_ff in the wide accumulator, one rounding;
//   output()               acc + k e + D + u_ff: in fixed point the exact
//                          sum, rounded once.
// The anti-windup (apply_limit) is NOT shared: the PID back-calculates one
// integrator with gain T/Tt, the regulator feeds E (u - v) into all three
// model states (paper 002 eq (17)).
#pragma once

#include <cstdint>

#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

template <typename Scalar>
struct LoopTerms {
  using Traits = numeric::ScalarTraits<Scalar>;
  using Acc = typename Traits::Acc;
  using Coeff = typename Traits::Coeff;

  // G, C: Coeff or the traits' AccCoeff (a gain held for the accumulator).
  template <typename G>
  static void weight_step(Acc& state, Scalar& prev_d_input, G one_minus_b_gain, Coeff c, Scalar step) {
    // Almost every tick has no explicit step: a zero step adds an exact zero
    // to both states (the caller's zero is +0, so no signed zero changes
    // either), so skipping it keeps every bit (issue 16).
    if (step == Traits::zero()) return;
    Traits::mac(state, one_minus_b_gain, -step);
    prev_d_input += step - Traits::mul(c, step);
  }

  template <typename C>
  static void filtered_derivative(Scalar& derivative, Scalar& prev_d_input, C a_d, C b_d, Scalar e) {
    derivative = Traits::mul_sum2(a_d, derivative, b_d, e - prev_d_input);
    prev_d_input = e;
  }

  // v = acc + k e + D + u_ff. Fixed point, whenever |acc| < 2^40 raw (256 A;
  // the PID bounds its integrator to 64 A): the exact sum in Q52 (acc 2^20,
  // k e, (D + u_ff) 2^28: below 2^62 + 2^61), rounded once to the Scalar. The
  // general form (mac, then finish_output) rounds k e to the accumulator first.
  template <typename C>
  static Scalar output(Acc acc, C k, Scalar e, Scalar derivative, Scalar feedforward) {
    if constexpr (Traits::kIsFixed) {
      constexpr int kAccToProduct = Coeff::kFracBits + Scalar::kFracBits - Acc::kFracBits;  // 20
      constexpr int kScalarToProduct = Coeff::kFracBits;                                     // 28
      static_assert(kAccToProduct >= 0 && kAccToProduct <= 22 && kScalarToProduct <= 28);
      const std::int64_t raw = acc.raw();
      if (static_cast<std::uint64_t>(raw) + (std::uint64_t{1} << 40) < (std::uint64_t{1} << 41)) {
        const std::int64_t sum = raw * (std::int64_t{1} << kAccToProduct) + std::int64_t{k.raw()} * e.raw() +
                                 (std::int64_t{derivative.raw()} + feedforward.raw()) * (std::int64_t{1} << kScalarToProduct);
        return Scalar::template round_product_sum<Coeff::kFracBits>(sum);
      }
    }
    Traits::mac(acc, k, e);
    return finish_output(acc, derivative, feedforward);
  }

  static Scalar finish_output(Acc v, Scalar derivative, Scalar feedforward) {
    v += Traits::acc_from_scalar(derivative);
    v += Traits::acc_from_scalar(feedforward);
    return Traits::acc_to_scalar(v);
  }
};

}  // namespace maglev::kernel
