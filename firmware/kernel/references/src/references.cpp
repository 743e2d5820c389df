// Reference generators; see references.hpp for the contract.
#include "maglev/io/code_placement.hpp"
#include "maglev/references/references.hpp"

#include <cmath>

#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/elementary.hpp"
// Per-tick int64 -> double (the sample() functions): Int64ToDouble gives the
// cast's value without libgcc's __aeabi_l2d, which runs through the soft-float
// add on the M7 (~80 instructions a call, measured in the replay's trace).
#include "maglev/numeric/int64_double.hpp"

namespace maglev::kernel {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kPicoPerSi = 1e12;

bool finite_all(std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

bool inside(std::int64_t p, const AxisReferenceLimits& l) { return p >= l.travel_min_pico && p <= l.travel_max_pico; }

MAGLEV_CONFIG_CODE bool limits_valid(const AxisReferenceLimits& l) {
  return finite_all({l.max_velocity, l.max_acceleration}) && l.max_velocity > 0.0 && l.max_acceleration > 0.0 &&
         l.travel_min_pico <= l.travel_max_pico;
}

// Ticks needed to cover duration_s (ceil), with a guard for rounding: a
// duration of exactly N periods gives N.
MAGLEV_CONFIG_CODE std::int64_t ticks_for(double duration_s, double servo_rate_Hz) {
  const double n = duration_s * servo_rate_Hz;
  const double c = std::ceil(n - 1e-9);
  return static_cast<std::int64_t>(c < 0.0 ? 0.0 : c);
}

}  // namespace

// --- Step -----------------------------------------------------------------

MAGLEV_CONFIG_CODE ReferenceError StepReference::plan(std::int64_t start_pico, std::int64_t step_pico, const AxisReferenceLimits& limits) {
  if (limits.travel_min_pico > limits.travel_max_pico) return ReferenceError::kBadParameter;
  if (step_pico == INT64_MIN) return ReferenceError::kStepTooLarge;  // -x would overflow
  const std::int64_t mag = step_pico < 0 ? -step_pico : step_pico;
  if (mag > limits.max_step_pico) return ReferenceError::kStepTooLarge;
  if (!inside(start_pico, limits)) return ReferenceError::kOutsideTravel;
  std::int64_t target = 0;
  if (__builtin_add_overflow(start_pico, step_pico, &target) || !inside(target, limits)) {
    return ReferenceError::kOutsideTravel;
  }
  start_ = start_pico;
  step_ = step_pico;
  return ReferenceError::kOk;
}

AxisReference StepReference::sample(std::int64_t tick) const {
  AxisReference r;
  r.position_pico = tick >= 0 ? start_ + step_ : start_;
  r.step_pico = tick == 0 ? step_ : 0;
  return r;
}

// --- Moves -----------------------------------------------------------------

__attribute__((always_inline)) inline MoveReference::State MoveReference::state_at(double t) const {
  if (n_seg_ == 0) return State{0.0, 0.0, 0.0};
  if (t < 0.0) t = 0.0;
  if (t > duration_s_) t = duration_s_;
  // The last segment whose start is <= t (segment 0 below seg_[1].t0): the
  // search may start at any segment that starts <= t.
  int i = seg_hint_ < n_seg_ && seg_[seg_hint_].t0 <= t ? seg_hint_ : 0;
  while (i + 1 < n_seg_ && seg_[i + 1].t0 <= t) ++i;
  seg_hint_ = i;
  const Segment& g = seg_[i];
  const double tau = t - g.t0;
  return State{g.s0 + g.v0 * tau + 0.5 * g.a0 * tau * tau + g.jerk * tau * tau * tau / 6.0,
               g.v0 + g.a0 * tau + 0.5 * g.jerk * tau * tau, g.a0 + g.jerk * tau};
}

void MoveReference::evaluate(double t, double* s, double* v, double* a) const {
  const State st = state_at(t);
  *s = st.s;
  *v = st.v;
  *a = st.a;
}

MAGLEV_CONFIG_CODE ReferenceError MoveReference::finish_plan(std::int64_t start_pico, std::int64_t target_pico, double servo_rate_Hz,
                                          const AxisReferenceLimits& limits) {
  if (!inside(start_pico, limits) || !inside(target_pico, limits)) return ReferenceError::kOutsideTravel;
  // Integrate the segment start states (s, v continuous; a as given).
  seg_hint_ = 0;
  double s = 0.0, v = 0.0, t = 0.0;
  peak_velocity_ = 0.0;
  for (int i = 0; i < n_seg_; ++i) {
    Segment& g = seg_[i];
    const double dur = (i + 1 < n_seg_ ? seg_[i + 1].t0 : duration_s_) - g.t0;
    g.t0 = t;
    g.s0 = s;
    g.v0 = v;
    s += v * dur + 0.5 * g.a0 * dur * dur + g.jerk * dur * dur * dur / 6.0;
    v += g.a0 * dur + 0.5 * g.jerk * dur * dur;
    t += dur;
    if (v > peak_velocity_) peak_velocity_ = v;
  }
  const std::int64_t ticks = ticks_for(duration_s_, servo_rate_Hz);
  if (ticks > kMaxProfileTicks) return ReferenceError::kTooLong;
  total_ticks_ = ticks;
  period_s_ = 1.0 / servo_rate_Hz;
  start_ = start_pico;
  target_ = target_pico;
  direction_ = target_pico >= start_pico ? 1.0 : -1.0;
  return ReferenceError::kOk;
}

MAGLEV_CONFIG_CODE ReferenceError MoveReference::plan_trapezoid(std::int64_t start_pico, std::int64_t target_pico, double vmax,
                                             double amax, double servo_rate_Hz, const AxisReferenceLimits& limits) {
  if (!finite_all({vmax, amax, servo_rate_Hz})) return ReferenceError::kNonFinite;
  if (!limits_valid(limits) || vmax <= 0.0 || amax <= 0.0 || servo_rate_Hz <= 0.0) {
    return ReferenceError::kBadParameter;
  }
  if (vmax > limits.max_velocity) return ReferenceError::kVelocityLimit;
  if (amax > limits.max_acceleration) return ReferenceError::kAccelerationLimit;
  const double d = std::fabs(static_cast<double>(target_pico - start_pico)) / kPicoPerSi;
  n_seg_ = 0;
  total_ticks_ = 0;
  if (d > 0.0) {
    if (d >= vmax * vmax / amax) {  // reaches vmax: accel, cruise, decel
      const double ta = vmax / amax;
      const double tc = (d - vmax * vmax / amax) / vmax;
      seg_[0] = {0.0, 0.0, 0.0, amax, 0.0};
      seg_[1] = {ta, 0.0, 0.0, 0.0, 0.0};
      seg_[2] = {ta + tc, 0.0, 0.0, -amax, 0.0};
      n_seg_ = 3;
      duration_s_ = 2.0 * ta + tc;
    } else {  // triangular
      const double ta = std::sqrt(d / amax);
      seg_[0] = {0.0, 0.0, 0.0, amax, 0.0};
      seg_[1] = {ta, 0.0, 0.0, -amax, 0.0};
      n_seg_ = 2;
      duration_s_ = 2.0 * ta;
    }
  } else {
    duration_s_ = 0.0;
  }
  return finish_plan(start_pico, target_pico, servo_rate_Hz, limits);
}

namespace {
// Acceleration phase of an S-curve from rest to v: jerk time Tj, total Ta.
MAGLEV_CONFIG_CODE void accel_phase(double v, double a, double j, double* tj, double* ta, double* a_peak) {
  if (v * j >= a * a) {
    *tj = a / j;
    *ta = v / a + a / j;
    *a_peak = a;
  } else {
    *tj = std::sqrt(v / j);
    *ta = 2.0 * *tj;
    *a_peak = j * *tj;
  }
}
}  // namespace

MAGLEV_CONFIG_CODE ReferenceError MoveReference::plan_scurve(std::int64_t start_pico, std::int64_t target_pico, double vmax,
                                          double amax, double jmax, double servo_rate_Hz,
                                          const AxisReferenceLimits& limits) {
  if (!finite_all({vmax, amax, jmax, servo_rate_Hz, limits.max_jerk})) return ReferenceError::kNonFinite;
  if (!limits_valid(limits) || vmax <= 0.0 || amax <= 0.0 || jmax <= 0.0 || servo_rate_Hz <= 0.0) {
    return ReferenceError::kBadParameter;
  }
  if (vmax > limits.max_velocity) return ReferenceError::kVelocityLimit;
  if (amax > limits.max_acceleration) return ReferenceError::kAccelerationLimit;
  if (jmax > limits.max_jerk) return ReferenceError::kJerkLimit;
  const double d = std::fabs(static_cast<double>(target_pico - start_pico)) / kPicoPerSi;
  n_seg_ = 0;
  total_ticks_ = 0;
  duration_s_ = 0.0;
  if (d > 0.0) {
    double v = vmax, tj = 0, ta = 0, ap = 0;
    accel_phase(v, amax, jmax, &tj, &ta, &ap);
    if (v * ta > d) {
      // Cannot reach vmax: the peak speed v solves v Ta(v) = d (monotone).
      double lo = 0.0, hi = vmax;
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        accel_phase(mid, amax, jmax, &tj, &ta, &ap);
        if (mid * ta > d) {
          hi = mid;
        } else {
          lo = mid;
        }
      }
      v = lo;
      accel_phase(v, amax, jmax, &tj, &ta, &ap);
    }
    const double tv = d / v - ta;  // cruise (>= 0 up to rounding)
    const double tc = ta - 2.0 * tj;  // constant-acceleration time
    double t = 0.0;
    auto add = [&](double dur, double a0, double jerk) {
      seg_[n_seg_++] = {t, 0.0, 0.0, a0, jerk};
      t += dur > 0.0 ? dur : 0.0;
    };
    add(tj, 0.0, jmax);
    add(tc, ap, 0.0);
    add(tj, ap, -jmax);
    add(tv, 0.0, 0.0);
    add(tj, 0.0, -jmax);
    add(tc, -ap, 0.0);
    add(tj, -ap, jmax);
    duration_s_ = t;
  }
  return finish_plan(start_pico, target_pico, servo_rate_Hz, limits);
}

