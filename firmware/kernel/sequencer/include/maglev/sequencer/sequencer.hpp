// The start-up / shut-down sequencer of paper 000, Section V.
//
//   Idle -> Homing -> InPlaneLock -> Lift -> ZLock -> TiltLock -> Ready
//   Ready (or any levitated state) -> Landing -> Idle
//
// The stage is open-loop unstable in x, y, theta_z once it floats, so the
// order is not negotiable: the in-plane loops close while the platen still
// rests on the magnet matrix, a gravity feed-forward ramp lifts it to the
// nominal height (within 40 um of rest), the z loop closes at low bandwidth
// while the feed-forward stays, then theta_x / theta_y close.
//
// The sequencer only decides; it never touches Scalar arithmetic. Its output
// per tick says which axes are closed, the gravity feed-forward fraction, the
// z reference and a few flags. It works in SI floats and in whole ticks, so
// its decisions are identical in the float and the Q7.24 kernel.
#pragma once

#include "maglev/io/enum_names.hpp"

#include <cstdint>

namespace maglev::kernel {

// Axis bit masks, in the order of maglev::kernel::Axis (axis_loops):
// x, y, theta_z, z, theta_x, theta_y -- the order of U in eq (21).
inline constexpr std::uint8_t kAxisBitX = 1u << 0;
inline constexpr std::uint8_t kAxisBitY = 1u << 1;
inline constexpr std::uint8_t kAxisBitThetaZ = 1u << 2;
inline constexpr std::uint8_t kAxisBitZ = 1u << 3;
inline constexpr std::uint8_t kAxisBitThetaX = 1u << 4;
inline constexpr std::uint8_t kAxisBitThetaY = 1u << 5;
inline constexpr std::uint8_t kAxisMaskInPlane = kAxisBitX | kAxisBitY | kAxisBitThetaZ;
inline constexpr std::uint8_t kAxisMaskTilt = kAxisBitThetaX | kAxisBitThetaY;
inline constexpr std::uint8_t kAxisMaskAll = kAxisMaskInPlane | kAxisBitZ | kAxisMaskTilt;
inline constexpr int kSequencedAxes = 6;

// SequencerState: value and name of every enumerator, defined once (the enum and
// to_string() are generated from it). Values cross a wire or a register:
// never renumber, only append.
#define MAGLEV_SEQUENCER_STATES(X) \
  X(kIdle, 0, "Idle") \
  X(kHoming, 1, "Homing") \
  X(kInPlaneLock, 2, "InPlaneLock") \
  X(kLift, 3, "Lift") \
  X(kZLock, 4, "ZLock") \
  X(kTiltLock, 5, "TiltLock") \
  X(kReady, 6, "Ready") \
  X(kLanding, 7, "Landing") \
  X(kFault, 8, "Fault")  /* latched by the supervisor's currents-off reaction (or a landing after a fault) */

enum class SequencerState : std::uint8_t {
  MAGLEV_SEQUENCER_STATES(MAGLEV_ENUMERATOR)
};

// Why the last transition happened. Stored with the state; CAN/Modbus report it.
// TransitionReason: value and name of every enumerator, defined once (the enum and
// to_string() are generated from it). Values cross a wire or a register:
// never renumber, only append.
#define MAGLEV_TRANSITION_REASONS(X) \
  X(kNone, 0, "None") \
  X(kPowerOn, 1, "PowerOn") \
  X(kHomeCommand, 2, "HomeCommand") \
  X(kLevitateCommand, 3, "LevitateCommand")  /* Idle -> InPlaneLock (already homed) or Idle -> Homing */ \
  X(kHomingDone, 4, "HomingDone")  /* Homing -> Idle (home only) or -> InPlaneLock (levitate pending) */ \
  X(kHomingFailed, 5, "HomingFailed")  /* Homing -> Idle: Hall phase implausible */ \
  X(kHomingTimeout, 6, "HomingTimeout")  /* Homing -> Idle */ \
  X(kInPlaneSettled, 7, "InPlaneSettled")  /* InPlaneLock -> Lift */ \
  X(kInPlaneTimeout, 8, "InPlaneTimeout")  /* InPlaneLock -> Idle */ \
  X(kNominalHeightReached, 9, "NominalHeightReached")  /* Lift -> ZLock */ \
  X(kLiftTimeout, 10, "LiftTimeout")  /* Lift -> Landing (platen lifted off but never captured) */ \
  X(kNoLiftOff, 11, "NoLiftOff")  /* Lift -> Landing (feed-forward at its cap, platen still on rest) */ \
  X(kZSettled, 12, "ZSettled")  /* ZLock -> TiltLock */ \
  X(kZLockTimeout, 13, "ZLockTimeout")  /* ZLock -> Landing */ \
  X(kTiltSettled, 14, "TiltSettled")  /* TiltLock -> Ready */ \
  X(kTiltLockTimeout, 15, "TiltLockTimeout")  /* TiltLock -> Landing */ \
  X(kLandCommand, 16, "LandCommand")  /* levitated -> Landing */ \
  X(kStopCommand, 17, "StopCommand")  /* levitated -> Landing, or Homing/InPlaneLock -> Idle */ \
  X(kTouchdown, 18, "Touchdown")  /* Landing -> Idle */ \
  X(kLandingTimeout, 19, "LandingTimeout")  /* Landing -> Idle (currents off; the platen is on rest or close to it) */ \
  X(kFaultLanding, 20, "FaultLanding")  /* levitated -> Landing, supervisor chose a controlled landing */ \
  X(kFaultCurrentsOff, 21, "FaultCurrentsOff")  /* any -> Fault, supervisor chose currents off */ \
  X(kFaultLatched, 22, "FaultLatched")  /* Landing (after a fault) -> Fault on touchdown/timeout */ \
  X(kFaultCleared, 23, "FaultCleared")  /* Fault -> Idle */

enum class TransitionReason : std::uint8_t {
  MAGLEV_TRANSITION_REASONS(MAGLEV_ENUMERATOR)
};

enum class SequencerCommand : std::uint8_t { kHome = 0, kLevitate, kLand, kStop, kClearFault };

enum class SequencerCommandResult : std::uint8_t {
  kAccepted = 0,
  kAlreadyThere,        // e.g. levitate while Ready: nothing to do, not an error
  kRefusedBusy,         // a transition is under way that the command may not interrupt
  kRefusedNotLevitated, // land while on rest
  kRefusedFaultLatched, // home / levitate while in Fault
  kRefusedNotFaulted,   // clear_fault while not in Fault
  kRefusedFaultActive,  // clear_fault while the supervisor still sees the cause
};

enum class FaultReaction : std::uint8_t { kNone = 0, kLand, kCurrentsOff };

enum class SequencerConfigError : std::uint8_t {
  kOk = 0,
  kBadTimeout,
  kBadRampRate,
  kBadThreshold,
  kBadHeight,
  kBadServoRate,
};

// Every timeout, ramp rate and threshold, in SI. Defaults: paper 000 Sec. V
// says "within a few seconds" for the whole start-up; the numbers below are
// ours and leave each state about an order of magnitude of margin.
struct SequencerConfig {
  float homing_time_s = 0.1f;        // Hall averaging window (the controller uses it)
  float homing_timeout_s = 1.0f;
  float inplane_settle_error_m = 2e-6f;      // |e_x|, |e_y| below this ...
  float inplane_settle_error_rad = 20e-6f;   // ... and |e_theta_z| below this ...
  float inplane_settle_time_s = 0.1f;        // ... for this long -> Lift
  float inplane_timeout_s = 2.0f;
  float lift_ramp_rate_per_s = 0.5f;  // gravity feed-forward fraction per second
  float lift_max_fraction = 1.5f;     // cap; weight + cable stiffness + payload margin
  float liftoff_height_m = 3e-6f;     // measured height that counts as "lifted off"
  float nominal_height_m = 30e-6f;    // io::stage::kNominalHeight_m
  float lift_capture_window_m = 4e-6f;  // |z - nominal| below this ...
  float lift_capture_time_s = 0.04f;    // ... for this long -> ZLock
  float lift_timeout_s = 6.0f;
  float z_reference_rate_m_per_s = 50e-6f;  // z ref: measured height -> nominal in ZLock
  float z_settle_error_m = 2e-6f;
  float z_settle_time_s = 0.1f;
  float zlock_timeout_s = 3.0f;
  float tilt_settle_error_rad = 20e-6f;
  float tilt_settle_time_s = 0.1f;
  // TiltLock: a tilt reference captured outside the reference range (a CoM
  // offset tilts the platen while it lifts with the tilts open) moves to the
  // range's nearest end at this rate before Ready (the controller ramps it).
  float tilt_reference_rate_rad_per_s = 1e-3f;
  float tiltlock_timeout_s = 2.0f;
  float landing_z_rate_m_per_s = 60e-6f;      // descent of the z reference
  float landing_ff_ramp_rate_per_s = 1.0f;   // feed-forward fraction ramp-out
  float touchdown_height_m = 3e-6f;
  float touchdown_time_s = 0.04f;
  float landing_timeout_s = 5.0f;
};

SequencerConfigError validate(const SequencerConfig& config, float servo_rate_Hz);

struct SequencerInputs {
  bool homing_done = false;    // Hall phase and interferometer zero latched
  bool homing_failed = false;  // Hall amplitude implausible
  bool z_valid = false;        // laser displacement sensors trustworthy this tick
  float z_m = 0.0f;            // measured height above rest
  // |reference - measured| per axis in the Axis order, SI (m or rad).
  float abs_error[kSequencedAxes] = {};
  // theta_x and theta_y references inside the reference range (last tick's):
  // TiltLock waits for it.
  bool tilt_references_in_range = true;
  FaultReaction fault_reaction = FaultReaction::kNone;
};

struct SequencerOutput {
  SequencerState state = SequencerState::kIdle;
  TransitionReason last_reason = TransitionReason::kPowerOn;
  std::uint8_t closed_axes = 0;       // kAxisBit* mask
  bool amplifier_enable = false;
  float feedforward_fraction = 0.0f;  // of the gravity feed-forward, 0 .. lift_max_fraction
  float z_reference_m = 0.0f;         // meaningful while z is closed
  bool homing_active = false;         // the controller runs the Hall/zero homing math
  bool homed = false;
  bool lifted_off = false;
  bool levitated = false;             // Lift (after lift-off) .. Landing
  bool motion_allowed = false;        // Ready: references may move
};

class Sequencer {
 public:
  // Converts seconds to whole ticks. The caller validates first.
  void configure(const SequencerConfig& config, float servo_rate_Hz);
  void reset();  // -> Idle, not homed, reason kPowerOn

