// One axis' loop as the controller runs it: the 2-DOF PID or the
// internal-model regulator, whichever the configuration selected. THE one
// place that dispatches on LoopType (visit); everything the controller does
// with a loop -- update, saturate, reset, anti-windup, last output -- goes
// through it. A view over coefficients and state held elsewhere (moteus
// style: storage outside), so it costs nothing to make one per tick.
#pragma once

#include <type_traits>

#include "maglev/axis_loops/defaults.hpp"
#include "maglev/axis_loops/internal_model.hpp"
#include "maglev/axis_loops/pid2dof.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

// kPidOnly: the caller knows every axis runs the 2-DOF PID (the
// configuration's usual case): the type tests compile out (three per axis
// and tick, ~50 M7 instructions a tick over the six axes, issue 16). The
// same calls on the same loop, so the same bits either way.
template <typename Scalar, bool kPidOnly = false>
class AxisLoop {
 public:
  AxisLoop(LoopType type, const Pid2DofCoefficients<Scalar>* pid, Pid2DofState<Scalar>* pid_state,
           const InternalModelCoefficients<Scalar>* imr, InternalModelState<Scalar>* imr_state)
      : type_(type), pid_(pid), pid_state_(pid_state), imr_(imr), imr_state_(imr_state) {}

  // One loop tick on the error e (um or urad), this tick's explicit step and
  // the feed-forward (A): the loop output before the biquads.
  Scalar update(Scalar e_um, Scalar step_um, Scalar ff_A) {
    return visit([&](auto loop) { return loop.update(e_um, step_um, ff_A); });
  }
  // The loop's own effort clamp.
  Scalar saturate(Scalar v) const {
    return numeric::clamp_abs(v, internal_model() ? imr_->effort_limit : pid_->effort_limit);
  }
  // Back-calculation: what was really applied.
  void apply_limit(Scalar applied_A) {
    visit([&](auto loop) { loop.apply_limit(applied_A); });
  }
  // An open axis: state reset on the present error (bumpless closing).
  void reset(Scalar e_um) {
    visit([&](auto loop) {
      if constexpr (std::is_same_v<decltype(loop), Pid2Dof<Scalar>>) {
        loop.reset(numeric::ScalarTraits<Scalar>::zero(), e_um);
      } else {
        loop.reset(e_um);
      }
    });
  }
  Scalar last_output() const {
    return internal_model() ? imr_state_->last_output : pid_state_->last_output;
  }

 private:
  bool internal_model() const {
    if constexpr (kPidOnly) {
      return false;
    } else {
      return type_ == LoopType::kInternalModel;
    }
  }
  template <typename F>
  decltype(auto) visit(F&& f) {
    if constexpr (!kPidOnly) {
      if (type_ == LoopType::kInternalModel) return f(InternalModelRegulator<Scalar>(imr_, imr_state_));
    }
    return f(Pid2Dof<Scalar>(pid_, pid_state_));
  }
  LoopType type_;
  const Pid2DofCoefficients<Scalar>* pid_;
  Pid2DofState<Scalar>* pid_state_;
  const InternalModelCoefficients<Scalar>* imr_;
  InternalModelState<Scalar>* imr_state_;
};

}  // namespace maglev::kernel