AxisReference MoveReference::sample(std::int64_t tick) const {
  AxisReference r;
  if (tick >= total_ticks_) {
    r.position_pico = target_;
    return r;
  }
  if (tick <= 0) {
    r.position_pico = start_;
    return r;
  }
  // 0 < tick < total_ticks_ <= kMaxProfileTicks = 2^31 here: an int32, whose
  // conversion is one VCVT (Int64ToDouble's general form was ~6 M7 instructions).
  static_assert(kMaxProfileTicks <= (std::int64_t{1} << 31));
  const State st = state_at(static_cast<double>(static_cast<std::int32_t>(tick)) * period_s_);
  const std::int64_t d_pico = target_ >= start_ ? target_ - start_ : start_ - target_;
  std::int64_t s_pico = numeric::si_to_pico(st.s);
  if (s_pico > d_pico) s_pico = d_pico;  // never past the target
  if (s_pico < 0) s_pico = 0;
  r.position_pico = direction_ > 0 ? start_ + s_pico : start_ - s_pico;
  r.velocity = static_cast<float>(direction_ * st.v);
  r.acceleration = static_cast<float>(direction_ * st.a);
  return r;
}

// --- Circle ------------------------------------------------------------------

MAGLEV_CONFIG_CODE ReferenceError CircleReference::plan(std::int64_t x0_pico, std::int64_t y0_pico, double diameter_m,
                                     double speed, double revolutions, double at, double jerk,
                                     double servo_rate_Hz, const AxisReferenceLimits& lx, const AxisReferenceLimits& ly) {
  if (!finite_all({diameter_m, speed, revolutions, at, jerk, servo_rate_Hz})) return ReferenceError::kNonFinite;
  if (!limits_valid(lx) || !limits_valid(ly) || diameter_m <= 0.0 || speed <= 0.0 || revolutions <= 0.0 ||
      at <= 0.0 || jerk <= 0.0 || servo_rate_Hz <= 0.0) {
    return ReferenceError::kBadParameter;
  }
  const double r = 0.5 * diameter_m;
  const double vlim = std::fmin(lx.max_velocity, ly.max_velocity);
  const double alim = std::fmin(lx.max_acceleration, ly.max_acceleration);
  const double jlim = std::fmin(lx.max_jerk, ly.max_jerk);
  if (speed > vlim) return ReferenceError::kVelocityLimit;
  // Worst-case per-axis acceleration <= |(a_t, v^2/r)|.
  // (sqrt of the sum of squares: IEEE-exact everywhere, where hypot is not.)
  const double an = speed * speed / r;
  if (std::sqrt(at * at + an * an) > alim) return ReferenceError::kAccelerationLimit;
  // Worst-case per-axis jerk <= j + 3 v a_t / r + v^3 / r^2.
  if (jerk + 3.0 * speed * at / r + speed * speed * speed / (r * r) > jlim) return ReferenceError::kJerkLimit;
  const std::int64_t r_pico = numeric::si_to_pico(r);
  const std::int64_t cx = x0_pico - r_pico;
  if (!inside(x0_pico, lx) || !inside(y0_pico, ly) || !inside(cx - r_pico, lx) || !inside(cx + r_pico, lx) ||
      !inside(y0_pico - r_pico, ly) || !inside(y0_pico + r_pico, ly)) {
    return ReferenceError::kOutsideTravel;
  }
  const double length = revolutions * 2.0 * kPi * r;
  AxisReferenceLimits arc;
  arc.max_velocity = speed;
  arc.max_acceleration = at;
  arc.max_jerk = jerk;
  arc.travel_min_pico = 0;
  arc.travel_max_pico = numeric::si_to_pico(length);
  const ReferenceError err = arc_.plan_scurve(0, arc.travel_max_pico, speed, at, jerk, servo_rate_Hz, arc);
  if (err != ReferenceError::kOk) return err;
  radius_m_ = r;
  cx_ = cx;
  cy_ = y0_pico;
  x0_ = x0_pico;
  y0_ = y0_pico;
  return ReferenceError::kOk;
}

