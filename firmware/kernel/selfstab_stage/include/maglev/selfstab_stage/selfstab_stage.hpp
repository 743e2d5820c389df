// Servo kernel of the solenoid_magnet family: paper 001 (Jung & Baek 2002),
// Fig. 8. Per tick:
//   PSD ADC codes --R--> pose --(feedback filter)--> PID on the ACTIVE axes
//   only, gains scheduled by the axis' own (filtered) position --T--> coil
//   current changes, + W (the nominal currents, which carry the weight and
//   make every axis passively stable) --> nine coil currents --> DAC codes.
// The passive axes get no effort: they keep the nominal currents (the
// paper's "uncontrolled d.o.f"). float32 throughout, static state, no heap,
// no exceptions; the same code runs on the host bench and the Cortex-M7.
//
// Axis order is the paper's, eq (13): x, y, z, alpha, beta, gamma (alpha
// about x, beta about y, gamma about z). Coil order: A, B, C (out-of-plane),
// dm, dn, em, en, fm, fn (in-plane), as hil/selfstab_plant.
#pragma once

#include <cstdint>

#include "maglev/axis_loops/biquad.hpp"
#include "maglev/io/enum_names.hpp"

namespace maglev::selfstab {

inline constexpr int kAxes = 6;
inline constexpr int kCoils = 9;
inline constexpr int kPsdChannels = 6;  // (tangential, vertical) of three PSDs
inline constexpr int kMaxSchedulePoints = 8;
enum SelfstabAxis : std::uint8_t { kX = 0, kY, kZ, kAlpha, kBeta, kGamma };

// One tick of sensor input: the six PSD channels as signed ADC codes (0 =
// the centre of the active area, one count = the profile's resolution).
inline constexpr std::uint8_t kPsdValid = 0x01;  // status bit: a fresh, valid conversion
struct SelfstabSensorSample {
  std::int16_t psd_code[kPsdChannels];
  std::uint8_t status;
  std::uint8_t reserved;  // zero
};

// One tick of output: the nine coil amplifiers' DAC codes (signed, one count
// = dac_A_per_code of current command) and the amplifiers' enable.
struct SelfstabCoilCommand {
  std::int16_t dac_code[kCoils];
  std::uint8_t enable;
  std::uint8_t reserved;  // zero
};

enum class AxisRole : std::uint8_t { kActive = 0, kPassive = 1, kAbsent = 2 };

struct SelfstabLoopConfig {
  // PID on the position error, effort in A (the current of the first coil of
  // the axis' bracket in eq (13); T distributes it). SI: A/m, A/(m s), A s/m
  // (per rad for angles).
  float kp;
  float ki;
  float kd;
  float derivative_filter_Hz;  // first-order filter of the derivative
  float effort_limit_A;        // clamp of the effort (and of the integrator)
  float travel_min;            // references outside [min, max] are refused
  float travel_max;
  float max_velocity;          // reference ramp rate after lift-off (m/s, rad/s)
  // Gain schedule: kp * kp_scale(y), kd * kd_scale(y) with y the axis'
  // filtered position, linear between the points, held beyond the ends. A
  // reference outside [at[0], at[n-1]] is refused (kOutsideSchedule). 0
  // points: fixed gains.
  std::uint8_t schedule_points;
  std::uint8_t reserved[3];
  float schedule_at[kMaxSchedulePoints];
  float kp_scale[kMaxSchedulePoints];
  float kd_scale[kMaxSchedulePoints];
  // Feedback-path filter on the measured position (paper: 10 Hz Butterworth).
  kernel::BiquadConfig feedback_filter;
};

struct SelfstabKernelConfig {
  float servo_rate_Hz;
  AxisRole role[kAxes];
  std::uint8_t feedback_filter_enabled;  // 1: the loops see the filtered position
  std::uint8_t reserved;
  SelfstabLoopConfig loop[kAxes];
  // Kinematic transform R of Fig. 8 with the ADC scale: pose (m, rad) per code.
  float pose_per_code[kAxes][kPsdChannels];
  // Dynamic transform T: coil current (A) per A of axis effort.
  float coil_per_effort[kCoils][kAxes];
  // Weight compensation W: the nominal currents (A), eq (13)'s operating point.
  float nominal_current_A[kCoils];
  float current_limit_A;    // per-coil clamp (the profile's peak current)
  float dac_A_per_code;     // current command per DAC count
  std::int16_t psd_code_limit;  // |code| >= this: the spot is off the PSD (saturated)
  std::uint16_t reserved2;
  float liftoff_ramp_s;     // W ramps from 0 over this time (docked, loops open)
  float liftoff_settle_s;   // then the loops close after this wait
  float land_ramp_s;        // currents ramp to 0 over this time (loops open)
};

// Why a configuration is refused (pinned values).
#define MAGLEV_SELFSTAB_CONFIG_ERRORS(X) \
  X(kOk, 0, "ok") \
  X(kBadServoRate, 1, "servo rate not positive or not finite") \
  X(kBadLoop, 2, "a loop gain, limit or travel is negative or not finite") \
  X(kBadFilter, 3, "the feedback filter cannot be designed") \
  X(kBadSchedule, 4, "schedule points not increasing or scales not positive") \
  X(kBadScale, 5, "DAC scale, current limit or ramp time not positive") \
  X(kNoActiveAxis, 6, "no active axis") \
  X(kNotDocked, 7, "a configuration is applied only while docked or faulted")
enum class SelfstabConfigError : std::uint8_t { MAGLEV_SELFSTAB_CONFIG_ERRORS(MAGLEV_ENUMERATOR) };
const char* to_string(SelfstabConfigError e);

// The result of a command (pinned values: they cross a register or a log).
#define MAGLEV_SELFSTAB_RESULTS(X) \
  X(kOk, 0, "ok") \
  X(kAxisPassive, 1, "the axis is passive: the profile leaves it to the stage") \
  X(kAxisAbsent, 2, "the axis is not a degree of freedom of this stage") \
  X(kOutsideSchedule, 3, "reference outside the range where the gain schedule is defined") \
  X(kOutsideTravel, 4, "reference outside the axis travel") \
  X(kWrongMode, 5, "command not allowed in this mode") \
  X(kBadValue, 6, "value not finite") \
  X(kBadAxis, 7, "no such axis") \
  X(kNotConfigured, 8, "no valid configuration")
enum class SelfstabResult : std::uint8_t { MAGLEV_SELFSTAB_RESULTS(MAGLEV_ENUMERATOR) };
const char* to_string(SelfstabResult r);

#define MAGLEV_SELFSTAB_MODES(X) \
  X(kDocked, 0, "docked") \
  X(kLifting, 1, "lifting") \
  X(kLevitated, 2, "levitated") \
  X(kLanding, 3, "landing") \
  X(kFault, 4, "fault")
enum class SelfstabMode : std::uint8_t { MAGLEV_SELFSTAB_MODES(MAGLEV_ENUMERATOR) };
const char* to_string(SelfstabMode m);

// What the kernel did this tick (telemetry; the bench logs it).
struct SelfstabTelemetry {
  float pose[kAxes];           // from R, unfiltered
  float feedback[kAxes];       // what the loops saw (filtered when enabled)
  float reference[kAxes];
  float effort_A[kAxes];
  float current_A[kCoils];
  float kp_scale[kAxes];       // the scheduled scales in use
  float kd_scale[kAxes];
  SelfstabMode mode;
};

class SelfstabKernel {
 public:
  // Validates and applies a configuration; only while docked or faulted (a
  // fault is left this way), or before the first one. On an error nothing
  // changes.
  SelfstabConfigError configure(const SelfstabKernelConfig& config);

