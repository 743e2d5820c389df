// maglev::kernel::Controller<Scalar>: one servo tick of the whole kernel.
//
//   SensorSample -> sensors_to_pose (int64 pose) -> supervisor -> sequencer
//   -> references (int64) -> axis loops (Scalar, kernel units) + feed-forward
//   -> force_allocation (i = 2 S_xy B U, whole-vector current limit k)
//   -> anti-windup (k U back to the loops) -> DAC codes -> ActuatorCommand
//
// All state lives inside the object; the caller places it statically. No heap,
// no exceptions. step() runs every loop every tick and selects outputs with the
// sequencer's closed-axis mask, so its cost does not depend on the data
// (homing's one-off Hall solve is the documented exception, docs/KERNEL.md).
#pragma once

#include "maglev/io/code_placement.hpp"
#include "maglev/io/enum_names.hpp"

#include <cstdint>
#include <type_traits>

#include "maglev/io/axis.hpp"
#include "maglev/axis_loops/axis_loop.hpp"
#include "maglev/axis_loops/defaults.hpp"
#include "maglev/coupling_calibration/coupling_calibration.hpp"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/opaque_pointer.hpp"
#include "maglev/numeric/scalar_traits.hpp"
#include "maglev/references/references.hpp"
#include "maglev/sensors_to_pose/sensors_to_pose.hpp"
#include "maglev/sequencer/sequencer.hpp"
#include "maglev/supervisor/supervisor.hpp"

