// Servo kernel of the solenoid_magnet family (selfstab_stage.hpp).
#include "maglev/selfstab_stage/selfstab_stage.hpp"

#include <cmath>

#include "maglev/numeric/dac_code.hpp"

namespace maglev::selfstab {

MAGLEV_ENUM_TO_STRING(SelfstabConfigError, MAGLEV_SELFSTAB_CONFIG_ERRORS)
MAGLEV_ENUM_TO_STRING(SelfstabResult, MAGLEV_SELFSTAB_RESULTS)
MAGLEV_ENUM_TO_STRING(SelfstabMode, MAGLEV_SELFSTAB_MODES)

namespace {

bool finite(float v) { return std::isfinite(v); }
float clamp(float v, float lim) { return v > lim ? lim : (v < -lim ? -lim : v); }

// Current -> DAC code: the quotient in float (as this stage always formed
// it), rounded half away from zero into [-32767, 32767] by the kernels'
// one DAC rounding (the same codes as the clamp and lround it replaced).
std::int16_t dac_code(float current_A, float A_per_code) {
  return numeric::SymmetricDacCode(static_cast<double>(current_A / A_per_code));
}

}  // namespace

SelfstabConfigError SelfstabKernel::configure(const SelfstabKernelConfig& c) {
  // Only at rest: docked, or fallen to the dock after a fault (the way out of it).
  if (configured_ && mode_ != SelfstabMode::kDocked && mode_ != SelfstabMode::kFault) {
    return SelfstabConfigError::kNotDocked;
  }
  if (!finite(c.servo_rate_Hz) || !(c.servo_rate_Hz > 0.0f)) return SelfstabConfigError::kBadServoRate;
  if (!(c.dac_A_per_code > 0.0f) || !(c.current_limit_A > 0.0f) || !(c.liftoff_ramp_s > 0.0f) ||
      !(c.land_ramp_s > 0.0f) || !(c.liftoff_settle_s >= 0.0f) || c.psd_code_limit <= 0) {
    return SelfstabConfigError::kBadScale;
  }
  int active = 0;
  kernel::BiquadCoefficients<float> filters[kAxes]{};
  float da[kAxes]{}, db[kAxes]{};
  const double T = 1.0 / static_cast<double>(c.servo_rate_Hz);
  for (int a = 0; a < kAxes; ++a) {
    if (c.role[a] != AxisRole::kActive) continue;
    ++active;
    const SelfstabLoopConfig& l = c.loop[a];
    const float v[] = {l.kp, l.ki, l.kd, l.derivative_filter_Hz, l.effort_limit_A, l.max_velocity};
    for (float x : v) {
      if (!finite(x) || x < 0.0f) return SelfstabConfigError::kBadLoop;
    }
    if (!(l.effort_limit_A > 0.0f) || !(l.max_velocity > 0.0f) || !finite(l.travel_min) || !finite(l.travel_max) ||
        !(l.travel_max > l.travel_min)) {
      return SelfstabConfigError::kBadLoop;
    }
    if (l.kd > 0.0f && !(static_cast<double>(l.derivative_filter_Hz) > 0.0 &&
                         static_cast<double>(l.derivative_filter_Hz) < 0.5 * static_cast<double>(c.servo_rate_Hz))) {
      return SelfstabConfigError::kBadLoop;
    }
    if (l.schedule_points == 1 || l.schedule_points > kMaxSchedulePoints) return SelfstabConfigError::kBadSchedule;
    for (int i = 0; i < l.schedule_points; ++i) {
      if (!finite(l.schedule_at[i]) || !(l.kp_scale[i] > 0.0f) || !(l.kd_scale[i] > 0.0f) || !finite(l.kp_scale[i]) ||
          !finite(l.kd_scale[i]) || (i > 0 && !(l.schedule_at[i] > l.schedule_at[i - 1]))) {
        return SelfstabConfigError::kBadSchedule;
      }
    }
    if (kernel::design_biquad(l.feedback_filter, static_cast<double>(c.servo_rate_Hz), &filters[a]) !=
        kernel::LoopDesignError::kOk) {
      return SelfstabConfigError::kBadFilter;
    }
    // Derivative: Tustin of s / (1 + s/wf) (as axis_loops' PID), in double at apply time.
    const double wf = 2.0 * 3.14159265358979323846 * static_cast<double>(l.derivative_filter_Hz);
    da[a] = static_cast<float>((2.0 - wf * T) / (2.0 + wf * T));
    db[a] = static_cast<float>(2.0 * wf / (2.0 + wf * T));
  }
  if (active == 0) return SelfstabConfigError::kNoActiveAxis;
  cfg_ = c;
  for (int a = 0; a < kAxes; ++a) {
    filter_[a] = filters[a];
    d_a_[a] = da[a];
    d_b_[a] = db[a];
  }
  T_s_ = static_cast<float>(T);
  configured_ = true;
  mode_ = SelfstabMode::kDocked;
  loops_closed_ = false;
  phase_ticks_ = 0;
  tel_ = SelfstabTelemetry{};
  return SelfstabConfigError::kOk;
}

SelfstabResult SelfstabKernel::lift_off() {
  if (!configured_) return SelfstabResult::kNotConfigured;
  if (mode_ != SelfstabMode::kDocked) return SelfstabResult::kWrongMode;
  mode_ = SelfstabMode::kLifting;
  phase_ticks_ = 0;
  loops_closed_ = false;
  return SelfstabResult::kOk;
}

SelfstabResult SelfstabKernel::check_reference(int axis, float target) const {
  if (!configured_) return SelfstabResult::kNotConfigured;
  if (axis < 0 || axis >= kAxes) return SelfstabResult::kBadAxis;
  if (cfg_.role[axis] == AxisRole::kPassive) return SelfstabResult::kAxisPassive;
  if (cfg_.role[axis] == AxisRole::kAbsent) return SelfstabResult::kAxisAbsent;
  if (!finite(target)) return SelfstabResult::kBadValue;
  const SelfstabLoopConfig& l = cfg_.loop[axis];
  if (l.schedule_points >= 2 &&
      (target < l.schedule_at[0] || target > l.schedule_at[l.schedule_points - 1])) {
    return SelfstabResult::kOutsideSchedule;
  }
  if (target < l.travel_min || target > l.travel_max) return SelfstabResult::kOutsideTravel;
  if (mode_ != SelfstabMode::kLevitated || !loops_closed_) return SelfstabResult::kWrongMode;
  return SelfstabResult::kOk;
}

SelfstabResult SelfstabKernel::move_to(int axis, float target) {
  const SelfstabResult r = check_reference(axis, target);
  if (r != SelfstabResult::kOk) return r;
  // A step (paper Figs. 10, 11): the reference jumps, the ramp stops.
  loop_[axis].reference = target;
  loop_[axis].target = target;
  return SelfstabResult::kOk;
}

SelfstabResult SelfstabKernel::hold() {
  if (!configured_) return SelfstabResult::kNotConfigured;
  if (mode_ != SelfstabMode::kLevitated || !loops_closed_) return SelfstabResult::kWrongMode;
  for (LoopState& s : loop_) s.target = s.reference;
  return SelfstabResult::kOk;
}

SelfstabResult SelfstabKernel::land() {
  if (!configured_) return SelfstabResult::kNotConfigured;
  if (mode_ != SelfstabMode::kLevitated) return SelfstabResult::kWrongMode;
  for (int j = 0; j < kCoils; ++j) ramp_start_A_[j] = tel_.current_A[j];
  mode_ = SelfstabMode::kLanding;
  phase_ticks_ = 0;
  loops_closed_ = false;
  return SelfstabResult::kOk;
}

SelfstabResult SelfstabKernel::set_feedback_filter(bool enabled) {
  if (!configured_) return SelfstabResult::kNotConfigured;
  cfg_.feedback_filter_enabled = enabled ? 1 : 0;
  // Restart each filter at the present position: no jump in what the loop sees.
  for (int a = 0; a < kAxes; ++a) kernel::biquad_reset(loop_[a].filter, tel_.pose[a], tel_.pose[a]);
  return SelfstabResult::kOk;
}

float SelfstabKernel::scale_at(const SelfstabLoopConfig& l, const float* s, float y) const {
  const int n = l.schedule_points;
  if (n < 2) return 1.0f;
  if (!(y > l.schedule_at[0])) return s[0];
  if (!(y < l.schedule_at[n - 1])) return s[n - 1];
  int i = 0;
  while (i < n - 2 && !(y < l.schedule_at[i + 1])) ++i;
  const float w = (y - l.schedule_at[i]) / (l.schedule_at[i + 1] - l.schedule_at[i]);
  return s[i] + w * (s[i + 1] - s[i]);
}

void SelfstabKernel::close_loops() {
  // Bumpless: each active loop starts at the present (filtered) position with
  // its reference there, and ramps to 0 (the nominal point) at max_velocity.
  for (int a = 0; a < kAxes; ++a) {
    LoopState& s = loop_[a];
    s.integrator = 0.0f;
    s.derivative = 0.0f;
    s.prev_y = tel_.feedback[a];
    s.prev_e = 0.0f;
    s.reference = tel_.feedback[a];
    s.target = 0.0f;
  }
  loops_closed_ = true;
}

SelfstabCoilCommand SelfstabKernel::tick(const SelfstabSensorSample& in) {
  SelfstabCoilCommand out{};
  if (!configured_) return out;
  SelfstabTelemetry& t = tel_;
  // 1. Kinematic transform R: pose from the six channels.
  bool saturated = false;
  for (int c = 0; c < kPsdChannels; ++c) {
    const int code = in.psd_code[c];
    if (code >= cfg_.psd_code_limit || code <= -cfg_.psd_code_limit) saturated = true;
  }
  const bool valid = (in.status & kPsdValid) != 0;
  if (valid) {
    for (int a = 0; a < kAxes; ++a) {
      float p = 0.0f;
      for (int c = 0; c < kPsdChannels; ++c) p += cfg_.pose_per_code[a][c] * static_cast<float>(in.psd_code[c]);
      t.pose[a] = p;
    }
  }
  // A levitated stage that loses its sensors cannot be controlled: fault,
  // currents off (the passive axes keep it on the way down to the dock).
  if ((mode_ == SelfstabMode::kLevitated) && (!valid || saturated)) {
    mode_ = SelfstabMode::kFault;
    loops_closed_ = false;
  }
  // 2. Feedback filter (every axis, so switching it in finds a warm filter).
  for (int a = 0; a < kAxes; ++a) {
    const float f = kernel::biquad_update(filter_[a], loop_[a].filter, t.pose[a]);
    t.feedback[a] = (cfg_.feedback_filter_enabled != 0 && cfg_.role[a] == AxisRole::kActive) ? f : t.pose[a];
  }
  // 3. Sequence.
  float lift = 0.0f;  // fraction of W applied
  bool loops = false;
  const float ramp_ticks = cfg_.liftoff_ramp_s * cfg_.servo_rate_Hz;
  const float settle_ticks = cfg_.liftoff_settle_s * cfg_.servo_rate_Hz;
  switch (mode_) {
    case SelfstabMode::kDocked:
    case SelfstabMode::kFault:
      break;
    case SelfstabMode::kLifting: {
      ++phase_ticks_;
      const float k = static_cast<float>(phase_ticks_);
      lift = k >= ramp_ticks ? 1.0f : k / ramp_ticks;
      if (k >= ramp_ticks + settle_ticks && valid && !saturated) {
        close_loops();
        mode_ = SelfstabMode::kLevitated;
        loops = true;
      }
      break;
    }
    case SelfstabMode::kLevitated:
      lift = 1.0f;
      loops = loops_closed_;
      break;
    case SelfstabMode::kLanding:
      ++phase_ticks_;
      break;
  }
  // 4. Loops of the active axes.
  for (int a = 0; a < kAxes; ++a) {
    t.effort_A[a] = 0.0f;
    t.kp_scale[a] = 1.0f;
    t.kd_scale[a] = 1.0f;
    if (cfg_.role[a] != AxisRole::kActive || !loops) {
      t.reference[a] = loops_closed_ ? loop_[a].reference : t.feedback[a];
      continue;
    }
    const SelfstabLoopConfig& l = cfg_.loop[a];
    LoopState& s = loop_[a];
    // Reference ramp towards the target (lift-off approach; steps jump).
    const float dr = l.max_velocity * T_s_;
    const float gap = s.target - s.reference;
    s.reference = gap > dr ? s.reference + dr : (gap < -dr ? s.reference - dr : s.target);
    const float y = t.feedback[a];
    const float e = s.reference - y;
    const float sp = scale_at(l, l.kp_scale, y);
    const float sd = scale_at(l, l.kd_scale, y);
    // Derivative on the measurement (a reference step gives no kick).
    s.derivative = d_a_[a] * s.derivative + d_b_[a] * (y - s.prev_y);
    s.prev_y = y;
    // Integral: Tustin on e, clamped to the effort limit (anti-windup).
    s.integrator = clamp(s.integrator + 0.5f * l.ki * T_s_ * (e + s.prev_e), l.effort_limit_A);
    s.prev_e = e;
    const float u = l.kp * sp * e + s.integrator - l.kd * sd * s.derivative;
    t.effort_A[a] = clamp(u, l.effort_limit_A);
    t.reference[a] = s.reference;
    t.kp_scale[a] = sp;
    t.kd_scale[a] = sd;
  }
  // 5. W + T effort -> currents -> DAC codes.
  const float land_ticks = cfg_.land_ramp_s * cfg_.servo_rate_Hz;
  for (int j = 0; j < kCoils; ++j) {
    float i = lift * cfg_.nominal_current_A[j];
    for (int a = 0; a < kAxes; ++a) i += cfg_.coil_per_effort[j][a] * t.effort_A[a];
    if (mode_ == SelfstabMode::kLanding) {
      const float k = static_cast<float>(phase_ticks_);
      i = k >= land_ticks ? 0.0f : ramp_start_A_[j] * (1.0f - k / land_ticks);
    }
    i = clamp(i, cfg_.current_limit_A);
    t.current_A[j] = i;
    out.dac_code[j] = dac_code(i, cfg_.dac_A_per_code);
  }
  if (mode_ == SelfstabMode::kLanding && static_cast<float>(phase_ticks_) >= land_ticks) {
    mode_ = SelfstabMode::kDocked;
  }
  out.enable = (mode_ == SelfstabMode::kDocked || mode_ == SelfstabMode::kFault) ? 0 : 1;
  if (out.enable == 0) {
    for (int j = 0; j < kCoils; ++j) {
      out.dac_code[j] = 0;
      t.current_A[j] = 0.0f;
    }
  }
  t.mode = mode_;
  return out;
}

}  // namespace maglev::selfstab
