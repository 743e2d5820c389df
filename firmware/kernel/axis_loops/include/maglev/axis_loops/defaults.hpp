// Per-axis loop configuration and the paper-000 defaults.
//
// PID gains are exactly eqs (27), (28), (32), (33). The choices the paper
// does not state, and why a precision engineer would start from them:
//  * derivative filter 1000 Hz (fs/2.5, prewarped): at the 49.8 Hz x/y
//    crossover it costs only atan(49.8/1000) = 2.9 deg of the 33.2 deg phase
//    margin, while bounding the high-frequency gain at kd*wf (noise).
//  * derivative on measurement only (c = 0): no derivative kick on steps.
//  * proportional setpoint weight b: the x/y loop (33.2 deg PM, 13 dB peak
//    at 44.9 Hz) overshoots 65 % on a step with b = 1 (simulated, 1-tick
//    computation delay). b = 0.4 gives 2.4 % on the 8 um step (spec
//    <= 3.25 %) and 2 % settling in 0.05 s (spec <= 0.32 s) without touching
//    the disturbance response. theta_z: b = 0.5 gives 0 % overshoot,
//    0.027 s. z (PI on an overdamped, stiff suspension): b = 1. theta_x/y:
//    b = 0.5 (same reasoning as theta_z).
//  * back-calculation Tt = sqrt(Ti Td) (Astrom & Hagglund), Ti = kp/ki,
//    Td = kd/kp; Tt = Ti for the PI of z.
//  * effort limits: 4 A (kPeakCoilCurrent_A) in-plane and tilt; 8 A for z,
//    which also carries the ~4.3 A dc lift (m g / 2b*). These are sanity
//    clamps: the allocator's coil-current scaling is the real limit and
//    reports back through apply_limit().
// Internal-model regulator (alternative, LoopType::kInternalModel): w0 =
// 1.5 pi rad/s (paper 002), plant pole pair at 20 Hz (x, y), 30 Hz (theta_z)
// or the identified suspension's own poles (z, theta_x/y); internal-model
// poles at 1.5 Hz (Bessel-3); Tt = 10 ms. Tracks a w0 sinusoid to the
// rounding floor, but a step overshoots ~21 % (the internal model's zeros):
// use the PID for the step experiments.
#pragma once

#include <cmath>

#include "maglev/io/axis.hpp"
#include "maglev/axis_loops/biquad.hpp"
#include "maglev/axis_loops/internal_model.hpp"
#include "maglev/axis_loops/pid2dof.hpp"
#include "maglev/io/stage_parameters.hpp"

namespace maglev::kernel {

enum class LoopType : std::uint8_t { kPid2Dof = 0, kInternalModel = 1 };

struct AxisLoopConfig {
  LoopType type = LoopType::kPid2Dof;
  std::uint8_t reserved[3] = {};  // explicit, always zero (see BiquadConfig::reserved)
  Pid2DofConfig pid;
  InternalModelConfig imr;
  BiquadConfig filters[kMaxBiquadStages];  // applied in series to the loop output
};

inline constexpr double kDefaultServoRate_Hz = io::stage::kServoRate_Hz;

// Plant of each axis, eqs (25), (26), (29)-(31): y'' + c' y' + k' y = g u.
struct AxisPlant {
  double gain;          // m/s^2 (rad/s^2) per A of effort
  double damping_per_s;
  double stiffness_per_s2;
};

constexpr AxisPlant axis_plant(Axis axis) {
  namespace s = io::stage;
  switch (axis) {
    case Axis::kX:
    case Axis::kY:
      return {s::kTwoBStarIdentified_N_per_A / s::kMass_kg, 0.0, 0.0};
    case Axis::kThetaZ:
      return {s::kTwoBStarIdentified_N_per_A / s::kIz_kgm2, 0.0, 0.0};
    case Axis::kZ:
      return {s::kTwoBStarIdentified_N_per_A / s::kMass_kg, s::kZDamping_Ns_per_m / s::kMass_kg,
              s::kZStiffness_N_per_m / s::kMass_kg};
    case Axis::kThetaX:
      return {s::kTwoBStarIdentified_N_per_A / s::kIx_kgm2, s::kTiltDamping_Nms_per_rad / s::kIx_kgm2,
              s::kTiltStiffness_Nm_per_rad / s::kIx_kgm2};
    case Axis::kThetaY:
      return {s::kTwoBStarIdentified_N_per_A / s::kIy_kgm2, s::kTiltDamping_Nms_per_rad / s::kIy_kgm2,
              s::kTiltStiffness_Nm_per_rad / s::kIy_kgm2};
  }
  return {0.0, 0.0, 0.0};
}

// Acceleration feed-forward gain: u_ff [A] = m a / (2 b*) = a / gain, in A
// per m/s^2 (A per rad/s^2 for rotations, with m -> I). Multiply the
// references' float acceleration by this.
constexpr double acceleration_feedforward_A_per_si(Axis axis) { return 1.0 / axis_plant(axis).gain; }

inline AxisLoopConfig default_axis_loop_config(Axis axis) {
  AxisLoopConfig c;
  float kp = 0, ki = 0, kd = 0, b = 1.0f, limit = 4.0f, imr_bw = 20.0f;
  switch (axis) {
    case Axis::kX:
    case Axis::kY:  // (27)
      kp = 36000.0f; ki = 2400000.0f; kd = 100.0f; b = 0.4f; imr_bw = 20.0f;
      break;
    case Axis::kThetaZ:  // (28)
      kp = 300.0f; ki = 24000.0f; kd = 1.0f; b = 0.5f; imr_bw = 30.0f;
      break;
    case Axis::kZ:  // (32)
      kp = 40000.0f; ki = 560000.0f; kd = 0.0f; b = 1.0f; limit = 8.0f; imr_bw = 5.0f;
      break;
    case Axis::kThetaX:
    case Axis::kThetaY:  // (33)
      kp = 70.0f; ki = 17600.0f; kd = 0.09f; b = 0.5f; imr_bw = 10.0f;
      break;
  }
  c.pid.kp = kp;
  c.pid.ki = ki;
  c.pid.kd = kd;
  c.pid.derivative_filter_hz = 1000.0f;
  c.pid.setpoint_weight_p = b;
  c.pid.setpoint_weight_d = 0.0f;
  const double ti = static_cast<double>(kp) / static_cast<double>(ki);
  const double td = static_cast<double>(kd) / static_cast<double>(kp);
  c.pid.antiwindup_tracking_time_s = static_cast<float>(kd > 0.0f ? std::sqrt(ti * td) : ti);
  c.pid.effort_limit_A = limit;

  const AxisPlant p = axis_plant(axis);
  c.imr.plant_gain = static_cast<float>(p.gain);
  c.imr.plant_damping_per_s = static_cast<float>(p.damping_per_s);
  c.imr.plant_stiffness_per_s2 = static_cast<float>(p.stiffness_per_s2);
  c.imr.bandwidth_Hz = imr_bw;
  c.imr.effort_limit_A = limit;
  return c;
}

}  // namespace maglev::kernel