namespace maglev::kernel {

static_assert(kSequencedAxes == kAxisCount, "sequencer masks and Axis disagree");

// Limits every motion command is checked against (SI). The stage is never
// commanded beyond them; they must lie inside the supervisor's window.
struct ReferenceLimits {
  // x, y: paper 000's travel, 56 mm x 35 mm (Sec. V, Fig. 10c moves the full
  // 56 mm), centred on the interferometer zero.
  static constexpr float kHalfTravelX_m = static_cast<float>(io::stage::kTravelX_m / 2);
  static constexpr float kHalfTravelY_m = static_cast<float>(io::stage::kTravelY_m / 2);
  float position_min[kAxisCount] = {-kHalfTravelX_m, -kHalfTravelY_m, -4e-3f, 10e-6f, -200e-6f, -200e-6f};
  float position_max[kAxisCount] = {kHalfTravelX_m, kHalfTravelY_m, 4e-3f, 38e-6f, 200e-6f, 200e-6f};
  float max_velocity[kAxisCount] = {0.15f, 0.15f, 0.05f, 200e-6f, 1e-3f, 1e-3f};
  float max_acceleration[kAxisCount] = {1.5f, 1.5f, 0.5f, 5e-3f, 0.05f, 0.05f};
  // Steps are applied in one tick: bounded so the error fits the Scalar range (128 um).
  float max_step[kAxisCount] = {100e-6f, 100e-6f, 100e-6f, 10e-6f, 20e-6f, 20e-6f};
  // Jerk bound of S-curve moves and of the circle's arc-length profile (m/s^3, rad/s^3).
  float max_jerk[kAxisCount] = {150.0f, 150.0f, 50.0f, 0.5f, 5.0f, 5.0f};
};

// Excitation injection (frequency-response measurement on the running loop):
// a known disturbance d is added to one axis' effort U before allocation.
// Bounded, deterministic (integer phase accumulators + the kernel's sine
// table), only in Ready, off by default.
inline constexpr int kMaxExcitationHarmonics = 8;
struct ExcitationLimits {
  float max_amplitude_A = 0.5f;       // |d| <= this, always (A of effort)
  float max_frequency_Hz = 1000.0f;   // highest line (< servo_rate / 2)
  float max_duration_s = 600.0f;
};

// External injection (firmware/lab_tools/wave_generator): one value per tick,
// handed to the kernel before step() by the servo tick's before_step hook.
// Effort: added to the axis' effort U like kExcite's d (A, clamped to
// ExcitationLimits::max_amplitude_A). Reference: added to the reference the
// axis loop sees (m or rad, clamped to ReferenceLimits::max_step), not to the
// stored reference (profiles and status.reference are unchanged). Applied
// only on a closed axis while motion is allowed (Ready); inactive by default.
struct Injection {
  bool active = false;
  bool at_reference = false;  // false: at the effort
  std::uint8_t axis = 0;      // kernel Axis index
  float value = 0.0f;         // A (effort) or m / rad (reference)
};

// The selected stage's own limits, which no register write may exceed. Set
// from the stage profile (stage_profile::MakeKernelConfig), never by a
// register: the register map's ranges are the board's envelope, wide enough
// for every stage this firmware runs, so that a stage whose limits differ
// from the seed's can save and restore its configuration. prepare_config
// refuses a supervisor limit beyond these (kBeyondStageLimits): whatever a
// host writes, the coils get no more current than the stage's coils take,
// and the travel window opens no further than the stage's travel.
struct StageEnvelope {
  float peak_current_A;  // the profile's peak_current_A (the seed: 4 A)
  float rms_current_A;   // the profile's rms_current_A (the seed: 3 A)
  // The supervisor's x / y travel window at most 2 mm beyond the profile's
  // travel: its 1 mm default and 1 mm to tune (the seed: +-30, +-19.5 mm).
  float x_min_m, x_max_m, y_min_m, y_max_m;
};
// The window's reach beyond a stage's travel (StageEnvelope).
inline constexpr double kStageWindowBeyondTravel_m = 2e-3;

// Payload (KernelConfig::payload_mass_kg): admitted while the stage hovers
// platen and payload on at most this fraction of its peak coil current
// (HoverPeakCurrent_A), the rest left to the loops. Paper 000's 539.6 g on
// the seed stage hovers on 3.71 A of 4 A (0.93); 1.0 kg would need 5.0 A.
inline constexpr double kMaxHoverFraction = 0.95;
// A sanity bound only; the hover rule is the stage's.
inline constexpr float kMaxPayloadSanity_kg = 100.0f;

struct KernelConfig {
  float servo_rate_Hz;
  SensorsToPoseConfig measurement;
  AxisLoopConfig axis[kAxisCount];
  ForceAllocationConfig allocation;
  ReferenceLimits references;
  SequencerConfig sequencer;
  SupervisorConfig supervisor;
  float payload_mass_kg;
  // Allows changing axis-loop gains while levitated (all other fields stay locked).
  bool live_tuning;
  // --- added in round 2 (default_kernel_config() sets them) ---
  // u_ff = (m or I) a / (2 b*) on every profiled axis (payload included).
  bool acceleration_feedforward;
  // Back-calculation / eq (17) anti-windup of every loop (off only for tests
  // and comparisons: the integrators then wind up while the current limit acts).
  bool antiwindup;
  // Payload inertia about the platen CoM axes z, x, y (kg m^2), added to Iz, Ix, Iy.
  float payload_inertia_kgm2[3];
  ExcitationLimits excitation;
  // --- issue 15: the cross-coupling correction U' = C U applied before the
  // force allocation (firmware/kernel/coupling_calibration). Off by default;
  // written by the kernel's own calibration (kCalibrateCoupling) or loaded
  // from the persisted configuration; locked while levitated.
  CouplingCorrection coupling;
  // --- the stage's limits (StageEnvelope), from its profile; no register.
  StageEnvelope stage;
};

KernelConfig default_kernel_config();

// The largest coil current the allocation asks for an effort vector (current
// limit undone), over places_per_pitch^2 places in one pitch of x and y.
template <typename Scalar>
double PeakCoilCurrent_A(const Scalar effort_A[kAxisCount], const ForceAllocationState<Scalar>& state, double pitch_m,
                         int places_per_pitch);
// That for the gravity feed-forward (platen and payload) over 4 x 4 places:
// the payload check's measure.
template <typename Scalar>
double HoverPeakCurrent_A(const ForceAllocationState<Scalar>& state, double pitch_m);

// Equality of the VALUES of two configuration (sub)structs, byte for byte
// with padding excluded. Padding bytes are unspecified: a brace-initialized
// temporary copied into a config (`beam[0] = {...}`) brings whatever the
// stack held, so a plain memcmp could call two equal configurations
// different (a sanitizer build showed it; the kernel's "locked while
// levitated" test compares sub-structs this way). GCC clears the padding of
// local copies; a compiler without __builtin_clear_padding (the clang of
// the fuzz targets) falls back to the plain compare.
template <typename T>
bool same_value_bytes(const T& a, const T& b) {
  T x = a;
  T y = b;
#if defined(__has_builtin)
#if __has_builtin(__builtin_clear_padding)
  __builtin_clear_padding(&x);
  __builtin_clear_padding(&y);
#endif
#endif
  return __builtin_memcmp(&x, &y, sizeof(T)) == 0;
}

template <typename T, decltype(sizeof 0) N>
bool same_value_bytes(const T (&a)[N], const T (&b)[N]) {
  for (decltype(sizeof 0) i = 0; i < N; ++i) {
    if (!same_value_bytes(a[i], b[i])) return false;
  }
  return true;
}

inline bool same_config(const KernelConfig& a, const KernelConfig& b) { return same_value_bytes(a, b); }

// ConfigError: value and name of every enumerator, defined once (the enum and
// to_string() are generated from it). Values cross a wire or a register:
// never renumber, only append.
#define MAGLEV_CONFIG_ERRORS(X) \
  X(kOk, 0, "Ok") \
  X(kBadServoRate, 1, "BadServoRate") \
  X(kMeasurement, 2, "Measurement")  /* sensors_to_pose refused its part */ \
  X(kAxisLoop, 3, "AxisLoop")  /* an axis loop design failed (see status().config_axis) */ \
  X(kUnsupportedLoopType, 4, "UnsupportedLoopType") \
  X(kAllocation, 5, "Allocation")  /* force_allocation refused its part */ \
  X(kReferenceLimits, 6, "ReferenceLimits")  /* limits outside the supervisor window / non-positive rates */ \
  X(kSequencer, 7, "Sequencer") \
  X(kSupervisor, 8, "Supervisor") \
  X(kPayload, 9, "Payload") \
  X(kLockedWhileLevitated, 10, "LockedWhileLevitated")  /* an unsafe-to-change field differs while not on rest */ \
  X(kGainsLockedWhileLevitated, 11, "GainsLockedWhileLevitated")  /* gains differ while levitated and live_tuning is off */ \
  X(kUnstableLoop, 12, "UnstableLoop")  /* the loop check finds a PID loop without crossover, phase margin or delay margin (config_axis) */ \
  X(kGainStepTooLarge, 13, "GainStepTooLarge")  /* live tuning: a PID gain (kp, ki, kd) moved by more than kMaxLiveGainStep in one write (config_axis) */ \
  X(kCouplingCorrection, 14, "CouplingCorrection")  /* coupling correction not finite, reserved bytes set or beyond kMaxCorrectionMagnitude */ \
  X(kBeyondStageLimits, 15, "BeyondStageLimits")  /* a current limit or travel window beyond the selected stage's (StageEnvelope) */

enum class ConfigError : std::uint8_t {
  MAGLEV_CONFIG_ERRORS(MAGLEV_ENUMERATOR)
};

// One axis' loop and filters as apply_config designs them, from the
// configuration alone: the loop check (PID axes), the selected loop's design
// and each biquad. kOk, kUnsupportedLoopType, kUnstableLoop or kAxisLoop.
// apply_config designs every axis with it; the stage-profile check calls it
// on the configuration a profile yields, so that what it accepts the kernel
// takes.
template <typename Scalar>
MAGLEV_CONFIG_CODE ConfigError DesignAxis(const KernelConfig& c, int axis, Pid2DofCoefficients<Scalar>* pid,
                                          InternalModelCoefficients<Scalar>* imr,
                                          BiquadCoefficients<Scalar> filter[kMaxBiquadStages]);

// Live tuning (levitated, KernelConfig::live_tuning): one write may move
// each PID gain (kp, ki, kd) of an axis by at most this factor up or down,
// keeping its sign; a zero gain stays zero until the stage rests. 2 = 6 dB,
// the gain margin a loop is designed with: one write cannot take a loop that
// holds the stage past its stability limit on the gain alone, whatever the
// loop check's model misses (the real loop's extra delay; campaign seed 1,
// run 3013: theta_x kp, kd x20 in one write, accepted, landed at 3.4 mm/s).
// Larger changes take several writes, each checked and each seen on the
// stage.
inline constexpr float kMaxLiveGainStep = 2.0f;

const char* to_string(ConfigError e);

enum class MotionType : std::uint8_t {
  kHome = 0, kLevitate, kLand, kStop, kClearFault,
  kMoveTo,             // trapezoid: axis, target, velocity, acceleration
  kMoveJerkLimited,    // axis, target, velocity, acceleration, jerk
  kStep,               // axis, delta
  kCircle,             // diameter, period, turns (x, y)
  kSinusoid,           // axis, amplitude, frequency
  kHold,               // every axis holds its present reference (stops profiles and excitation)
  // Excitation: axis, amplitude (A of effort, peak of the sum), frequency_Hz,
  // harmonics (1 = one sine; N > 1 = Schroeder multisine on f, 2f, ..., Nf,
  // each amplitude/N), duration_s (0 = until kStopExcitation / kHold).
  kExcite,
  kStopExcitation,
  // Cross-coupling calibration (issue 15): Ready, nothing else moving; runs
  // ~30 s (12 excitations), see CouplingCalibrationConfig.
  kCalibrateCoupling,
};

struct MotionCommand {
  MotionType type = MotionType::kHold;
  Axis axis = Axis::kX;
  double target = 0.0;        // m or rad (absolute, magnet frame) / step delta
  double velocity = 0.0;      // m/s or rad/s
  double acceleration = 0.0;  // m/s^2 or rad/s^2
  double jerk = 0.0;
  double amplitude = 0.0;
  double frequency_Hz = 0.0;
  double diameter_m = 0.0;
  double period_s = 0.0;
  double turns = 0.0;           // circle turns; sinusoid cycles (0 = until kHold)
  double duration_s = 0.0;      // kExcite
  std::uint8_t harmonics = 1;   // kExcite
};

// CommandResult: value and name of every enumerator, defined once (the enum and
// to_string() are generated from it). Values cross a wire or a register:
// never renumber, only append.
#define MAGLEV_COMMAND_RESULTS(X) \
  X(kAccepted, 0, "accepted") \
  X(kAlreadyThere, 1, "already there") \
  X(kRefusedBusy, 2, "refused: busy") \
  X(kRefusedNotLevitated, 3, "refused: not levitated") \
  X(kRefusedFaultLatched, 4, "refused: fault latched") \
  X(kRefusedNotFaulted, 5, "refused: not faulted") \
  X(kRefusedFaultActive, 6, "refused: fault active") \
  X(kRefusedNotReady, 7, "refused: not ready")  /* motion commands need Ready */ \
  X(kRefusedOutOfRange, 8, "refused: out of range")  /* target / step beyond ReferenceLimits */ \
  X(kRefusedBadProfile, 9, "refused: bad profile")  /* v, a, jerk <= 0 or beyond the limits */ \
  X(kUnsupported, 10, "unsupported by this kernel build")  /* profile type not available in this build */ \
  X(kRefusedExcitation, 11, "refused: excitation beyond its limits")  /* amplitude / frequency / duration / harmonics beyond ExcitationLimits */

enum class CommandResult : std::uint8_t {
  MAGLEV_COMMAND_RESULTS(MAGLEV_ENUMERATOR)
};
const char* to_string(CommandResult r);

struct ControllerStatus {
  Pose64 pose{};
  Pose64 reference{};
  std::uint8_t pose_valid = 0;
  SequencerState state = SequencerState::kIdle;
  TransitionReason last_reason = TransitionReason::kPowerOn;
  std::uint8_t closed_axes = 0;
  float feedforward_fraction = 0.0f;
  FaultCode fault = FaultCode::kNone;      // latched first fault
  FaultRecord first_fault{};
  FaultReaction reaction = FaultReaction::kNone;
  bool saturated = false;
  float scale_k = 1.0f;
  // The currents commanded (0 with the amplifiers off); the supervisor's
  // next tick reads them here (the controller keeps no second copy).
  float coil_current_A[io::kCoils] = {};
  float effort_A[kAxisCount] = {};          // U = u_loop + d, into the allocation
  std::uint32_t tick = 0;
  ConfigError last_config_error = ConfigError::kOk;
  std::uint8_t config_axis = 0xFF;
  // --- added in round 2 ---
  // Per axis: the loop's own effort (after its clamp, incl. its feed-forward)
  // and k U (what was applied); the total U = loop + excitation d is effort_A.
  // Open-loop gain at the excitation line: L = -u_loop / U.
  float loop_effort_A[kAxisCount] = {};
  float applied_effort_A[kAxisCount] = {};
  float excitation_A[kAxisCount] = {};
  bool excitation_active = false;
  std::uint8_t excitation_axis = 0;
  float excitation_frequency_Hz = 0.0f;     // the fundamental actually generated (phase-increment quantised)
  std::uint32_t excitation_tick = 0;        // ticks since the excitation started
  double reference_acceleration[kAxisCount] = {};  // SI, of the active profile
  // --- added in round 3 ---
  // A reference profile (move, sinusoid, circle), a not yet applied step or
  // the excitation is running: the stage is being moved on purpose. The
  // Modbus map's "not moving" write rule and status.moving read it.
  bool motion_active = false;
  // --- lab tools: the external injection applied this tick (0 when none) ---
  // (one axis at a time: the values below are for injection_axis)
  bool injection_active = false;
  bool injection_at_reference = false;
  std::uint8_t injection_axis = 0;
  float reference_injection = 0.0f;  // m or rad, added to that axis loop's reference
  // --- issue 15: the coupling calibration (last result / reason, progress) ---
  CouplingCalibrationResult calibration_result = CouplingCalibrationResult::kNone;
  std::uint8_t calibration_experiment = 0;  // 0-5 identification, 6-11 verification
  float calibration_coupling_before = 0.0f;  // max scaled off-diagonal of R, identification
  float calibration_coupling_after = 0.0f;   // the same with the new C applied (verification)
  float calibration_inconsistency = 0.0f;    // max line spread of R (scaled)
  bool coupling_correction_active = false;   // a correction (or its ramp) acts this tick
  // --- issue 15: laser displacement sensor target steps repaired
  // (SensorsToPoseConfig::lds_target_*) since the configuration was applied ---
  std::uint32_t lds_target_steps = 0;
};

template <typename Scalar>
class Controller {
 public:
  using Traits = numeric::ScalarTraits<Scalar>;