void CircleReference::sample(std::int64_t tick, AxisReference* x, AxisReference* y) const {
  const AxisReference s = arc_.sample(tick);  // arc length in pm
  const double theta = numeric::Int64ToDouble(s.position_pico) / kPicoPerSi / radius_m_;
  double sn = 0.0, c = 0.0;
  numeric::dsincos(theta, &sn, &c);
  const double v = static_cast<double>(s.velocity), at = static_cast<double>(s.acceleration);
  // Each field written once (zeroing the two and then filling them in cost
  // the stores twice: x and y may alias, so the compiler kept both).
  const AxisReference rx{cx_ + numeric::si_to_pico(radius_m_ * c), static_cast<float>(-sn * v),
                         static_cast<float>(-sn * at - c * v * v / radius_m_), 0};
  const AxisReference ry{cy_ + numeric::si_to_pico(radius_m_ * sn), static_cast<float>(c * v),
                         static_cast<float>(c * at - sn * v * v / radius_m_), 0};
  *x = rx;
  *y = ry;
}

// --- Sinusoid ----------------------------------------------------------------

MAGLEV_CONFIG_CODE ReferenceError SinusoidReference::plan(std::int64_t start_pico, double amplitude_m, double frequency_Hz,
                                       double cycles, double servo_rate_Hz, const AxisReferenceLimits& limits,
                                       double phase_rad) {
  if (!finite_all({amplitude_m, frequency_Hz, cycles, servo_rate_Hz, phase_rad})) return ReferenceError::kNonFinite;
  if (!limits_valid(limits) || frequency_Hz <= 0.0 || cycles < 0.0 || servo_rate_Hz <= 0.0 ||
      frequency_Hz >= 0.5 * servo_rate_Hz) {
    return ReferenceError::kBadParameter;
  }
  const double w = 2.0 * kPi * frequency_Hz;
  const double a = std::fabs(amplitude_m);
  if (a * w > limits.max_velocity) return ReferenceError::kVelocityLimit;
  if (a * w * w > limits.max_acceleration) return ReferenceError::kAccelerationLimit;
  const double s0 = numeric::dsin(phase_rad);
  // p - p0 = A sin(ph) - A sin(phi), and A sin(ph) spans [-|A|, |A|].
  const std::int64_t hi = start_pico + numeric::si_to_pico(a - amplitude_m * s0);
  const std::int64_t lo = start_pico + numeric::si_to_pico(-a - amplitude_m * s0);
  if (!inside(start_pico, limits) || !inside(hi, limits) || !inside(lo, limits)) return ReferenceError::kOutsideTravel;
  const double n = cycles * servo_rate_Hz / frequency_Hz;
  if (n > static_cast<double>(kMaxProfileTicks)) return ReferenceError::kTooLong;
  // A finite sinusoid ends where its velocity is zero (whole half cycles of
  // the paper's p0 + A (1 - cos w t)): the reference holds its last sample,
  // so ending elsewhere stops a moving reference in one tick (0.25 cycles
  // of 19.7 mm at 1.2 Hz: 371 m/s^2 against a 1.5 m/s^2 limit).
  if (cycles > 0.0) {
    double s_end = 0.0, c_end = 1.0;
    numeric::dsincos(2.0 * kPi * cycles + phase_rad, &s_end, &c_end);
    if (std::fabs(c_end) > 1e-6) return ReferenceError::kBadParameter;
  }
  start_ = start_pico;
  amplitude_ = amplitude_m;
  omega_ = w;
  phase_ = phase_rad;
  sin_phase_ = s0;
  period_s_ = 1.0 / servo_rate_Hz;
  // (Whole half cycles below fs / 2 last at least two ticks: a positive
  // count never becomes 0, "until kHold".)
  total_ticks_ = cycles > 0.0 ? ticks_for(cycles / frequency_Hz, servo_rate_Hz) : 0;
  return ReferenceError::kOk;
}

