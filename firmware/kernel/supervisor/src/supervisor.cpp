#include "maglev/supervisor/supervisor.hpp"

#include "maglev/io/stage_parameters.hpp"

#include <cmath>

namespace maglev::kernel {
namespace {

bool positive(float v) { return v > 0.0f && v < 1e30f; }  // also rejects NaN
float abs_f(float v) { return v < 0.0f ? -v : v; }

constexpr std::int16_t kAdcRailHigh = 32767;
constexpr std::int16_t kAdcRailLow = -32768;
bool at_rail(std::int16_t code) { return code >= kAdcRailHigh || code <= kAdcRailLow; }

// A check that tripped this tick. Evaluated in priority order: the most
// fundamental cause first (a lost beam also produces a following error).
struct Trip {
  FaultCode code = FaultCode::kNone;
  std::uint8_t axis = kNoAxis;
  float value = 0.0f;
};

// A run counter of consecutive ticks a condition held (saturating).
std::uint16_t next_run(bool holds, std::uint16_t run) {
  return holds ? static_cast<std::uint16_t>(run < 0xFFFF ? run + 1 : run) : 0;
}

// Field by field (no memcmp over padding bytes, whose value is unspecified).
bool same_sample(const io::SensorSample& a, const io::SensorSample& b) {
  bool same = a.status_flags == b.status_flags;
  for (int k = 0; k < io::kInterferometerAxes; ++k) same = same && a.interferometer_counts[k] == b.interferometer_counts[k];
  for (int k = 0; k < io::kDisplacementSensors; ++k) same = same && a.displacement_adc[k] == b.displacement_adc[k];
  for (int k = 0; k < io::kHallChannels; ++k) same = same && a.hall_adc[k] == b.hall_adc[k];
  for (int k = 0; k < io::kCoils; ++k) same = same && a.coil_current_adc[k] == b.coil_current_adc[k];
  return same;
}

void note(Trip& t, bool tripped, FaultCode code, std::uint8_t axis, float value) {
  // Branch-light: every check is computed; only the first tripping one is kept.
  if (tripped && t.code == FaultCode::kNone) {
    t.code = code;
    t.axis = axis;
    t.value = value;
  }
}

}  // namespace

SupervisorConfigError validate(const SupervisorConfig& c, float servo_rate_Hz) {
  if (!(c.x_min_m < c.x_max_m) || !(c.y_min_m < c.y_max_m) || c.x_min_m < -0.1f ||
      c.x_max_m > 0.1f || c.y_min_m < -0.1f || c.y_max_m > 0.1f ||
      !positive(c.theta_z_limit_rad) || c.theta_z_limit_rad > 0.1f) {
    return SupervisorConfigError::kBadTravel;
  }
  // The z envelope must contain the rest position and stay inside the 40 um
  // levitation range (paper 000 Sec. V) -- anything larger risks the coils.
  if (!(c.z_min_m < 0.0f) || !(c.z_max_m > 0.0f) || c.z_max_m > 100e-6f || c.z_min_m < -100e-6f ||
      !positive(c.tilt_limit_rad) || c.tilt_limit_rad > 2e-3f) {
    return SupervisorConfigError::kBadEnvelope;
  }
  for (float f : c.following_error_limit) {
    if (!positive(f) || f > 0.01f) return SupervisorConfigError::kBadFollowingError;
  }
  if (!positive(c.peak_current_A) || c.peak_current_A > 5.0f || !positive(c.rms_current_A) ||
      c.rms_current_A > c.peak_current_A || !(c.measured_current_margin_A >= 0.0f) ||
      c.measured_current_margin_A > 2.0f || !positive(c.current_mismatch_A) || c.current_mismatch_A > 10.0f ||
      c.current_mismatch_ticks == 0) {
    return SupervisorConfigError::kBadCurrentLimit;
  }
  if (!positive(c.thermal_time_constant_s) || c.thermal_time_constant_s * servo_rate_Hz < 10.0f ||
      c.thermal_time_constant_s > 3600.0f) {
    return SupervisorConfigError::kBadThermal;
  }
  if (!positive(c.max_interferometer_speed_m_per_s) || !positive(c.interferometer_lsb_m) ||
      !(servo_rate_Hz > 0.0f) ||
      c.max_interferometer_speed_m_per_s / servo_rate_Hz / c.interferometer_lsb_m > 1e9f) {
    return SupervisorConfigError::kBadPlausibility;
  }
  return SupervisorConfigError::kOk;
}

void Supervisor::configure(const SupervisorConfig& c, float servo_rate_Hz) {
  config_ = c;
  // The two durations counted in ticks of the default 2.5 kHz rate (50 ms of
  // saturation, 4 ms of current mismatch) keep their time at any servo rate.
  const double per_default_tick = static_cast<double>(servo_rate_Hz) / io::stage::kServoRate_Hz;
  auto held = [per_default_tick](std::uint16_t ticks) {
    const double n = std::round(static_cast<double>(ticks) * per_default_tick);
    return static_cast<std::uint16_t>(n < 1.0 ? 1.0 : (n > 65535.0 ? 65535.0 : n));
  };
  config_.max_saturated_ticks = held(c.max_saturated_ticks);
  config_.current_mismatch_ticks = held(c.current_mismatch_ticks);
  thermal_alpha_ = 1.0f / (c.thermal_time_constant_s * servo_rate_Hz);
  max_count_step_ = static_cast<std::int32_t>(c.max_interferometer_speed_m_per_s / servo_rate_Hz /
                                              c.interferometer_lsb_m);
}

void Supervisor::reset() {
  status_ = SupervisorStatus{};
  have_previous_ = false;
  stale_run_ = 0;
  identical_run_ = 0;
  for (auto& r : mismatch_run_) r = 0;
  overrun_run_ = 0;
  for (float& v : i2_filtered_) v = 0.0f;
}

const SupervisorStatus& Supervisor::step(const SupervisorInputs& in) {
  const io::SensorSample& s = *in.sample;
  Trip t;

  // --- configuration: first, so that it names the reason ---------------------
  note(t, in.stage_profile_error != 0, FaultCode::kStageProfileInvalid, kNoAxis,
       static_cast<float>(in.stage_profile_error));

  // --- sensor plausibility --------------------------------------------------
  const std::uint16_t flags = s.status_flags;
  const std::uint16_t beam_bits = io::kBeamLoss0 | io::kBeamLoss1 | io::kBeamLoss2;
  const std::uint16_t lds_bits =
      io::kDisplacementOutOfRange0 | io::kDisplacementOutOfRange1 | io::kDisplacementOutOfRange2;
  const bool beam_loss = (flags & beam_bits) != 0;
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    const bool lost = (flags & (1u << a)) != 0;
    note(t, lost, FaultCode::kBeamLoss, static_cast<std::uint8_t>(a), 0.0f);
  }
  bool jump = false;
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    // Wrap-safe difference of the 32-bit hardware counter.
    const auto delta = static_cast<std::int32_t>(s.interferometer_counts[a] - previous_counts_[a]);
    const std::int32_t mag = delta < 0 ? -delta : delta;
    const bool j = have_previous_ && mag > max_count_step_;
    jump = jump || j;
    note(t, j, FaultCode::kCounterJump, static_cast<std::uint8_t>(a),
         static_cast<float>(delta) * config_.interferometer_lsb_m);
    previous_counts_[a] = s.interferometer_counts[a];
  }
  // A glitch that sensors_to_pose repaired: the pose stays valid (the step
  // was replaced by the previous one and the jump taken as an offset), but a
  // sensor that glitches once is not trusted to hold the stage: land. A
  // 22 um jump of one beam during a landing otherwise read as motion, the
  // in-plane loops chased it and a corner touched down at 0.73 mm/s
  // (campaign seed 1, run 5693).
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    note(t, (in.beam_glitch & (1u << a)) != 0, FaultCode::kCounterGlitch, static_cast<std::uint8_t>(a),
         in.beam_glitch_m[a]);
  }
  const bool stale = (flags & io::kStaleFrame) != 0;
  stale_run_ = next_run(stale, stale_run_);
  // Only while a loop is closed: a landed stage's sensors may legitimately
  // sit still (and the check is armed again before the first loop closes).
  const bool identical = have_previous_ && in.closed_axes != 0 && same_sample(s, previous_sample_);
  identical_run_ = next_run(identical, identical_run_);
  previous_sample_ = s;
  have_previous_ = true;
  const bool frozen = config_.max_identical_samples != 0 && identical_run_ > config_.max_identical_samples;
  const bool stale_fault = stale_run_ > config_.max_consecutive_stale_frames || frozen;
  note(t, stale_run_ > config_.max_consecutive_stale_frames, FaultCode::kStaleFrames, kNoAxis,
       static_cast<float>(stale_run_));
  note(t, frozen, FaultCode::kFrozenSample, kNoAxis, static_cast<float>(identical_run_));
  const bool adc_fault = (flags & io::kAdcFault) != 0;
  note(t, adc_fault, FaultCode::kAdcFault, kNoAxis, 0.0f);
  bool lds_bad = (flags & lds_bits) != 0;
  for (int k = 0; k < io::kDisplacementSensors; ++k) {
    const bool bad = (flags & (io::kDisplacementOutOfRange0 << k)) != 0 || at_rail(s.displacement_adc[k]);
    lds_bad = lds_bad || bad;
    note(t, bad, FaultCode::kDisplacementOutOfRange, static_cast<std::uint8_t>(k),
         static_cast<float>(s.displacement_adc[k]));
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, at_rail(s.coil_current_adc[j]), FaultCode::kCurrentMonitorOutOfRange,
         static_cast<std::uint8_t>(j), static_cast<float>(s.coil_current_adc[j]));
  }

  // --- timing ----------------------------------------------------------------
  overrun_run_ = next_run(in.tick_overrun, overrun_run_);
  note(t, overrun_run_ > config_.max_consecutive_overruns, FaultCode::kTickOverrun, kNoAxis,
       static_cast<float>(overrun_run_));

  // --- currents ----------------------------------------------------------------
  saturated_run_ = next_run(in.current_limited, saturated_run_);
  note(t, saturated_run_ >= config_.max_saturated_ticks, FaultCode::kCurrentSaturation, kNoAxis,
       static_cast<float>(saturated_run_));
  const float measured_limit = config_.peak_current_A + config_.measured_current_margin_A;
  bool actuator_failed = false;
  for (int j = 0; j < io::kCoils; ++j) {
    const bool off = abs_f(in.coil_current_measured_A[j] - in.coil_current_cmd_A[j]) > config_.current_mismatch_A;
    mismatch_run_[j] = next_run(off, mismatch_run_[j]);
    const bool broken = mismatch_run_[j] >= config_.current_mismatch_ticks;
    actuator_failed = actuator_failed || broken;  // the actuator does not follow: it cannot land the stage
    note(t, broken, FaultCode::kCurrentMismatch, static_cast<std::uint8_t>(j), in.coil_current_measured_A[j]);
  }
  for (int j = 0; j < io::kCoils; ++j) {
    const float m = in.coil_current_measured_A[j];
    const bool over = abs_f(m) > measured_limit;
    actuator_failed = actuator_failed || over;
    note(t, over, FaultCode::kPeakCurrentMeasured, static_cast<std::uint8_t>(j), m);
  }
  const float rms2_limit = config_.rms_current_A * config_.rms_current_A;
  for (int j = 0; j < io::kCoils; ++j) {
    const float i = in.coil_current_cmd_A[j];
    note(t, abs_f(i) > config_.peak_current_A * 1.001f, FaultCode::kPeakCurrentCommanded,
         static_cast<std::uint8_t>(j), i);
    // Thermal model: first-order low-pass of i^2 with the coil's time constant.
    i2_filtered_[j] += thermal_alpha_ * (i * i - i2_filtered_[j]);
    status_.rms_current_A[j] = std::sqrt(i2_filtered_[j]);
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, i2_filtered_[j] > rms2_limit, FaultCode::kRmsCurrent, static_cast<std::uint8_t>(j),
         status_.rms_current_A[j]);
  }

  // --- position limits ---------------------------------------------------------
  const float x = in.pose[0], y = in.pose[1], tz = in.pose[2], z = in.pose[3];
  note(t, in.positions_valid && (x < config_.x_min_m || x > config_.x_max_m), FaultCode::kTravelX, 0, x);
  note(t, in.positions_valid && (y < config_.y_min_m || y > config_.y_max_m), FaultCode::kTravelY, 1, y);
  note(t, in.positions_valid && abs_f(tz) > config_.theta_z_limit_rad, FaultCode::kTravelThetaZ, 2, tz);
  note(t, in.envelope_active && (z < config_.z_min_m || z > config_.z_max_m), FaultCode::kZEnvelope, 3, z);
  for (int a = 4; a < kSequencedAxes; ++a) {
    note(t, in.envelope_active && abs_f(in.pose[a]) > config_.tilt_limit_rad, FaultCode::kTiltEnvelope,
         static_cast<std::uint8_t>(a), in.pose[a]);
  }
  for (int a = 0; a < kSequencedAxes; ++a) {
    const bool closed = (in.closed_axes & (1u << a)) != 0;
    note(t, closed && abs_f(in.following_error[a]) > config_.following_error_limit[a],
         FaultCode::kFollowingError, static_cast<std::uint8_t>(a), in.following_error[a]);
  }

  // --- latch and reaction --------------------------------------------------------
  status_.in_plane_sensors_valid = !beam_loss && !jump && !stale_fault;
  status_.z_sensors_valid = !lds_bad && !adc_fault;
  status_.active = t.code;
  if (t.code != FaultCode::kNone) {
    ++status_.fault_count;
    if (status_.first_fault.code == FaultCode::kNone) {
      status_.first_fault = FaultRecord{t.code, in.tick, t.axis, t.value};
    }
  }
  if (status_.first_fault.code != FaultCode::kNone) {
    // Landing needs the in-plane loops (they stabilise the floating platen)
    // and an actuator that follows its commands.
    const bool can_land = status_.in_plane_sensors_valid && !actuator_failed;
    const FaultReaction wanted = can_land ? FaultReaction::kLand : FaultReaction::kCurrentsOff;
    if (static_cast<std::uint8_t>(wanted) > static_cast<std::uint8_t>(status_.reaction)) {
      status_.reaction = wanted;
    }
  }
  return status_;
}

bool Supervisor::clear_fault() {
  if (status_.active != FaultCode::kNone) return false;
  status_.first_fault = FaultRecord{};
  status_.reaction = FaultReaction::kNone;
  return true;
}

MAGLEV_ENUM_TO_STRING(FaultCode, MAGLEV_FAULT_CODES)

}  // namespace maglev::kernel