  MAGLEV_CONFIG_CODE Controller();  // applies default_kernel_config()

  MAGLEV_CONFIG_CODE ConfigError apply_config(const KernelConfig& config);  // prepare, then commit
  // apply_config in two parts, for a board whose servo tick runs meanwhile:
  // prepare_config validates and designs into the idle slot (4 M M7
  // instructions with the six loop checks: ~9 ms at 480 MHz) and touches
  // nothing the tick reads, so it may run with the tick enabled;
  // commit_config makes the checks against the live state (levitated? gain
  // steps) and swaps, a few thousand instructions with the tick masked. Call
  // commit_config with the configuration just prepared; without a prepare
  // (or after another) it prepares first.
  MAGLEV_CONFIG_CODE ConfigError prepare_config(const KernelConfig& config);
  MAGLEV_CONFIG_CODE ConfigError commit_config(const KernelConfig& config);
  MAGLEV_CONFIG_CODE CommandResult command(const MotionCommand& cmd);
  io::ActuatorCommand step(const io::SensorSample& sample, bool tick_overrun);
  // Work that need not run in the servo tick: homing's Hall solve (two
  // atan2 and 14 Newton steps, ~10 000 M7 instructions) and the homing
  // offsets from it (128-bit products), handed over by
  // step() seven ticks before homing needs it. Call it from thread mode on
  // the same core, below step()'s priority (the board's main loop), as often
  // as convenient: step() never waits for it. A solve that background() has
  // not finished when homing needs it is done in step() itself from the same
  // inputs, so the result bits do not depend on whether or when this runs.
  // True if it ran the solve.
  bool background();
  // Homing Hall solves step() had to do itself (background() had not run).
  std::uint32_t hall_solves_in_tick() const { return hall_solves_in_tick_; }

