// The supervisor: limits, sensor plausibility and the fault latch.
//
// Every tick it evaluates EVERY check into one bit each (bounded cost, one
// pass); only on a tick where a bit is set does it walk the checks in their
// priority order to name the first (code, axis, value). The first that trips
// while nothing is latched becomes the first-fault
// record (code, tick, axis, value). The reaction is the safest one still
// possible: a controlled landing while the in-plane sensors (x, y, theta_z
// interferometers) are valid -- the in-plane loops are what keep the floating
// platen stable -- and currents off otherwise. Reactions only escalate
// (land -> currents off), never relax, until clear_fault().
#pragma once

#include "maglev/io/enum_names.hpp"

#include <cstdint>

#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/sequencer/sequencer.hpp"

namespace maglev::kernel {

// FaultCode: value and name of every enumerator, defined once (the enum and
// to_string() are generated from it). Values cross a wire or a register:
// never renumber, only append.
#define MAGLEV_FAULT_CODES(X) \
  X(kNone, 0, "None") \
  X(kTravelX, 1, "TravelX")  /* x outside the travel window */ \
  X(kTravelY, 2, "TravelY") \
  X(kTravelThetaZ, 3, "TravelThetaZ") \
  X(kZEnvelope, 4, "ZEnvelope")  /* z outside [z_min, z_max] while z is closed */ \
  X(kTiltEnvelope, 5, "TiltEnvelope")  /* |theta_x| or |theta_y| beyond the envelope while z is closed */ \
  X(kFollowingError, 6, "FollowingError")  /* |reference - measured| of a closed axis beyond its limit */ \
  X(kPeakCurrentCommanded, 7, "PeakCurrentCommanded")  /* defensive: the allocation's limiter should make this impossible */ \
  X(kPeakCurrentMeasured, 8, "PeakCurrentMeasured")  /* amplifier monitor beyond peak + margin: actuator not following */ \
  X(kRmsCurrent, 9, "RmsCurrent")  /* thermal: first-order filtered i^2 beyond rms^2 */ \
  X(kTickOverrun, 10, "TickOverrun")  /* more consecutive servo overruns than allowed */ \
  X(kBeamLoss, 11, "BeamLoss")  /* interferometer signal loss (status bit) */ \
  X(kCounterJump, 12, "CounterJump")  /* interferometer count step beyond the plausible speed */ \
  X(kStaleFrames, 13, "StaleFrames")  /* more consecutive stale samples than allowed */ \
  X(kDisplacementOutOfRange, 14, "DisplacementOutOfRange")  /* laser displacement sensor: status bit or ADC at a rail */ \
  X(kAdcFault, 15, "AdcFault")  /* AD7606 conversion fault */ \
  X(kCurrentMonitorOutOfRange, 16, "CurrentMonitorOutOfRange")  /* coil current monitor ADC at a rail */ \
  X(kCurrentSaturation, 17, "CurrentSaturation")  /* the current limit acted for max_saturated_ticks in a row */ \
  X(kStageProfileInvalid, 18, "StageProfileInvalid")  /* the selected stage profile failed its boot check (value: ProfileError) */ \
  X(kCurrentMismatch, 19, "CurrentMismatch")  /* a coil's monitored current left its command for current_mismatch_ticks: amplifier shorted or open */ \
  X(kFrozenSample, 20, "FrozenSample")  /* the whole sample bit-identical for more than max_identical_samples ticks while a loop is closed */ \
  X(kCounterGlitch, 21, "CounterGlitch")  /* an interferometer step whose change no actuator can produce (sensors_to_pose replaced it): land */

enum class FaultCode : std::uint8_t {
  MAGLEV_FAULT_CODES(MAGLEV_ENUMERATOR)
};

inline constexpr std::uint8_t kNoAxis = 0xFF;

struct FaultRecord {
  FaultCode code = FaultCode::kNone;
  std::uint32_t tick = 0;
  std::uint8_t axis = kNoAxis;  // Axis index, coil index (current faults) or sensor index
  float value = 0.0f;           // the offending value, SI
};

enum class SupervisorConfigError : std::uint8_t {
  kOk = 0,
  kBadTravel,
  kBadEnvelope,
  kBadFollowingError,
  kBadCurrentLimit,
  kBadThermal,
  kBadPlausibility,
};

struct SupervisorConfig {
  // Travel window about the interferometer zero: paper 000's 56 mm x 35 mm
  // plus 1 mm, so that a move to the end of travel (where the references may
  // go) does not trip on its small following error.
  float x_min_m = -static_cast<float>(io::stage::kTravelX_m / 2 + 1e-3);
  float x_max_m = static_cast<float>(io::stage::kTravelX_m / 2 + 1e-3);
  float y_min_m = -static_cast<float>(io::stage::kTravelY_m / 2 + 1e-3);
  float y_max_m = static_cast<float>(io::stage::kTravelY_m / 2 + 1e-3);
  float theta_z_limit_rad = 5e-3f;
  // z / tilt envelope while z is closed (paper 000: within 40 um of rest).
  float z_min_m = -5e-6f, z_max_m = 40e-6f;
  float tilt_limit_rad = 300e-6f;  // 0.07 m half-frame * 300 urad = 21 um of edge travel
  // Following error per axis, Axis order, SI (m or rad).
  float following_error_limit[kSequencedAxes] = {200e-6f, 200e-6f, 500e-6f, 15e-6f, 200e-6f, 200e-6f};
  float peak_current_A = 4.0f;              // io::stage::kPeakCoilCurrent_A
  float measured_current_margin_A = 0.5f;   // monitor noise + amplifier tracking error
  float rms_current_A = 3.0f;               // io::stage::kRmsCoilCurrent_A
  float thermal_time_constant_s = 10.0f;    // coil thermal time constant (ours)
  // 2x the fastest move the suite makes (150 mm/s): a count step beyond
  // this per tick is a glitch. 0.5 m/s let a 173 um count jump through as a
  // "following error", and the landing then chased a false theta_z (campaign).
  float max_interferometer_speed_m_per_s = 0.3f;
  float interferometer_lsb_m = 0.618e-9f;   // io::stage::kInterferometerLsb_m
  std::uint16_t max_consecutive_stale_frames = 2;
  // A sample bit-identical to the previous one, in every field, for more
  // than this many ticks while a loop is closed is a frozen sensor node whose
  // transport does not flag it (a stale value): live sensors never repeat
  // three interferometer counts, three displacement codes, four Hall codes
  // and eight current-monitor codes exactly. 10 ticks = 4 ms at 2.5 kHz.
  // Without it a frozen sample also froze the current monitor, and an
  // amplifier shorted 9 ms later threw the platen out of its travel
  // unseen (campaign seed 1, run 1747). 0 disables the check.
  std::uint16_t max_identical_samples = 10;
  std::uint16_t max_consecutive_overruns = 2;
  // The whole-vector current limit acting without pause for this many ticks
  // is a fault: the coils cannot give what the loops ask (50 ms; ticks of the
  // default 2.5 kHz rate, configure() holds the time at other rates).
  // A stiff-gain attack once sagged z by 22 um for 8 s with the status Ready.
  std::uint16_t max_saturated_ticks = 125;
  // A coil whose monitored current stays further than this from its command
  // for this many ticks has an amplifier that does not follow (shorted to a
  // rail, or open): currents off at once, it cannot land the stage. 1.5 A and
  // 10 ticks (4 ms) stay clear of the held monitor value (a frame every 5
  // ticks) and the amplifier's step response; a shorted amplifier at 4 A was
  // left on for 38 ms and threw the platen 18 mm sideways (campaign).
  float current_mismatch_A = 1.5f;
  std::uint16_t current_mismatch_ticks = 10;  // 2.5 kHz ticks (4 ms at any rate, see configure())
};

SupervisorConfigError validate(const SupervisorConfig& config, float servo_rate_Hz);

// The position limits as integers in pm / prad (numeric::PicoFirstAbove /
// PicoFirstAtOrAbove of the float limits): v < *_below is PicoToSi(v) < min,
// v >= *_above is PicoToSi(v) > max, |v| >= *_above (the uint64 ones) is
// |PicoToSi(v)| > limit. The tick compares the pose and the following errors
// with these and converts none of them.
struct SupervisorPicoLimits {
  std::int64_t x_below, x_above, y_below, y_above, z_below, z_above;
  std::uint64_t theta_z_above, tilt_above;
  std::uint64_t following_above[kSequencedAxes];
};

// A validated configuration as the tick uses it, prepared at configuration
// time: the durations in ticks of the rate and the integer limits (twelve
// 64-step bisections, ~20 k M7 instructions: the controller prepares it with
// interrupts enabled, prepare_config, and commit_config only copies it).
struct SupervisorSettings {
  SupervisorConfig config;  // max_saturated_ticks, current_mismatch_ticks at the rate
  float thermal_alpha;      // dt / tau
  std::int32_t max_count_step;
  SupervisorPicoLimits pico;
};
SupervisorSettings PrepareSupervisorSettings(const SupervisorConfig& config, float servo_rate_Hz);

// An aggregate without member initializers: the controller fills every
// field each tick (zeroing it first cost a memset per step()); elsewhere
// value-initialize it (`SupervisorInputs in{};`).
struct SupervisorInputs {
  const io::SensorSample* sample;
  bool tick_overrun;
  std::uint32_t tick;
  bool positions_valid;     // homed: the pose means something
  bool envelope_active;     // z closed: z/tilt envelope applies
  std::uint8_t closed_axes;     // following error applies to these
  // Measured pose and reference, Axis order, pm / prad: the controller's own
  // arrays, read in place. The checks compare them with integer thresholds
  // that give the outcome of comparing numeric::PicoToSi(v) with the float
  // limits (configure()), so no position is converted in the tick; only a
  // fault record's value is (attribute()).
  const std::int64_t* pose_pico;
  const std::int64_t* reference_pico;
  // Last tick's commanded coil currents (io::kCoils of them), read in place
  // from the caller's own copy (the controller's status().coil_current_A): no copy per tick.
  const float* coil_current_cmd_A;
  float coil_current_measured_A[io::kCoils];
  bool current_limited;  // last tick's allocation scaled its currents down (k < 1)
  // sensors_to_pose replaced this tick's step of these beams (bit b: beam b)
  // because its change implied an acceleration no actuator can produce
  // (PoseMeasurement::beam_glitch); beam_glitch_m: the refused change, SI.
  std::uint8_t beam_glitch;
  float beam_glitch_m[io::kInterferometerAxes];
  // The laser displacement readings sensors_to_pose refused this tick
  // (PoseMeasurement::displacement_bad, bit s: its out-of-range status bit,
  // or its ADC code at a rail): kDisplacementOutOfRange. One definition of a
  // bad reading, the measurement's, which the supervisor used to repeat.
  std::uint8_t displacement_bad;
  // Nonzero: the stage profile selected in the persisted configuration was
  // refused at boot (its stage_profile::ProfileError). A cause that stays
  // present until a valid profile is selected: the stage cannot leave rest.
  std::uint8_t stage_profile_error;
};

struct SupervisorStatus {
  FaultCode active = FaultCode::kNone;  // the highest-priority check tripping THIS tick
  FaultReaction reaction = FaultReaction::kNone;  // latched reaction
  FaultRecord first_fault{};
  bool in_plane_sensors_valid = true;
  bool z_sensors_valid = true;
  std::uint32_t fault_count = 0;  // ticks on which any check tripped
};

class Supervisor {
 public:
  void configure(const SupervisorSettings& settings);  // a copy: cheap
  void configure(const SupervisorConfig& config, float servo_rate_Hz) {
    configure(PrepareSupervisorSettings(config, servo_rate_Hz));
  }
  void reset();  // clears the latch AND the thermal state (power-on only)

