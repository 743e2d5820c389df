#include "maglev/io/code_placement.hpp"
#include "maglev/supervisor/supervisor.hpp"

#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/int64_double.hpp"

#include <cmath>

namespace maglev::kernel {
namespace {

bool positive(float v) { return v > 0.0f && v < 1e30f; }  // also rejects NaN
// |v| by the FPU's VABS (one instruction; a compare-and-negate was 4 on the M7).
// Every use compares it with a limit: the same outcome for every v, NaN included.
float abs_f(float v) { return std::fabs(v); }

constexpr std::int16_t kAdcRailHigh = 32767;
constexpr std::int16_t kAdcRailLow = -32768;
bool at_rail(std::int16_t code) { return code >= kAdcRailHigh || code <= kAdcRailLow; }


// A run counter of consecutive ticks a condition held (saturating).
std::uint16_t next_run(bool holds, std::uint16_t run) {
  return holds ? static_cast<std::uint16_t>(run < 0xFFFF ? run + 1 : run) : 0;
}

// Field by field (no memcmp over padding bytes, whose value is unspecified).
// The interferometer counts are not compared here: the caller has their
// differences already, and a moving or noisy stage differs there first.
bool same_sample_but_counts(const io::SensorSample& a, const io::SensorSample& b) {
  bool same = a.status_flags == b.status_flags;
  for (int k = 0; k < io::kDisplacementSensors; ++k) same = same && a.displacement_adc[k] == b.displacement_adc[k];
  for (int k = 0; k < io::kHallChannels; ++k) same = same && a.hall_adc[k] == b.hall_adc[k];
  for (int k = 0; k < io::kCoils; ++k) same = same && a.coil_current_adc[k] == b.coil_current_adc[k];
  return same;
}

}  // namespace

MAGLEV_CONFIG_CODE SupervisorConfigError validate(const SupervisorConfig& c, float servo_rate_Hz) {
  if (!(c.x_min_m < c.x_max_m) || !(c.y_min_m < c.y_max_m) || c.x_min_m < -0.1f ||
      c.x_max_m > 0.1f || c.y_min_m < -0.1f || c.y_max_m > 0.1f ||
      !positive(c.theta_z_limit_rad) || c.theta_z_limit_rad > 0.1f) {
    return SupervisorConfigError::kBadTravel;
  }
  // The z envelope must contain the rest position. Its top is a stage's
  // (a profile's z travel + 2 um: the seed's 40 um, paper 000 Sec. V);
  // prepare_config bounds it by the laser displacement sensors' range, this
  // only by 1 mm (the seed's 100 um cap here refused a lab stage that
  // levitates higher).
  if (!(c.z_min_m < 0.0f) || !(c.z_max_m > 0.0f) || c.z_max_m > 1e-3f || c.z_min_m < -100e-6f ||
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

MAGLEV_CONFIG_CODE SupervisorSettings PrepareSupervisorSettings(const SupervisorConfig& c, float servo_rate_Hz) {
  SupervisorSettings st{};
  st.config = c;
  // The two durations counted in ticks of the default 2.5 kHz rate (50 ms of
  // saturation, 4 ms of current mismatch) keep their time at any servo rate.
  const double per_default_tick = static_cast<double>(servo_rate_Hz) / io::stage::kServoRate_Hz;
  auto held = [per_default_tick](std::uint16_t ticks) {
    const double n = std::round(static_cast<double>(ticks) * per_default_tick);
    return static_cast<std::uint16_t>(n < 1.0 ? 1.0 : (n > 65535.0 ? 65535.0 : n));
  };
  st.config.max_saturated_ticks = held(c.max_saturated_ticks);
  st.config.current_mismatch_ticks = held(c.current_mismatch_ticks);
  st.thermal_alpha = 1.0f / (c.thermal_time_constant_s * servo_rate_Hz);
  st.max_count_step = static_cast<std::int32_t>(c.max_interferometer_speed_m_per_s / servo_rate_Hz /
                                                c.interferometer_lsb_m);
  // The limits validate() admits are positive where compared with |v|, so
  // those thresholds are positive and fit the uint64 compare.
  const auto above = [](float limit) { return numeric::PicoFirstAbove(limit); };
  const auto below = [](float limit) { return numeric::PicoFirstAtOrAbove(limit); };
  const auto mag_above = [](float limit) { return static_cast<std::uint64_t>(numeric::PicoFirstAbove(limit)); };
  SupervisorPicoLimits& p = st.pico;
  p.x_below = below(c.x_min_m);
  p.x_above = above(c.x_max_m);
  p.y_below = below(c.y_min_m);
  p.y_above = above(c.y_max_m);
  p.z_below = below(c.z_min_m);
  p.z_above = above(c.z_max_m);
  p.theta_z_above = mag_above(c.theta_z_limit_rad);
  p.tilt_above = mag_above(c.tilt_limit_rad);
  for (int a = 0; a < kSequencedAxes; ++a) p.following_above[a] = mag_above(c.following_error_limit[a]);
  return st;
}

MAGLEV_CONFIG_CODE void Supervisor::configure(const SupervisorSettings& st) {
  config_ = st.config;
  thermal_alpha_ = st.thermal_alpha;
  max_count_step_ = st.max_count_step;
  pico_ = st.pico;
}

MAGLEV_CONFIG_CODE void Supervisor::reset() {
  status_ = SupervisorStatus{};
  have_previous_ = false;
  stale_run_ = 0;
  identical_run_ = 0;
  for (auto& r : mismatch_run_) r = 0;
  mismatch_running_ = false;
  overrun_run_ = 0;
  for (float& v : i2_filtered_) v = 0.0f;
}

void Supervisor::note(Trip& t, bool tripped, FaultCode code, std::uint8_t axis, float value) {
  if (tripped && t.code == FaultCode::kNone) {
    t.code = code;
    t.axis = axis;
    t.value = value;
  }
}

// Every check's outcome of one tick, one bit per check instance (axis, beam,
// sensor or coil). Computed in one pass with no attribution; the priority
// walk (attribute) runs only on the rare tick where any bit is set.
struct Supervisor::Checks {
  std::uint8_t beam_lost;     // kBeamLoss, bit = beam
  std::uint8_t jump;          // kCounterJump, bit = beam
  std::int32_t count_delta[io::kInterferometerAxes];
  std::uint8_t lds_bad;       // kDisplacementOutOfRange, bit = sensor
  // The coil checks: any coil tripping (attribute() finds which, coil_masks()).
  bool monitor_rail;    // kCurrentMonitorOutOfRange
  bool mismatch;        // kCurrentMismatch
  bool peak_measured;   // kPeakCurrentMeasured
  bool peak_commanded;  // kPeakCurrentCommanded
  bool rms;             // kRmsCurrent
  std::uint8_t limits;          // bit a: kTravelX/Y/ThetaZ (0..2), kZEnvelope (3), kTiltEnvelope (4, 5)
  std::uint8_t following;       // kFollowingError, bit = axis
  bool stale, frozen, adc_fault, overrun, saturation;
};

const SupervisorStatus& Supervisor::step(const SupervisorInputs& in) {
  const io::SensorSample& s = *in.sample;
  Checks c;
  c.jump = c.following = 0;

  // --- sensor plausibility --------------------------------------------------
  const std::uint16_t flags = s.status_flags;
  c.beam_lost = static_cast<std::uint8_t>(flags & (io::kBeamLoss0 | io::kBeamLoss1 | io::kBeamLoss2));
  std::uint32_t counts_moved = 0;
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    // Wrap-safe difference of the 32-bit hardware counter.
    const auto delta = static_cast<std::int32_t>(s.interferometer_counts[a] - previous_counts_[a]);
    const std::int32_t mag = delta < 0 ? -delta : delta;
    c.count_delta[a] = delta;
    counts_moved |= static_cast<std::uint32_t>(delta);
    c.jump = static_cast<std::uint8_t>(c.jump | ((have_previous_ && mag > max_count_step_) ? (1u << a) : 0u));
    previous_counts_[a] = s.interferometer_counts[a];
  }
  stale_run_ = next_run((flags & io::kStaleFrame) != 0, stale_run_);
  // Only while a loop is closed: a landed stage's sensors may legitimately
  // sit still (and the check is armed again before the first loop closes).
  const bool identical =
      have_previous_ && in.closed_axes != 0 && counts_moved == 0 && same_sample_but_counts(s, previous_sample_);
  identical_run_ = next_run(identical, identical_run_);
  previous_sample_ = s;
  have_previous_ = true;
  c.frozen = config_.max_identical_samples != 0 && identical_run_ > config_.max_identical_samples;
  c.stale = stale_run_ > config_.max_consecutive_stale_frames;
  c.adc_fault = (flags & io::kAdcFault) != 0;
  c.lds_bad = static_cast<std::uint8_t>(in.displacement_bad & ((1u << io::kDisplacementSensors) - 1u));

  // --- timing ----------------------------------------------------------------
  overrun_run_ = next_run(in.tick_overrun, overrun_run_);
  c.overrun = overrun_run_ > config_.max_consecutive_overruns;

  // --- currents: one pass over the coils -------------------------------------
  saturated_run_ = next_run(in.current_limited, saturated_run_);
  c.saturation = saturated_run_ >= config_.max_saturated_ticks;
  // A normal tick needs only "does any coil trip": per check one maximum (VMAXNM)
  // or one OR, compared once after the loop. The tick where one does trips
  // attribute(), which finds the coil from the same values (coil_masks()).
  // fmax ignores a NaN operand and a NaN compares false: a NaN current trips
  // neither form. (The per-coil masks this replaced cost 106 M7 instructions
  // a tick more at the replay's Ready maximum.)
  const CoilLimits lim = coil_limits();
  const float mismatch_A = config_.current_mismatch_A;
  std::uint32_t monitor_rail = 0;
  float max_off = 0.0f, max_measured = 0.0f, max_commanded = 0.0f, max_i2 = 0.0f;
#pragma GCC unroll 8
  for (int j = 0; j < io::kCoils; ++j) {
    const float m = in.coil_current_measured_A[j];
    const float i = in.coil_current_cmd_A[j];
    // Like the other maxima: "is any coil off" is one compare after the
    // loop; the coils that are off are found below only when one is (a
    // per-coil mask here cost ~5 M7 instructions a coil on every tick).
    max_off = std::fmax(max_off, abs_f(m - i));
    // Thermal model: first-order low-pass of i^2 with the coil's time constant.
    const float i2 = i2_filtered_[j] + thermal_alpha_ * (i * i - i2_filtered_[j]);
    i2_filtered_[j] = i2;
    monitor_rail |= at_rail(s.coil_current_adc[j]) ? 1u : 0u;
    max_measured = std::fmax(max_measured, abs_f(m));
    max_commanded = std::fmax(max_commanded, abs_f(i));
    max_i2 = std::fmax(max_i2, i2);
  }
  // The mismatch runs: while no coil is off and every run is zero (nearly
  // every tick) each stays zero, and the per-coil counting (~50 M7
  // instructions a tick) is skipped. A coil is off where |m - i| exceeds
  // the limit, so none is unless the maximum does (a NaN difference is off
  // in neither form: fmax ignores it, and it compares false).
  std::uint32_t max_run = 0;
  if (max_off > mismatch_A || mismatch_running_) {
#pragma GCC unroll 8
    for (int j = 0; j < io::kCoils; ++j) {
      const bool off = abs_f(in.coil_current_measured_A[j] - in.coil_current_cmd_A[j]) > mismatch_A;
      const std::uint16_t run = next_run(off, mismatch_run_[j]);
      mismatch_run_[j] = run;
      max_run = run > max_run ? run : max_run;
    }
  }
  mismatch_running_ = max_run != 0;
  c.monitor_rail = monitor_rail != 0;
  c.mismatch = max_run >= config_.current_mismatch_ticks;
  c.peak_measured = max_measured > lim.measured_A;
  c.peak_commanded = max_commanded > lim.commanded_A;
  c.rms = max_i2 > lim.rms2_A2;

  // --- position limits ---------------------------------------------------------
  // In pm / prad against the integer thresholds (configure()): the outcome of
  // comparing PicoToSi of each with the float limits, for every value.
  const std::int64_t* p = in.pose_pico;
  const std::int64_t* r = in.reference_pico;
  const bool travel = in.positions_valid, envelope = in.envelope_active;
  using numeric::UnsignedMagnitude64;
  c.limits = static_cast<std::uint8_t>(
      ((travel && (p[0] < pico_.x_below || p[0] >= pico_.x_above)) ? 1u : 0u) |
      ((travel && (p[1] < pico_.y_below || p[1] >= pico_.y_above)) ? 2u : 0u) |
      ((travel && UnsignedMagnitude64(p[2]) >= pico_.theta_z_above) ? 4u : 0u) |
      ((envelope && (p[3] < pico_.z_below || p[3] >= pico_.z_above)) ? 8u : 0u) |
      ((envelope && UnsignedMagnitude64(p[4]) >= pico_.tilt_above) ? 16u : 0u) |
      ((envelope && UnsignedMagnitude64(p[5]) >= pico_.tilt_above) ? 32u : 0u));
  for (int a = 0; a < kSequencedAxes; ++a) {
    const bool over = UnsignedMagnitude64(r[a] - p[a]) >= pico_.following_above[a];
    c.following = static_cast<std::uint8_t>(c.following | (over ? (1u << a) : 0u));
  }
  c.following = static_cast<std::uint8_t>(c.following & in.closed_axes);

  // --- latch and reaction --------------------------------------------------------
  const bool any = (in.stage_profile_error | c.beam_lost | c.jump | in.beam_glitch | c.lds_bad | c.limits |
                    c.following) != 0 ||
                   c.monitor_rail || c.mismatch || c.peak_measured || c.peak_commanded || c.rms || c.stale || c.frozen || c.adc_fault || c.overrun || c.saturation;
  // attribute() reads a copy, made only on a tick where a check trips: c's
  // own address is never taken, so GCC keeps its fields in registers (as a
  // reference argument it was stored field by field on every tick).
  Trip t{};
  if (any) {
    const Checks tripped = c;
    t = attribute(in, tripped);
  }
  const bool actuator_failed = c.mismatch || c.peak_measured;  // it cannot land the stage
  status_.in_plane_sensors_valid = c.beam_lost == 0 && c.jump == 0 && !c.stale && !c.frozen;
  status_.z_sensors_valid = c.lds_bad == 0 && !c.adc_fault;
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

float Supervisor::rms_current_A(int j) const { return std::sqrt(i2_filtered_[j]); }

Supervisor::CoilLimits Supervisor::coil_limits() const {
  return CoilLimits{config_.peak_current_A + config_.measured_current_margin_A, config_.peak_current_A * 1.001f,
                    config_.rms_current_A * config_.rms_current_A};
}

// The coil checks per coil, from the values step() compared this tick (the
// inputs, the mismatch runs and the thermal state it left): the same
// outcome coil by coil as its maxima, bit j = coil j.
MAGLEV_FAULT_PATH_CODE Supervisor::CoilMasks Supervisor::coil_masks(const SupervisorInputs& in) const {
  const CoilLimits lim = coil_limits();
  CoilMasks m{};
  for (int j = 0; j < io::kCoils; ++j) {
    const std::uint32_t bit = 1u << j;
    m.monitor_rail |= at_rail(in.sample->coil_current_adc[j]) ? bit : 0u;
    m.mismatch |= mismatch_run_[j] >= config_.current_mismatch_ticks ? bit : 0u;
    m.peak_measured |= abs_f(in.coil_current_measured_A[j]) > lim.measured_A ? bit : 0u;
    m.peak_commanded |= abs_f(in.coil_current_cmd_A[j]) > lim.commanded_A ? bit : 0u;
    m.rms |= i2_filtered_[j] > lim.rms2_A2 ? bit : 0u;
  }
  return m;
}

// The first tripping check in priority order -- the most fundamental cause
// first (a lost beam also produces a following error) -- with its axis and
// value. The order is the contract (tests/kernel/supervisor): configuration,
// sensors, timing, currents, positions.
MAGLEV_FAULT_PATH_CODE Supervisor::Trip Supervisor::attribute(const SupervisorInputs& in, const Checks& c) const {
  const io::SensorSample& s = *in.sample;
  Trip t;
  const auto bit = [](std::uint32_t mask, int k) { return (mask & (1u << k)) != 0; };
  const auto u8 = [](int k) { return static_cast<std::uint8_t>(k); };
  const CoilMasks cm = coil_masks(in);
  note(t, in.stage_profile_error != 0, FaultCode::kStageProfileInvalid, kNoAxis,
       static_cast<float>(in.stage_profile_error));
  for (int a = 0; a < io::kInterferometerAxes; ++a) note(t, bit(c.beam_lost, a), FaultCode::kBeamLoss, u8(a), 0.0f);
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    note(t, bit(c.jump, a), FaultCode::kCounterJump, u8(a),
         static_cast<float>(c.count_delta[a]) * config_.interferometer_lsb_m);
  }
  // A glitch that sensors_to_pose repaired: the pose stays valid (the step
  // was replaced by the previous one and the jump taken as an offset), but a
  // sensor that glitches once is not trusted to hold the stage: land. A
  // 22 um jump of one beam during a landing otherwise read as motion, the
  // in-plane loops chased it and a corner touched down at 0.73 mm/s
  // (campaign seed 1, run 5693).
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    note(t, bit(in.beam_glitch, a), FaultCode::kCounterGlitch, u8(a), in.beam_glitch_m[a]);
  }
  note(t, c.stale, FaultCode::kStaleFrames, kNoAxis, static_cast<float>(stale_run_));
  note(t, c.frozen, FaultCode::kFrozenSample, kNoAxis, static_cast<float>(identical_run_));
  note(t, c.adc_fault, FaultCode::kAdcFault, kNoAxis, 0.0f);
  for (int k = 0; k < io::kDisplacementSensors; ++k) {
    note(t, bit(c.lds_bad, k), FaultCode::kDisplacementOutOfRange, u8(k), static_cast<float>(s.displacement_adc[k]));
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, bit(cm.monitor_rail, j), FaultCode::kCurrentMonitorOutOfRange, u8(j),
         static_cast<float>(s.coil_current_adc[j]));
  }
  note(t, c.overrun, FaultCode::kTickOverrun, kNoAxis, static_cast<float>(overrun_run_));
  note(t, c.saturation, FaultCode::kCurrentSaturation, kNoAxis, static_cast<float>(saturated_run_));
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, bit(cm.mismatch, j), FaultCode::kCurrentMismatch, u8(j), in.coil_current_measured_A[j]);
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, bit(cm.peak_measured, j), FaultCode::kPeakCurrentMeasured, u8(j), in.coil_current_measured_A[j]);
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, bit(cm.peak_commanded, j), FaultCode::kPeakCurrentCommanded, u8(j), in.coil_current_cmd_A[j]);
  }
  for (int j = 0; j < io::kCoils; ++j) {
    note(t, bit(cm.rms, j), FaultCode::kRmsCurrent, u8(j), rms_current_A(j));
  }
  const auto pose = [&in](int a) { return numeric::PicoToSi(in.pose_pico[a]); };
  note(t, bit(c.limits, 0), FaultCode::kTravelX, 0, pose(0));
  note(t, bit(c.limits, 1), FaultCode::kTravelY, 1, pose(1));
  note(t, bit(c.limits, 2), FaultCode::kTravelThetaZ, 2, pose(2));
  note(t, bit(c.limits, 3), FaultCode::kZEnvelope, 3, pose(3));
  for (int a = 4; a < kSequencedAxes; ++a) note(t, bit(c.limits, a), FaultCode::kTiltEnvelope, u8(a), pose(a));
  for (int a = 0; a < kSequencedAxes; ++a) {
    note(t, bit(c.following, a), FaultCode::kFollowingError, u8(a),
         numeric::PicoToSi(in.reference_pico[a] - in.pose_pico[a]));
  }
  return t;
}

MAGLEV_CONFIG_CODE bool Supervisor::clear_fault() {
  if (status_.active != FaultCode::kNone) return false;
  status_.first_fault = FaultRecord{};
  status_.reaction = FaultReaction::kNone;
  return true;
}

MAGLEV_ENUM_TO_STRING(FaultCode, MAGLEV_FAULT_CODES)

}  // namespace maglev::kernel