  const ControllerStatus& status() const { return status_; }
  const KernelConfig& config() const { return config_; }
  // The discrete 2-DOF PID axis a runs with (designed at apply_config from
  // the continuous gains at config().servo_rate_Hz).
  const Pid2DofCoefficients<Scalar>& pid_coefficients(int a) const { return applied_[active_].pid[a]; }
  // Live value of ControllerStatus::motion_active (also right between a
  // command() that started a profile and the next step()).
  bool motion_active() const;
  // The stage profile check's verdict from boot (stage_profile::ProfileError,
  // 0 = ok): while nonzero the supervisor holds FaultCode::kStageProfileInvalid
  // (the stage stays landed; clear_fault is refused while the cause remains).
  void set_stage_profile_error(std::uint8_t error) { stage_profile_error_ = error; }
  // The next step()'s external injection (see Injection); stays until replaced.
  void set_injection(const Injection& injection) { injection_ = injection; }
  const Injection& injection() const { return injection_; }
  std::uint8_t stage_profile_error() const { return stage_profile_error_; }
  // The calibration's excitation and checks (not persisted; defaults documented there).
  void set_calibration_config(const CouplingCalibrationConfig& c) { calibration_config_ = c; }
  const CouplingCalibrationConfig& calibration_config() const { return calibration_config_; }

