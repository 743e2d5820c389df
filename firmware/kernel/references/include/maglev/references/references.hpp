// Per-axis reference generators: explicit step, trapezoidal-velocity move,
// jerk-limited (S-curve) move, xy circle, sinusoid, stop.
//
// Output per tick (AxisReference):
//   position_pico      int64, 1 pm (lengths) or 1 prad (angles) per LSB,
//                      the 64-bit fixed-point position of docs/ARCHITECTURE.md
//   velocity           float, SI (m/s or rad/s)
//   acceleration       float, SI (m/s^2 or rad/s^2): the controller's
//                      feed-forward is u_ff = m a / (2 b*) (A)
//   step_pico          the explicit step applied at THIS tick (0 otherwise);
//                      pass it, converted to um, as Pid2Dof::update's
//                      reference_step_um so the setpoint weights act on it.
// Everything is a pure function of the tick index k (t = k / servo_rate):
// sample(k) may be called in any order and is bit-reproducible; the profile
// arithmetic is double (Cortex-M7 has a double FPU) with one rounding to pm.
// Profiles end EXACTLY on their target (the last samples are clamped to it).
//
// Every plan() validates the request against the caller's AxisReferenceLimits
// (max velocity, acceleration, jerk, max step, travel window) and returns an
// error code instead of a profile that would exceed them: the stage is never
// commanded beyond its limits. On error the generator is left idle (it keeps
// holding its previous hold position).
#pragma once

#include <cstdint>

namespace maglev::kernel {

enum class ReferenceError : std::uint8_t {
  kOk = 0,
  kNonFinite,          // NaN/inf in the request
  kBadParameter,       // non-positive limit/frequency/diameter, zero revolutions ...
  kVelocityLimit,      // the request needs more than max_velocity
  kAccelerationLimit,  // ... more than max_acceleration (incl. centripetal)
  kJerkLimit,          // ... more than max_jerk
  kStepTooLarge,       // |step| > max_step
  kOutsideTravel,      // start or any reached position outside the window
  kTooLong,            // duration beyond kMaxProfileTicks
};

// Longest profile: 2^31 ticks (9.9 days at 2.5 kHz).
inline constexpr std::int64_t kMaxProfileTicks = std::int64_t{1} << 31;

struct AxisReferenceLimits {
  double max_velocity = 0.0;      // m/s (rad/s), > 0
  double max_acceleration = 0.0;  // m/s^2 (rad/s^2), > 0
  double max_jerk = 0.0;          // m/s^3 (rad/s^3), > 0 (S-curve only)
  std::int64_t max_step_pico = 0;  // largest explicit step
  std::int64_t travel_min_pico = 0;
  std::int64_t travel_max_pico = 0;
};

struct AxisReference {
  std::int64_t position_pico = 0;
  float velocity = 0.0f;
  float acceleration = 0.0f;
  std::int64_t step_pico = 0;
};

// --- Step -----------------------------------------------------------------
class StepReference {
 public:
  ReferenceError plan(std::int64_t start_pico, std::int64_t step_pico, const AxisReferenceLimits& limits);
  AxisReference sample(std::int64_t tick) const;  // tick 0 carries the step
  bool done(std::int64_t tick) const { return tick >= 0; }

 private:
  std::int64_t start_ = 0;
  std::int64_t step_ = 0;
};

// --- Point-to-point moves (trapezoid / S-curve) ---------------------------
// A profile of up to 7 constant-jerk segments along the move direction.
class MoveReference {
 public:
  // Trapezoidal velocity: v and a limited (jerk unbounded), eq. Fig. 10.
  ReferenceError plan_trapezoid(std::int64_t start_pico, std::int64_t target_pico, double max_velocity,
                                double max_acceleration, double servo_rate_Hz, const AxisReferenceLimits& limits);
  // Jerk-limited 7-segment S-curve (v, a, j limited).
  ReferenceError plan_scurve(std::int64_t start_pico, std::int64_t target_pico, double max_velocity,
                             double max_acceleration, double max_jerk, double servo_rate_Hz,
                             const AxisReferenceLimits& limits);
  AxisReference sample(std::int64_t tick) const;
  bool done(std::int64_t tick) const { return tick >= total_ticks_; }
  std::int64_t total_ticks() const { return total_ticks_; }
  double duration_s() const { return duration_s_; }  // analytic duration
  double peak_velocity() const { return peak_velocity_; }

