#pragma once
// Rigid-body model (5)-(7) of paper 002 with the linear guides, integrated by
// RK4 at a fixed step. State x1..x10 as Table II (stored 0-based):
//   x[0] gap x1 [m], x[1] its rate, x[2] X x3 [m], x[3], x[4] Z x5 [m], x[5],
//   x[6] phi x7 (about X) [rad], x[7], x[8] theta x9 (about Z) [rad], x[9].
// Motors 2 and 4 lie along X (their i_q is u_x), motors 1 and 3 along Z
// (i_q = u_z); gaps by (5). The guides: X, Y, Z translation carry different
// masses (M_x, M_y, M_z: each guide set carries the ones above it), yaw is
// blocked, and the four vertical guides add torsional springs k_s_phi,
// k_s_theta about X and Z (7). The guides' mechanical stops clamp the gap and
// the horizontal travel.
#include <array>
#include <cstdint>

#include "maglev/pmlsm_plant/amplifier.hpp"
#include "maglev/pmlsm_plant/force_law.hpp"
#include "maglev/pmlsm_plant/params.hpp"

namespace maglev::pmlsm_plant {

using State = std::array<double, 10>;
inline constexpr int kMotors = 4;

// Per-motor (i_d, i_q) actually flowing, index 0..3 = motors 1..4.
using MotorCurrents = std::array<DqCurrents, kMotors>;

// Air gaps g_1..g_4 from (5).
std::array<double, kMotors> AirGaps_m(const StageParams& p, const State& x);

// Right-hand side of (6)-(7) with the per-motor forces of (1)-(2); quadratic
// terms included (this is the plant, not the simplified model (11)).
State Derivative(const StageParams& p, const ForceConstants& k, const State& x, const MotorCurrents& i);

// Encoder outputs y = [x1 x3 x5 x7 x9], quantized (round to nearest count).
struct Measurement {
  std::array<double, 5> y{};
};
Measurement MeasureEncoders(const EncoderParams& e, const State& x);

class Plant {
 public:
  explicit Plant(const StageParams& p, const AmplifierParams& a = {}, const EncoderParams& e = {});

  void Reset(const State& x0) { x_ = x0; }
  const State& state() const { return x_; }
  const StageParams& params() const { return p_; }
  const ForceConstants& constants() const { return k_; }

  // Commands (i_d, i_q) for each motor through its amplifiers (commutation
  // and phase clamp), holds them for dt_s (zero-order hold, as the 1 kHz DAC
  // does) and advances the state by one RK4 step. Returns the delivered currents.
  MotorCurrents Step(const MotorCurrents& command, double dt_s);
  // The same from the phase currents a firmware's commutation commands (the
  // amplifiers' clamp, then the motor sees the Park transform at the TRUE
  // mover position): the bench's path, where the kernel commutates.
  MotorCurrents StepPhases(const std::array<PhaseCurrents, kMotors>& command, double dt_s);
  // Encoder counts of y = [x1 x3 x5 x7 x9] (round to nearest count).
  std::array<std::int32_t, 5> EncoderCounts() const;
  bool last_step_saturated() const { return saturated_; }

  Measurement Measure() const { return MeasureEncoders(e_, x_); }

 private:
  MotorCurrents Advance(const MotorCurrents& delivered, double dt_s);
  StageParams p_;
  AmplifierParams a_;
  EncoderParams e_;
  ForceConstants k_;
  State x_{};
  bool saturated_ = false;
};

}  // namespace maglev::pmlsm_plant