 private:
  // The generator driving an axis (firmware/kernel/references), sampled at
  // its own tick counter from the reference it started on.
  enum class ProfileKind : std::uint8_t { kNone = 0, kMove, kSinusoid, kCircle, kStop };
  struct Profile {
    ProfileKind kind = ProfileKind::kNone;
    std::int64_t tick = 0;
  };
  // In the tick's order of use, what every tick reads first: a VFP load
  // reaches 1020 bytes past its base (the allocation's tick fields lead its
  // state; the internal-model coefficients, read only by such axes, last).
  struct Applied {
    LoopType type[kAxisCount];
    bool all_pid;  // every type is kPid2Dof: the loops' PID-only form (AxisLoop<Scalar, true>)
    bool filtered[kAxisCount];  // biquad_chain_enabled(filter[a])
    Pid2DofCoefficients<Scalar> pid[kAxisCount];
    BiquadCoefficients<Scalar> filter[kAxisCount][kMaxBiquadStages];
    double inertia_over_two_b_star[kAxisCount];  // (m or I) / (2 b*): A per (m/s^2) or (rad/s^2)
    ForceAllocationState<Scalar> allocation;
    InternalModelCoefficients<Scalar> imr[kAxisCount];
  };
  // Excitation generator: integer phase accumulators (2^32 = one turn).
  struct Excitation {
    bool active = false;
    int axis = 0;
    std::uint32_t phase[kMaxExcitationHarmonics] = {};
    std::uint32_t increment[kMaxExcitationHarmonics] = {};
    Scalar amplitude[kMaxExcitationHarmonics] = {};
    std::uint32_t tick = 0;
    std::uint32_t duration_ticks = 0;  // 0: until stopped
  };
  // The running calibration (CouplingIdentifier holds the DFTs).
  struct Calibration {
    bool running = false;
    int experiment = 0;            // 0-5 identify axis j, 6-11 verify axis j - 6
    std::uint32_t tick = 0;        // within the experiment
    std::uint32_t settle_ticks = 0;
    std::uint32_t window_ticks = 0;
    std::uint32_t increment = 0;   // the fundamental's phase increment
    std::uint32_t phase = 0;       // DFT reference phase (0 at the window's start)
    Pose64 start{};                // pose at the window's start
    CouplingCorrection previous{};  // restored when the calibration fails
  };
  // Correction ramp: the applied matrix moves from `from` to config_.coupling
  // over kCouplingRampTicks, so switching it while levitated is no effort step.
  static constexpr float kCouplingRamp_s = 0.5f;
  std::uint32_t coupling_ramp_ticks_ = 1250;  // kCouplingRamp_s at the configured rate (apply_config)
  struct CouplingRamp {
    std::uint32_t left = 0;
    float from[kCouplingMatrixSize] = {};
  };
  // The active configuration, through numeric::OpaquePointer: GCC otherwise
  // rebuilds this + 2272 * active_ + offset before nearly every float load
  // of the unrolled per-axis code (docs/PERFORMANCE.md, "Session of
  // 2026-11-28").
  const Applied& applied() const { return *numeric::OpaquePointer(&applied_[active_]); }
  // Axis a's loop, whichever type `ap` selected (AxisLoop dispatches);
  // kPidOnly only where ap.all_pid.
  template <bool kPidOnly = false>
  AxisLoop<Scalar, kPidOnly> loop(const Applied& ap, int a) {
    return AxisLoop<Scalar, kPidOnly>(ap.type[a], &ap.pid[a], &pid_state_[a], &ap.imr[a], &imr_state_[a]);
  }