  const SupervisorStatus& step(const SupervisorInputs& in);

  // Clears the latch if no check tripped on the last tick; the thermal state is kept.
  bool clear_fault();
  bool cause_present() const { return status_.active != FaultCode::kNone; }
  const SupervisorStatus& status() const { return status_; }
  // Coil j's rms current (A), the square root of its thermal state (the
  // filtered i^2). Asked for, not kept: a square root per coil per tick cost
  // ~89 M7 instructions for a value only a fault record and a test read.
  float rms_current_A(int j) const;

 private:
  // A check that tripped this tick (the first in priority order).
  struct Trip {
    FaultCode code = FaultCode::kNone;
    std::uint8_t axis = kNoAxis;
    float value = 0.0f;
  };
  struct Checks;  // every check's outcome of one tick, as bits (supervisor.cpp)
  // The coil current limits as the checks compare them.
  struct CoilLimits {
    float measured_A;   // peak + the monitor's margin
    float commanded_A;  // peak, 0.1 % over
    float rms2_A2;      // rms limit squared: compared with the filtered i^2
  };
  // The coil checks coil by coil (bit j = coil j), for attribute().
  struct CoilMasks {
    std::uint32_t monitor_rail, mismatch, peak_measured, peak_commanded, rms;
  };
  CoilLimits coil_limits() const;
  CoilMasks coil_masks(const SupervisorInputs& in) const;
  Trip attribute(const SupervisorInputs& in, const Checks& c) const;
  // Keeps the first tripping check only.
  static void note(Trip& t, bool tripped, FaultCode code, std::uint8_t axis, float value);

  SupervisorConfig config_{};
  SupervisorPicoLimits pico_{};
  float thermal_alpha_ = 0.0f;     // dt / tau
  std::int32_t max_count_step_ = 0;
  SupervisorStatus status_{};
  std::uint32_t previous_counts_[io::kInterferometerAxes] = {};
  bool have_previous_ = false;
  std::uint16_t stale_run_ = 0;
  std::uint16_t identical_run_ = 0;
  io::SensorSample previous_sample_{};
  std::uint16_t overrun_run_ = 0;
  std::uint16_t saturated_run_ = 0;
  std::uint16_t mismatch_run_[io::kCoils] = {};
  bool mismatch_running_ = false;  // some mismatch_run_ is nonzero
  float i2_filtered_[io::kCoils] = {};
};

const char* to_string(FaultCode c);

}  // namespace maglev::kernel