  // Distance (>= 0) travelled, speed and acceleration at time t in [0, T].
  void evaluate(double t, double* s, double* v, double* a) const;

 private:
  struct Segment {
    double t0, s0, v0, a0, jerk;
  };
  struct State {
    double s, v, a;
  };
  // The profile at t, as evaluate() gives it; inlined into sample() (the
  // per-tick path: no call, no results through memory).
  State state_at(double t) const;
  ReferenceError finish_plan(std::int64_t start_pico, std::int64_t target_pico, double servo_rate_Hz,
                             const AxisReferenceLimits& limits);
  Segment seg_[7] = {};
  int n_seg_ = 0;
  // The segment the last evaluate() found: sampling moves forward in time,
  // so the next search starts there instead of at segment 0 (the same
  // segment either way: the t0 do not decrease). finish_plan() resets it.
  mutable int seg_hint_ = 0;
  double duration_s_ = 0.0;
  double peak_velocity_ = 0.0;
  double period_s_ = 0.0;
  double direction_ = 1.0;
  std::int64_t start_ = 0;
  std::int64_t target_ = 0;
  std::int64_t total_ticks_ = 0;
};

// --- Circle in the xy plane -------------------------------------------------
// The stage starts ON the circle at (x0, y0); the centre is (x0 - r, y0).
// The arc length follows a jerk-limited S-curve (smooth start and stop:
// zero velocity and acceleration at both ends), `revolutions` full turns
// counter-clockwise at the requested tangential speed.
class CircleReference {
 public:
  ReferenceError plan(std::int64_t x0_pico, std::int64_t y0_pico, double diameter_m, double speed_m_per_s,
                      double revolutions, double tangential_acceleration, double jerk, double servo_rate_Hz,
                      const AxisReferenceLimits& limits_x, const AxisReferenceLimits& limits_y);
  void sample(std::int64_t tick, AxisReference* x, AxisReference* y) const;
  bool done(std::int64_t tick) const { return arc_.done(tick); }
  std::int64_t total_ticks() const { return arc_.total_ticks(); }
  double radius_m() const { return radius_m_; }

 private:
  MoveReference arc_;  // arc length in pm along the path
  double radius_m_ = 0.0;
  std::int64_t cx_ = 0, cy_ = 0;
  std::int64_t x0_ = 0, y0_ = 0;
};

// --- Sinusoid ---------------------------------------------------------------
// p(t) = p0 + A (sin(w t + phi) - sin(phi)), for `cycles` periods (0 = run
// forever). phi = -pi/2 (default) starts at rest: p0 + A (1 - cos w t), the
// form paper 002 uses (sin(1.5 pi t - pi/2)).
class SinusoidReference {
 public:
  ReferenceError plan(std::int64_t start_pico, double amplitude_m, double frequency_Hz, double cycles,
                      double servo_rate_Hz, const AxisReferenceLimits& limits, double phase_rad = -1.5707963267948966);
  AxisReference sample(std::int64_t tick) const;
  bool done(std::int64_t tick) const { return total_ticks_ > 0 && tick >= total_ticks_; }

 private:
  std::int64_t start_ = 0;
  double amplitude_ = 0.0, omega_ = 0.0, phase_ = 0.0, period_s_ = 0.0;
  double sin_phase_ = 0.0;  // dsin(phase_), planned once
  std::int64_t total_ticks_ = 0;
};

// --- Stop (kHold) -------------------------------------------------------------
// A moving reference brought to rest at the axis' max_acceleration a, from
// its present position and velocity: p(t) = p0 + v0 t - a t^2 / 2 up to
// T = |v0| / a, sampled at the ticks, then held at p(T); never beyond travel.
// The acceleration steps from the running profile's to -a, as a trapezoid's
// does at its corners (an S-curve's jerk limit is not kept by a stop).
class StopReference {
 public:
  ReferenceError plan(std::int64_t start_pico, double velocity, double servo_rate_Hz,
                      const AxisReferenceLimits& limits);
  AxisReference sample(std::int64_t tick) const;
  bool done(std::int64_t tick) const { return tick >= total_ticks_; }
  std::int64_t total_ticks() const { return total_ticks_; }

 private:
  std::int64_t start_ = 0;
  double v0_ = 0.0, decel_ = 0.0, period_s_ = 0.0, t_stop_s_ = 0.0;
  std::int64_t total_ticks_ = 0;
  std::int64_t travel_min_pico_ = 0, travel_max_pico_ = 0;
};

}  // namespace maglev::kernel