  // The locals of one step(), handed from stage to stage of the data path.
  // The arrays and results below are written in full by their stage every
  // tick before anything reads them, so they are left uninitialized: zeroing
  // the whole Tick was a ~600-byte memset per step() (issue 16, measured).
  // Tick::out, allocate_forces()'s result. Fixed point: the controller's
  // (allocation_out_), by reference. A Tick-local one was value-initialized
  // every tick (Fixed's zero default: a memset call, ~137 M7 instructions),
  // and allocate_forces() writes every field of it on every tick before
  // anything reads it. Float's is trivial, so it stays in the Tick (reached
  // from the stack pointer: 5 instructions fewer than through a reference).
  template <bool kByReference, typename = void>
  struct AllocationOutputSlot {
    explicit AllocationOutputSlot(AllocationOutput<Scalar>&) {}
    AllocationOutput<Scalar> out;
  };
  template <typename Unused>
  struct AllocationOutputSlot<true, Unused> {
    explicit AllocationOutputSlot(AllocationOutput<Scalar>& allocation) : out(allocation) {}
    AllocationOutput<Scalar>& out;
  };
  struct Tick : AllocationOutputSlot<Traits::kIsFixed> {
    // step()'s local, initialized by SensorsToPoseStep's return value in
    // place: held by reference, the Tick no longer copies the 136-byte
    // result into itself (a memcpy per tick, ~90 M7 instructions).
    // The sequencer's inputs are the controller's (sequencer_inputs_): a
    // Tick-local SequencerInputs{} cost a 36-byte memset call every tick,
    // though supervise() and sequence() write every field but the two
    // homing flags, which step() clears.
    Tick(PoseMeasurement& pose, SequencerInputs& inputs, AllocationOutput<Scalar>& allocation)
        : AllocationOutputSlot<Traits::kIsFixed>(allocation), m(pose), qi(inputs) {}
    PoseMeasurement& m;   // sensors -> pose (step())
    SupervisorInputs si;  // supervise()
    const SupervisorStatus* sup = nullptr;
    const SequencerOutput* so = nullptr;
    SequencerInputs& qi;  // supervise() (abs_error), home() (homing flags), sequence()
    Scalar accel_ff[kAxisCount];         // advance_references()
    std::int64_t step_pm[kAxisCount];    // advance_references()
    Scalar excitation[kAxisCount];       // excite()
    // External injection at the reference: added to the reference around the
    // axis loops (no per-axis cost), in pm / prad.
    std::int64_t reference_injection_pm = 0;
    float reference_injection = 0.0f;  // the same, m or rad (status)
    bool injecting = false;
    Scalar effort[kAxisCount];     // run_axis_loops()
    Scalar aw_offset[kAxisCount];  // loop output before the biquads minus after them
  };
  // step(), stage by stage: sensors -> pose -> supervision -> homing ->
  // sequencer -> references -> excitation -> axis loops -> force allocation
  // (+ anti-windup) -> coil currents -> DAC -> status.
  void supervise(const io::SensorSample& sample, bool tick_overrun, Tick& t);
  void home(const io::SensorSample& sample, Tick& t);
  void sequence(Tick& t);
  void advance_references(Tick& t);
  void excite(Tick& t);
  void run_axis_loops(Tick& t);
  // f(std::true_type) where every axis is a PID (Applied::all_pid: the
  // loops' PID-only form), else f(std::false_type).
  template <typename F>
  void in_loop_form(F&& f) {
    if (applied().all_pid) {
      f(std::true_type{});
    } else {
      f(std::false_type{});
    }
  }
  template <bool kPidOnly>
  void run_axis_loops_as(Tick& t);
  void allocate_forces(Tick& t);
  template <bool kPidOnly>
  void apply_loop_limits_as(Tick& t);
  io::ActuatorCommand coil_currents_to_dac(const Tick& t);
  void publish_status(const Tick& t, bool amplifiers_enabled);