AxisReference SinusoidReference::sample(std::int64_t tick) const {
  AxisReference r;
  if (tick < 0) tick = 0;
  const bool finished = total_ticks_ > 0 && tick >= total_ticks_;
  const double t = numeric::Int64ToDouble(finished ? total_ticks_ : tick) * period_s_;
  const double ph = omega_ * t + phase_;
  // One reduction for sin and cos of ph; sin of the start phase is planned.
  double s = 0.0, c = 0.0;
  numeric::dsincos(ph, &s, &c);
  r.position_pico = start_ + numeric::si_to_pico(amplitude_ * (s - sin_phase_));
  if (!finished) {
    r.velocity = static_cast<float>(amplitude_ * omega_ * c);
    r.acceleration = static_cast<float>(-amplitude_ * omega_ * omega_ * s);
  }
  return r;
}

// --- Stop --------------------------------------------------------------------

MAGLEV_CONFIG_CODE ReferenceError StopReference::plan(std::int64_t start_pico, double velocity,
                                                      double servo_rate_Hz, const AxisReferenceLimits& limits) {
  if (!finite_all({velocity, servo_rate_Hz})) return ReferenceError::kNonFinite;
  if (!limits_valid(limits) || servo_rate_Hz <= 0.0) return ReferenceError::kBadParameter;
  // The continuous stop at max_acceleration, sampled at the ticks, held at
  // its end from the first tick at or after it: it ends where a constant
  // max_acceleration from (p0, v0) ends, v0^2 / (2 a) on, the shortest stop
  // within the limit -- never beyond where the running profile could itself
  // have stopped (its target, inside travel; a sinusoid's or a circle's
  // bounds: their accelerations are within the limit too). Whole ticks at a
  // deceleration rounded down to fit them, as before 2026-11-29, covered up
  // to half a tick of motion more: a hold on a move to the travel's end took
  // the reference 8.7 um beyond it (test References.
  // AStopNeverEndsBeyondTheTargetOfTheMoveItStops). A reference at rest
  // stops in one tick where it is.
  const double t_stop = std::fabs(velocity) / limits.max_acceleration;
  const double n = std::ceil(t_stop * servo_rate_Hz - 1e-9);
  if (n > static_cast<double>(kMaxProfileTicks)) return ReferenceError::kTooLong;
  start_ = start_pico;
  v0_ = velocity;
  period_s_ = 1.0 / servo_rate_Hz;
  t_stop_s_ = t_stop;
  total_ticks_ = n < 1.0 ? 1 : static_cast<std::int64_t>(n);
  decel_ = velocity > 0.0 ? limits.max_acceleration : (velocity < 0.0 ? -limits.max_acceleration : 0.0);
  travel_min_pico_ = limits.travel_min_pico;
  travel_max_pico_ = limits.travel_max_pico;
  return ReferenceError::kOk;
}

AxisReference StopReference::sample(std::int64_t tick) const {
  AxisReference r;
  if (tick < 0) tick = 0;
  const bool finished = tick >= total_ticks_;
  const double t = finished ? t_stop_s_ : numeric::Int64ToDouble(tick) * period_s_;
  std::int64_t p = start_ + numeric::si_to_pico(v0_ * t - 0.5 * decel_ * t * t);
  // Never beyond travel, whatever: the stop's end is inside it by the
  // argument above up to the float velocity's rounding (nm).
  p = p > travel_max_pico_ ? travel_max_pico_ : (p < travel_min_pico_ ? travel_min_pico_ : p);
  r.position_pico = p;
  if (!finished) {
    r.velocity = static_cast<float>(v0_ - decel_ * t);
    r.acceleration = static_cast<float>(-decel_);
  }
  return r;
}

}  // namespace maglev::kernel