  SequencerCommandResult command(SequencerCommand cmd, bool fault_cause_present);

  // One tick: applies the fault reaction, advances the state, returns the output.
  const SequencerOutput& step(const SequencerInputs& in);

  // The states whose step reads SequencerInputs::abs_error (the settle
  // checks of InPlaneLock, ZLock and TiltLock): in every other state the
  // controller leaves those errors unformed (no conversion per tick).
  // Test Sequencer.OnlyTheLockStatesReadTheFollowingErrors holds it to step().
  static constexpr bool ReadsFollowingErrors(SequencerState s) {
    return s == SequencerState::kInPlaneLock || s == SequencerState::kZLock || s == SequencerState::kTiltLock;
  }

  const SequencerOutput& output() const { return out_; }
  std::uint32_t ticks_in_state() const { return ticks_in_state_; }
  // Homing is lost after any fault: the interferometer zero may have slipped.
  void invalidate_homing() { out_.homed = false; }

 private:
  struct Ticks {
    std::uint32_t homing_timeout, inplane_settle, inplane_timeout, lift_capture,
        lift_timeout, z_settle, zlock_timeout, tilt_settle, tiltlock_timeout,
        touchdown, landing_timeout;
  };
  enum class LandingPhase : std::uint8_t { kDescend, kRampOut };

  void enter(SequencerState s, TransitionReason r);
  void begin_landing(TransitionReason r);
  void update_outputs();

  SequencerConfig config_{};
  Ticks ticks_{};
  float dt_s_ = 1.0f / 2500.0f;
  SequencerOutput out_{};
  std::uint32_t ticks_in_state_ = 0;
  std::uint32_t settle_ticks_ = 0;  // consecutive ticks inside the settle window
  bool levitate_pending_ = false;
  bool fault_latched_ = false;      // landing caused by a fault ends in Fault, not Idle
  bool landing_with_z_ = false;     // z was closed when landing began
  std::uint8_t landing_closed_ = 0; // axes closed during the descent phase
  LandingPhase landing_phase_ = LandingPhase::kDescend;
};

const char* to_string(SequencerState s);
const char* to_string(TransitionReason r);

}  // namespace maglev::kernel