  bool levitated_or_busy() const;
  MAGLEV_CONFIG_CODE AxisReferenceLimits axis_limits(int a) const;
  void hold();
  MAGLEV_CONFIG_CODE ConfigError refuse_config(ConfigError e);  // records it as the last config error
  MAGLEV_CONFIG_CODE CommandResult start_excitation(const MotionCommand& cmd);
  MAGLEV_CONFIG_CODE CommandResult start_calibration();
  void calibrate(Tick& t);            // before excite(): aborts, starts each experiment
  void calibration_accumulate();      // after the loops: the DFTs of U and Y
  void finish_calibration(CouplingCalibrationResult r, bool restore);
  void set_coupling(const CouplingCorrection& c);  // with the ramp
  void radii(float r[kAxisCount]) const;

  // The tick's own state first, in the order of use: a VFP load or an LDRD
  // reaches 1020 bytes past its base, and GCC addresses members as this +
  // offset, so each one further away costs an address computation before
  // its loads (issue 16; docs/PERFORMANCE.md, "Session of 2026-11-28").
  int active_ = 0;
  Pid2DofState<Scalar> pid_state_[kAxisCount]{};
  BiquadBank<Scalar, kAxisCount> filters_{};
  ControllerStatus status_{};  // the pose and the reference included
  std::int64_t pending_step_pm_[kAxisCount] = {};  // step() applies and reports it
  // Bit a: axis a may have a profile or a pending step (a superset: command()
  // sets the bit with either, advance_references() clears it once both are
  // gone). The tick visits these axes only; a clear bit is a quiet axis.
  std::uint32_t maybe_busy_axes_ = 0;
  // Bit a: status_.reference_acceleration[a] may be nonzero (a superset).
  std::uint32_t reference_acceleration_set_ = 0;
  bool last_current_limited_ = false;  // last tick's allocation scaled the currents down
  std::uint8_t stage_profile_error_ = 0;  // see set_stage_profile_error()
  Profile profile_[kAxisCount]{};
  Excitation excitation_{};
  Injection injection_{};
  SequencerInputs sequencer_inputs_{};  // Tick::qi
  AllocationOutput<Scalar> allocation_out_{};  // Tick::out (fixed point)
  KernelConfig config_{};
  Applied applied_[2]{};
  SensorsToPoseState s2p_{};
  Sequencer sequencer_{};
  Supervisor supervisor_{};
  InternalModelState<Scalar> imr_state_[kAxisCount]{};
  LoopType running_type_[kAxisCount] = {};  // detects a live loop-type switch (bumpless hand-over)
  MoveReference move_[kAxisCount]{};
  SinusoidReference sinusoid_[kAxisCount]{};
  CircleReference circle_{};  // drives x (its Profile) and y (kind kCircle, tick unused)
  AxisReference circle_y_{};  // y's sample, produced with x's in the same tick
  bool circle_y_valid_ = false;
  bool circle_y_last_ = false;
  StopReference stop_[kAxisCount]{};  // kHold: a moving reference brought to rest
  std::uint32_t homing_ticks_ = 0;
  std::uint32_t homing_needed_ticks_ = 1;
  // TiltLock levelling (apply_config): the theta_x / theta_y reference range
  // and the ramp per tick, in pico; and whether both references are inside
  // it (advance_references -> next tick's sequencer inputs).
  std::int64_t tilt_min_pico_[2] = {};
  std::int64_t tilt_max_pico_[2] = {};
  std::int64_t tilt_level_step_pico_ = 1;
  bool tilt_references_in_range_ = false;
  // Homing's Hall solve: what it reads of the sample seven ticks before the
  // end of the homing window, with that sample's unhomed pose, and what it
  // gives; the generation ties a result to its request.
  struct HallRequest {
    HallSolveInputs inputs;
    Pose64 pose_unhomed;
    std::uint32_t generation;
  };
  struct HallResult {
    HallPhase phase;
    HomingOffsets offsets;  // zero when the phase is not plausible
    std::uint32_t generation;
  };
  static HallResult SolveHoming(const HallRequest& request);
  // step()'s own request, and the job handed to background(). Single core,
  // step() above background(): step() writes the job's request only while
  // the job is not kRunning, and background() reads it only after setting
  // kRunning, so each sees the other's writes whole.
  enum class HallJob : std::uint8_t { kIdle = 0, kRequested = 1, kRunning = 2, kDone = 3 };
  HallRequest hall_request_{};
  volatile HallJob hall_job_ = HallJob::kIdle;
  HallRequest hall_job_request_{};
  HallResult hall_job_result_{};
  std::uint32_t hall_solves_in_tick_ = 0;
  CouplingCalibrationConfig calibration_config_{};
  Calibration cal_{};
  CouplingIdentifier identifier_{};
  CouplingRamp ramp_{};
  float calib_effort_[kAxisCount] = {};  // this tick's U (float) for the DFT
  // prepare_config's results for commit_config (the designs are in the idle
  // slot of applied_).
  SensorsToPoseState s2p_next_{};
  SupervisorSettings supervisor_next_{};  // prepare_config's, for commit_config
  bool prepared_ = false;
};

extern template class Controller<float>;
extern template class Controller<numeric::Q7_24>;

}  // namespace maglev::kernel
