#include "maglev/pmlsm_stage/pmlsm_controller.hpp"

#include <cmath>

#include "maglev/numeric/dac_code.hpp"
#include "maglev/numeric/sin_cos.hpp"

namespace maglev::pmlsm_stage {
namespace {

constexpr float kTwoPi = 6.28318530717958648f;
constexpr float kQ30 = 1.0f / 1073741824.0f;
// Range checks forgive one micrometre (microradian) of float rounding, so
// that 25 mm - 5 mm is not refused against a 20 mm bound.
constexpr float kRangeTolerance = 1e-6f;
constexpr std::uint32_t kThirdTurn = 1431655765u;  // 2^32 / 3

bool finite(float v) { return std::isfinite(v); }

// The kernels' one DAC rounding, symmetric range. (Its own code + 0.5f and
// truncation gave 1 for 0.49999997: the float sum rounded up.)
std::int16_t to_dac(float amps, float amps_per_code) {
  return numeric::SymmetricDacCode(static_cast<double>(amps / amps_per_code));
}

bool positive_finite(float v) { return finite(v) && v > 0.0f; }

}  // namespace

const char* to_string(StageState s) {
  switch (s) {
    case StageState::kLanded: return "landed";
    case StageState::kLifting: return "lifting";
    case StageState::kReady: return "ready";
    case StageState::kLanding: return "landing";
    case StageState::kFault: return "fault";
  }
  return "?";
}

const char* to_string(PmlsmConfigError e) {
  switch (e) {
    case PmlsmConfigError::kOk: return "ok";
    case PmlsmConfigError::kBadServoRate: return "servo rate outside 500..20000 Hz";
    case PmlsmConfigError::kBadBody: return "mass, inertia or radius not positive";
    case PmlsmConfigError::kBadTable: return "force-law table not finite or not increasing";
    case PmlsmConfigError::kBadGains: return "regulator gains or internal model not finite";
    case PmlsmConfigError::kBadLimits: return "limits outside the hardware or the supervision window";
    case PmlsmConfigError::kLockedWhileLevitated: return "configuration locked while levitated";
  }
  return "?";
}

PmlsmConfigError PmlsmController::apply_config(const PmlsmKernelConfig& c) {
  if (status_.state != StageState::kLanded && status_.state != StageState::kFault) {
    return PmlsmConfigError::kLockedWhileLevitated;
  }
  if (!(c.servo_rate_Hz >= 500.0f && c.servo_rate_Hz <= 20000.0f)) return PmlsmConfigError::kBadServoRate;
  const float body[] = {c.mass_gap_kg, c.mass_x_kg, c.mass_z_kg, c.inertia_phi_kgm2, c.inertia_theta_kgm2,
                        c.radius_m, c.gravity_m_per_s2};
  for (float v : body) {
    if (!positive_finite(v)) return PmlsmConfigError::kBadBody;
  }
  if (!finite(c.torsion_phi_per_s2) || !finite(c.torsion_theta_per_s2)) return PmlsmConfigError::kBadBody;
  if (!positive_finite(c.force.step_m) || !finite(c.force.gap0_m)) return PmlsmConfigError::kBadTable;
  for (int i = 0; i < kGapTablePoints; ++i) {
    if (!finite(c.force.attraction_N[i]) || !positive_finite(c.force.direct_N_per_A[i]) ||
        !finite(c.force.quadratic_N_per_A2[i]) || c.force.quadratic_N_per_A2[i] < 0.0f ||
        !positive_finite(c.force.thrust_N_per_A[i])) {
      return PmlsmConfigError::kBadTable;
    }
  }
  for (int a = 0; a < kAxes; ++a) {
    for (float k : c.axis[a].Ks) {
      if (!finite(k)) return PmlsmConfigError::kBadGains;
    }
    for (float e : c.axis[a].E) {
      if (!finite(e)) return PmlsmConfigError::kBadGains;
    }
    if (!positive_finite(c.encoder_resolution[a])) return PmlsmConfigError::kBadLimits;
    if (!(c.reference_min[a] < c.reference_max[a]) || !(c.window_min[a] < c.window_max[a]) ||
        !(c.reference_min[a] >= c.window_min[a]) || !(c.reference_max[a] <= c.window_max[a]) ||
        !positive_finite(c.max_speed[a]) || !positive_finite(c.max_ramp_speed[a])) {
      return PmlsmConfigError::kBadLimits;
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (!finite(c.xi_Ad_minus_I[i][j]) || !finite(c.xi_Bd[i][j])) return PmlsmConfigError::kBadGains;
    }
  }
  if (!positive_finite(c.derivative_filter_rad_per_s) || !(c.derivative_filter_alpha > 0.0f) ||
      !(c.derivative_filter_alpha <= 1.0f)) {
    return PmlsmConfigError::kBadGains;
  }
  // The stage is never commanded beyond the amplifiers: the phase clamp must
  // fit the DAC's full scale.
  if (!positive_finite(c.phase_peak_A) || !positive_finite(c.amps_per_dac_code) ||
      !(c.phase_peak_A <= 32767.0f * c.amps_per_dac_code) || !positive_finite(c.horizontal_limit_A)) {
    return PmlsmConfigError::kBadLimits;
  }
  const int gap = static_cast<int>(Axis::kGap);
  if (!(c.rest_gap_m >= c.window_min[gap] && c.rest_gap_m <= c.window_max[gap]) ||
      !(c.nominal_gap_m >= c.reference_min[gap] && c.nominal_gap_m <= c.reference_max[gap]) ||
      !positive_finite(c.lift_speed_m_per_s) || c.max_saturated_ticks == 0) {
    return PmlsmConfigError::kBadLimits;
  }
  config_ = c;
  configured_ = true;
  return PmlsmConfigError::kOk;
}

bool PmlsmController::reference_in_range(int a, float v) const {
  return finite(v) && v >= config_.reference_min[a] - kRangeTolerance &&
         v <= config_.reference_max[a] + kRangeTolerance;
}

void PmlsmController::cancel(int a) {
  ramp_[a].active = false;
  sine_[a].active = false;
}

CommandResult PmlsmController::command(const MotionCommand& cmd) {
  const StageState s = status_.state;
  switch (cmd.type) {
    case MotionType::kLevitate:
      if (!configured_) return CommandResult::kRefusedNotReady;
      if (s == StageState::kFault) return CommandResult::kRefusedFaultLatched;
      if (s != StageState::kLanded) return CommandResult::kAlreadyThere;
      if (first_sample_) return CommandResult::kRefusedNotReady;  // no pose yet
      for (int a = 0; a < kAxes; ++a) {
        ref_[a] = status_.pose[a];
        cancel(a);
        pending_step_[a] = 0.0f;
      }
      ramp_[0] = {true, config_.nominal_gap_m, config_.lift_speed_m_per_s / config_.servo_rate_Hz};
      reset_loops();
      status_.state = StageState::kLifting;
      return CommandResult::kAccepted;
    case MotionType::kLand:
      if (s == StageState::kFault) return CommandResult::kRefusedFaultLatched;
      if (s == StageState::kLanded || s == StageState::kLanding) return CommandResult::kAlreadyThere;
      for (int a = 0; a < kAxes; ++a) {
        cancel(a);
        ref_[a] += pending_step_[a];
        pending_step_[a] = 0.0f;
      }
      // The ramp aims 1 mm beyond the stops, so the platen meets them at the
      // ramp's speed (a reference that stops exactly at the stop leaves the
      // loop's overshoot to decide the touchdown: 6.1 mm/s measured).
      ramp_[0] = {true, config_.rest_gap_m + 1e-3f, config_.lift_speed_m_per_s / config_.servo_rate_Hz};
      status_.state = StageState::kLanding;
      return CommandResult::kAccepted;
    case MotionType::kClearFault:
      if (s != StageState::kFault) return CommandResult::kRefusedNotFaulted;
      if (fault_landing_) return CommandResult::kRefusedBusy;  // still landing
      suspect_ = 0;
      status_.state = StageState::kLanded;
      status_.fault = FaultCode::kNone;
      return CommandResult::kAccepted;
    default:
      break;
  }
  if (s == StageState::kFault) return CommandResult::kRefusedFaultLatched;
  if (s != StageState::kReady) return CommandResult::kRefusedNotReady;
  if (cmd.type == MotionType::kHold) {
    for (int a = 0; a < kAxes; ++a) cancel(a);
    return CommandResult::kAccepted;
  }
  const int a = static_cast<int>(cmd.axis);
  if (a < 0 || a >= kAxes) return CommandResult::kRefusedOutOfRange;
  switch (cmd.type) {
    case MotionType::kStep: {
      const float target = ref_[a] + pending_step_[a] + cmd.delta;
      if (!finite(cmd.delta) || !reference_in_range(a, target)) return CommandResult::kRefusedOutOfRange;
      cancel(a);
      pending_step_[a] += cmd.delta;
      return CommandResult::kAccepted;
    }
    case MotionType::kMoveTo: {
      if (!reference_in_range(a, cmd.target)) return CommandResult::kRefusedOutOfRange;
      if (!positive_finite(cmd.velocity) || cmd.velocity > config_.max_ramp_speed[a]) {
        return CommandResult::kRefusedBadProfile;
      }
      cancel(a);
      ramp_[a] = {true, cmd.target, cmd.velocity / config_.servo_rate_Hz};
      return CommandResult::kAccepted;
    }
    case MotionType::kSinusoid: {
      if (!finite(cmd.amplitude) || cmd.amplitude < 0.0f || !reference_in_range(a, cmd.center + cmd.amplitude) ||
          !reference_in_range(a, cmd.center - cmd.amplitude)) {
        return CommandResult::kRefusedOutOfRange;
      }
      // Up to a tenth of the servo rate, so the sampled sine stays a sine.
      const float turns_per_tick = cmd.omega_rad_per_s / (kTwoPi * config_.servo_rate_Hz);
      if (!positive_finite(turns_per_tick) || turns_per_tick > 0.1f || !finite(cmd.phase_rad) ||
          std::fabs(cmd.phase_rad) > 2.0f * kTwoPi) {
        return CommandResult::kRefusedBadProfile;
      }
      cancel(a);
      Sinusoid& q = sine_[a];
      q.active = true;
      q.center = cmd.center;
      q.amplitude = cmd.amplitude;
      q.increment = static_cast<std::uint32_t>(static_cast<std::int64_t>(turns_per_tick * 4294967296.0f + 0.5f));
      q.phase = static_cast<std::uint32_t>(static_cast<std::int64_t>(cmd.phase_rad / kTwoPi * 4294967296.0f));
      return CommandResult::kAccepted;
    }
    default:
      return CommandResult::kUnsupported;
  }
}

// A fault's reaction depends on what is still trustworthy. Amplifiers off
// is NOT this stage's safe state above ~29 mm: there the magnets'
// attraction exceeds the weight and the platen would snap up onto the
// 18 mm stops. So while the gap encoder is good, a fault lands the platen
// under control onto its lower stops (the suspect axes' loops opened), and
// only then cuts the amplifiers; without the gap (its encoder lost or
// jumping, the gap outside its window, no fresh samples) nothing can be
// controlled and the amplifiers go off at once.
void PmlsmController::latch(FaultCode f, std::uint8_t suspect_axes) {
  suspect_ |= suspect_axes;
  const bool gap_good = (suspect_ & 1u) == 0u && f != FaultCode::kStaleFrames;
  if (status_.state == StageState::kFault) {
    if (!gap_good) fault_landing_ = false;  // a second fault took the gap away
    return;
  }
  status_.state = StageState::kFault;
  status_.fault = f;
  for (int a = 0; a < kAxes; ++a) {
    cancel(a);
    ref_[a] += pending_step_[a];
    pending_step_[a] = 0.0f;
  }
  fault_landing_ = gap_good;
  if (fault_landing_) {
    ramp_[0] = {true, config_.rest_gap_m + 1e-3f, config_.lift_speed_m_per_s / config_.servo_rate_Hz};
  }
}

void PmlsmController::reset_loops() {
  for (int a = 0; a < kAxes; ++a) {
    xi_[a][0] = xi_[a][1] = xi_[a][2] = 0.0f;
    filt_[a] = 0.0f;
  }
  loops_fresh_ = true;
  status_.saturated_ticks = 0;
}

// Sensor supervision; returns true when the loops may run this tick.
bool PmlsmController::supervise(const SensorSample& s) {
  const bool levitated = status_.state == StageState::kLifting || status_.state == StageState::kReady ||
                         status_.state == StageState::kLanding || fault_landing_;
  if (levitated) {
    if (s.status_flags & kAnyEncoderLoss) {
      latch(FaultCode::kBeamLoss, static_cast<std::uint8_t>(s.status_flags & kAnyEncoderLoss));
    }
    stale_ticks_ = (s.status_flags & kStaleFrame) ? stale_ticks_ + 1 : 0;
    if (stale_ticks_ > config_.max_stale_ticks) latch(FaultCode::kStaleFrames, 0x1Fu);
    for (int a = 0; a < kAxes && !first_sample_; ++a) {
      // int64: a wrapped or corrupted counter cannot overflow the difference.
      const std::int64_t d = std::int64_t{s.encoder_counts[a]} - std::int64_t{last_counts_[a]};
      const float speed = std::fabs(static_cast<float>(d)) * config_.encoder_resolution[a] * config_.servo_rate_Hz;
      if (speed > config_.max_speed[a]) latch(FaultCode::kCounterJump, static_cast<std::uint8_t>(1u << a));
    }
    static constexpr FaultCode kWindowFault[kAxes] = {FaultCode::kZEnvelope, FaultCode::kTravelX,
                                                      FaultCode::kTravelY, FaultCode::kTiltEnvelope,
                                                      FaultCode::kTiltEnvelope};
    for (int a = 0; a < kAxes; ++a) {
      if (!(status_.pose[a] >= config_.window_min[a] && status_.pose[a] <= config_.window_max[a])) {
        latch(kWindowFault[a], static_cast<std::uint8_t>(1u << a));
      }
    }
  } else {
    stale_ticks_ = 0;
  }
  for (int a = 0; a < kAxes; ++a) last_counts_[a] = s.encoder_counts[a];
  first_sample_ = false;
  return status_.state == StageState::kLifting || status_.state == StageState::kReady ||
         status_.state == StageState::kLanding || fault_landing_;
}

void PmlsmController::advance_references() {
  for (int a = 0; a < kAxes; ++a) {
    ref_[a] += pending_step_[a];
    pending_step_[a] = 0.0f;
    Ramp& r = ramp_[a];
    if (r.active) {
      const float d = r.target - ref_[a];
      if (std::fabs(d) <= r.step) {
        ref_[a] = r.target;
        r.active = false;
      } else {
        ref_[a] += d > 0.0f ? r.step : -r.step;
      }
    }
    Sinusoid& q = sine_[a];
    if (q.active) {
      ref_[a] = q.center + q.amplitude * (static_cast<float>(numeric::sin_q30(q.phase)) * kQ30);
      q.phase += q.increment;
    }
  }
  if (status_.state == StageState::kLifting && !ramp_[0].active) status_.state = StageState::kReady;
}

ActuatorCommand PmlsmController::step(const SensorSample& sample) {
  ++status_.tick;
  for (int a = 0; a < kAxes; ++a) {
    status_.pose[a] = static_cast<float>(sample.encoder_counts[a]) * config_.encoder_resolution[a];
  }
  const bool run = configured_ && supervise(sample);
  status_.phase_clamped = false;
  status_.horizontal_saturated = false;
  if (!run) {
    for (int m = 0; m < kMotors; ++m) {
      status_.i_d_A[m] = status_.i_q_A[m] = 0.0f;
      status_.phase_A[m][0] = status_.phase_A[m][1] = status_.phase_A[m][2] = 0.0f;
    }
    for (int a = 0; a < kAxes; ++a) status_.w[a] = 0.0f;
    status_.saturated_ticks = 0;
    status_.motion_active = false;
    return kSafeActuatorCommand;
  }
  advance_references();
  // A fault landing opens X and Z (they only need to coast) and any axis
  // whose encoder is suspect; a suspect tilt reads as level for (12).
  float y[kAxes];
  bool closed[kAxes];
  for (int a = 0; a < kAxes; ++a) {
    const bool suspect = fault_landing_ && (suspect_ & (1u << a)) != 0u;
    y[a] = suspect ? 0.0f : status_.pose[a];
    closed[a] = config_.axis[a].closed && !(fault_landing_ && (a == 1 || a == 2 || suspect));
  }
  float e[kAxes], edot[kAxes];
  for (int a = 0; a < kAxes; ++a) {
    e[a] = y[a] - ref_[a];
    if (loops_fresh_) filt_[a] = e[a];
    edot[a] = config_.derivative_filter_rad_per_s * (e[a] - filt_[a]);
    const RegulatorConfig& r = config_.axis[a];
    // (16): w = Ks [e e' xi] + Gamma xi, Gamma = [1 0 0].
    status_.w[a] = closed[a] ? r.Ks[0] * e[a] + r.Ks[1] * edot[a] + r.Ks[2] * xi_[a][0] + r.Ks[3] * xi_[a][1] +
                                  r.Ks[4] * xi_[a][2] + xi_[a][0]
                            : 0.0f;
  }
  loops_fresh_ = false;
  const bool rotation_loops = (config_.axis[3].closed || config_.axis[4].closed) &&
                              !(fault_landing_ && (suspect_ & 0x18u) == 0x18u);
  const LinearizedCurrents f = FeedbackLinearize(config_, y, status_.w, rotation_loops);
  status_.u_x_raw_A = f.u_x_raw_A;
  status_.u_z_raw_A = f.u_z_raw_A;
  status_.horizontal_saturated = f.u_x_A != f.u_x_raw_A || f.u_z_A != f.u_z_raw_A;
  // Internal models (14) with anti-windup (17), advanced by their ZOH.
  const float aw[kAxes] = {0.0f, f.u_x_A - f.u_x_raw_A, f.u_z_A - f.u_z_raw_A, 0.0f, 0.0f};
  for (int a = 0; a < kAxes; ++a) {
    if (closed[a]) {
      const float* E = config_.axis[a].E;
      const float in[3] = {E[0] * aw[a], E[1] * aw[a], e[a] + E[2] * aw[a]};
      float xn[3];
      for (int i = 0; i < 3; ++i) {
        const float* D = config_.xi_Ad_minus_I[i];
        const float* B = config_.xi_Bd[i];
        xn[i] = xi_[a][i] + ((D[0] * xi_[a][0] + D[1] * xi_[a][1] + D[2] * xi_[a][2]) +
                             (B[0] * in[0] + B[1] * in[1] + B[2] * in[2]));
      }
      for (int i = 0; i < 3; ++i) xi_[a][i] = xn[i];
    }
    filt_[a] += config_.derivative_filter_alpha * (e[a] - filt_[a]);
  }
  // Commutation: theta_e = pi s / tau from the mover's encoder; motors 2, 4
  // ride on X, motors 1, 3 on Z. Phase k lags by k * 120 degrees.
  const std::uint32_t phase_x = static_cast<std::uint32_t>(sample.encoder_counts[1]) * config_.phase_per_count_x;
  const std::uint32_t phase_z = static_cast<std::uint32_t>(sample.encoder_counts[2]) * config_.phase_per_count_z;
  ActuatorCommand out{};
  bool clamped = false;
  for (int m = 0; m < kMotors; ++m) {
    const std::uint32_t th = (m % 2 == 1) ? phase_x : phase_z;
    float id = f.i_d_A[m], iq = f.i_q_A[m];
    float ph[3];
    float peak = 0.0f;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t p = th - static_cast<std::uint32_t>(k) * kThirdTurn;
      const float c = static_cast<float>(numeric::cos_q30(p)) * kQ30;
      const float s = static_cast<float>(numeric::sin_q30(p)) * kQ30;
      ph[k] = id * c - iq * s;
      if (std::fabs(ph[k]) > peak) peak = std::fabs(ph[k]);
    }
    if (peak > config_.phase_peak_A) {
      // Star winding: the whole vector scales, its direction kept (what the
      // amplifiers would do anyway; done here so the command never exceeds them).
      const float scale = config_.phase_peak_A / peak;
      for (float& v : ph) v *= scale;
      id *= scale;
      iq *= scale;
      clamped = true;
    }
    status_.i_d_A[m] = id;
    status_.i_q_A[m] = iq;
    for (int k = 0; k < 3; ++k) status_.phase_A[m][k] = ph[k];
    out.dac_code[2 * m] = to_dac(ph[0], config_.amps_per_dac_code);
    out.dac_code[2 * m + 1] = to_dac(ph[1], config_.amps_per_dac_code);
  }
  out.amplifier_enable = true;
  status_.phase_clamped = clamped;
  status_.saturated_ticks = clamped ? status_.saturated_ticks + 1 : 0;
  for (int a = 0; a < kAxes; ++a) status_.reference[a] = ref_[a];
  bool moving = false;
  for (int a = 0; a < kAxes; ++a) moving = moving || ramp_[a].active || sine_[a].active;
  status_.motion_active = moving;
  // Landing ends on the stops: the gap encoder has read the stop itself
  // (half a count of margin for float rounding) for 20 ms, the loop still
  // following the ramp into them. Cutting the currents as soon as the
  // encoder reads within a count lets the platen fall the last count
  // (measured: 6.7 mm/s one count early, 4.4 mm/s at the first reading).
  const bool on_stops = y[0] >= config_.rest_gap_m - 0.5f * config_.encoder_resolution[0];
  const bool landing = status_.state == StageState::kLanding || fault_landing_;
  landing_hold_ticks_ = (landing && on_stops) ? landing_hold_ticks_ + 1 : 0;
  if (landing_hold_ticks_ > static_cast<std::uint32_t>(0.02f * config_.servo_rate_Hz)) {
    landing_hold_ticks_ = 0;
    if (fault_landing_) {
      fault_landing_ = false;  // landed; the fault stays latched
      return kSafeActuatorCommand;
    }
    status_.state = StageState::kLanded;
    return kSafeActuatorCommand;
  }
  if (status_.saturated_ticks > config_.max_saturated_ticks) {
    if (fault_landing_) {
      fault_landing_ = false;  // not even the landing can be held
      return kSafeActuatorCommand;
    }
    latch(FaultCode::kCurrentSaturation, 0u);
    status_.saturated_ticks = 0;
  }
  return out;
}

}  // namespace maglev::pmlsm_stage