  // Commands. Each returns why it was refused; a refused command changes nothing.
  SelfstabResult lift_off();                       // docked -> lifting -> levitated at 0
  SelfstabResult move_to(int axis, float target);  // step of an active axis' reference
  SelfstabResult hold();                           // stop every ramp where it is
  SelfstabResult land();                           // levitated -> landing -> docked
  SelfstabResult set_feedback_filter(bool enabled);  // the paper's filter in or out

  // One servo tick.
  SelfstabCoilCommand tick(const SelfstabSensorSample& sample);

  SelfstabMode mode() const { return mode_; }
  const SelfstabTelemetry& telemetry() const { return tel_; }
  const SelfstabKernelConfig& config() const { return cfg_; }

 private:
  struct LoopState {
    float integrator;
    float derivative;  // filtered d(y)/dt
    float prev_y;
    float prev_e;
    float reference;
    float target;
    kernel::BiquadState<float> filter;
  };
  SelfstabResult check_reference(int axis, float target) const;
  void close_loops();
  float scale_at(const SelfstabLoopConfig& l, const float* scales, float y) const;

  SelfstabKernelConfig cfg_{};
  bool configured_ = false;
  kernel::BiquadCoefficients<float> filter_[kAxes]{};
  float T_s_ = 0.0f;
  float d_a_[kAxes]{};  // derivative filter pole
  float d_b_[kAxes]{};  // derivative filter gain (1/s)
  SelfstabMode mode_ = SelfstabMode::kDocked;
  std::uint32_t phase_ticks_ = 0;  // ticks in the current lifting / landing phase
  float ramp_start_A_[kCoils]{};   // currents when landing began
  LoopState loop_[kAxes]{};
  bool loops_closed_ = false;
  SelfstabTelemetry tel_{};
};

}  // namespace maglev::selfstab
