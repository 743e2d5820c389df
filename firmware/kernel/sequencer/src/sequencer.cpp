#include "maglev/io/code_placement.hpp"
#include "maglev/sequencer/sequencer.hpp"

namespace maglev::kernel {
namespace {

bool positive(float v) { return v > 0.0f && v < 1e30f; }  // also rejects NaN

std::uint32_t to_ticks(float seconds, float rate_Hz) {
  const float t = seconds * rate_Hz;
  // Round up: a timeout never fires early; at least one tick.
  auto n = static_cast<std::uint32_t>(t);
  if (static_cast<float>(n) < t) ++n;
  return n == 0 ? 1u : n;
}


// Moves value toward target by at most step; returns the new value.
float approach(float value, float target, float step) {
  if (value < target) return (target - value) <= step ? target : value + step;
  return (value - target) <= step ? target : value - step;
}

}  // namespace

MAGLEV_CONFIG_CODE SequencerConfigError validate(const SequencerConfig& c, float servo_rate_Hz) {
  if (!(servo_rate_Hz >= 100.0f && servo_rate_Hz <= 100000.0f)) return SequencerConfigError::kBadServoRate;
  const float timeouts[] = {c.homing_time_s, c.homing_timeout_s, c.inplane_settle_time_s,
                            c.inplane_timeout_s, c.lift_capture_time_s, c.lift_timeout_s,
                            c.z_settle_time_s, c.zlock_timeout_s, c.tilt_settle_time_s,
                            c.tiltlock_timeout_s, c.touchdown_time_s, c.landing_timeout_s};
  for (float t : timeouts) {
    if (!positive(t) || t > 60.0f) return SequencerConfigError::kBadTimeout;
  }
  // A settle window must fit inside its state's timeout, or the state can only time out.
  if (c.homing_time_s >= c.homing_timeout_s || c.inplane_settle_time_s >= c.inplane_timeout_s ||
      c.lift_capture_time_s >= c.lift_timeout_s || c.z_settle_time_s >= c.zlock_timeout_s ||
      c.tilt_settle_time_s >= c.tiltlock_timeout_s || c.touchdown_time_s >= c.landing_timeout_s) {
    return SequencerConfigError::kBadTimeout;
  }
  if (!positive(c.lift_ramp_rate_per_s) || !positive(c.landing_ff_ramp_rate_per_s) ||
      !positive(c.z_reference_rate_m_per_s) || !positive(c.landing_z_rate_m_per_s) ||
      c.z_reference_rate_m_per_s > 1e-2f || c.landing_z_rate_m_per_s > 1e-2f ||
      !positive(c.tilt_reference_rate_rad_per_s) || c.tilt_reference_rate_rad_per_s > 0.1f ||
      c.lift_ramp_rate_per_s > 10.0f || c.landing_ff_ramp_rate_per_s > 10.0f) {
    return SequencerConfigError::kBadRampRate;
  }
  if (!(c.lift_max_fraction >= 0.5f && c.lift_max_fraction <= 3.0f)) return SequencerConfigError::kBadThreshold;
  if (!positive(c.inplane_settle_error_m) || !positive(c.inplane_settle_error_rad) ||
      !positive(c.z_settle_error_m) || !positive(c.tilt_settle_error_rad) ||
      !positive(c.lift_capture_window_m) || !positive(c.liftoff_height_m) ||
      !positive(c.touchdown_height_m)) {
    return SequencerConfigError::kBadThreshold;
  }
  // Paper 000 Sec. V puts the seed's within 40 um of rest; a stage's own
  // comes from its profile, and prepare_config keeps it inside the
  // supervisor's z window (itself inside the height sensors' range). 1 mm
  // is a sanity bound only (the seed's 40 um here refused a taller stage).
  if (!positive(c.nominal_height_m) || c.nominal_height_m > 1e-3f ||
      c.liftoff_height_m >= c.nominal_height_m - c.lift_capture_window_m ||
      c.touchdown_height_m >= c.nominal_height_m) {
    return SequencerConfigError::kBadHeight;
  }
  return SequencerConfigError::kOk;
}

MAGLEV_CONFIG_CODE void Sequencer::configure(const SequencerConfig& c, float servo_rate_Hz) {
  config_ = c;
  dt_s_ = 1.0f / servo_rate_Hz;
  ticks_.homing_timeout = to_ticks(c.homing_timeout_s, servo_rate_Hz);
  ticks_.inplane_settle = to_ticks(c.inplane_settle_time_s, servo_rate_Hz);
  ticks_.inplane_timeout = to_ticks(c.inplane_timeout_s, servo_rate_Hz);
  ticks_.lift_capture = to_ticks(c.lift_capture_time_s, servo_rate_Hz);
  ticks_.lift_timeout = to_ticks(c.lift_timeout_s, servo_rate_Hz);
  ticks_.z_settle = to_ticks(c.z_settle_time_s, servo_rate_Hz);
  ticks_.zlock_timeout = to_ticks(c.zlock_timeout_s, servo_rate_Hz);
  ticks_.tilt_settle = to_ticks(c.tilt_settle_time_s, servo_rate_Hz);
  ticks_.tiltlock_timeout = to_ticks(c.tiltlock_timeout_s, servo_rate_Hz);
  ticks_.touchdown = to_ticks(c.touchdown_time_s, servo_rate_Hz);
  ticks_.landing_timeout = to_ticks(c.landing_timeout_s, servo_rate_Hz);
}

MAGLEV_CONFIG_CODE void Sequencer::reset() {
  out_ = SequencerOutput{};
  levitate_pending_ = false;
  fault_latched_ = false;
  enter(SequencerState::kIdle, TransitionReason::kPowerOn);
}

void Sequencer::enter(SequencerState s, TransitionReason r) {
  out_.state = s;
  out_.last_reason = r;
  ticks_in_state_ = 0;
  settle_ticks_ = 0;
  if (s == SequencerState::kIdle || s == SequencerState::kFault) {
    out_.feedforward_fraction = 0.0f;
    out_.lifted_off = false;
  }
  if (s == SequencerState::kFault) {
    out_.homed = false;
    levitate_pending_ = false;
  }
  update_outputs();
}

void Sequencer::begin_landing(TransitionReason r) {
  landing_with_z_ = (out_.closed_axes & kAxisBitZ) != 0;
  landing_closed_ = out_.closed_axes;
  landing_phase_ = landing_with_z_ ? LandingPhase::kDescend : LandingPhase::kRampOut;
  levitate_pending_ = false;
  enter(SequencerState::kLanding, r);
}

MAGLEV_CONFIG_CODE SequencerCommandResult Sequencer::command(SequencerCommand cmd, bool fault_cause_present) {
  using S = SequencerState;
  using R = SequencerCommandResult;
  const S s = out_.state;
  const bool levitating = s == S::kLift || s == S::kZLock || s == S::kTiltLock || s == S::kReady;
  switch (cmd) {
    case SequencerCommand::kHome:
      if (s == S::kFault) return R::kRefusedFaultLatched;
      if (s == S::kHoming) return R::kAlreadyThere;
      if (s != S::kIdle) return R::kRefusedBusy;
      levitate_pending_ = false;
      enter(S::kHoming, TransitionReason::kHomeCommand);
      return R::kAccepted;
    case SequencerCommand::kLevitate:
      if (s == S::kFault) return R::kRefusedFaultLatched;
      if (s == S::kLanding) return R::kRefusedBusy;
      if (s == S::kHoming) {
        levitate_pending_ = true;
        return R::kAccepted;
      }
      if (s != S::kIdle) return R::kAlreadyThere;
      if (out_.homed) {
        enter(S::kInPlaneLock, TransitionReason::kLevitateCommand);
      } else {
        levitate_pending_ = true;
        enter(S::kHoming, TransitionReason::kLevitateCommand);
      }
      return R::kAccepted;
    case SequencerCommand::kLand:
      if (s == S::kLanding) return R::kAlreadyThere;
      if (!levitating) return R::kRefusedNotLevitated;
      begin_landing(TransitionReason::kLandCommand);
      return R::kAccepted;
    case SequencerCommand::kStop:
      if (levitating) {
        begin_landing(TransitionReason::kStopCommand);
        return R::kAccepted;
      }
      if (s == S::kHoming || s == S::kInPlaneLock) {
        levitate_pending_ = false;
        enter(S::kIdle, TransitionReason::kStopCommand);
        return R::kAccepted;
      }
      return R::kAlreadyThere;
    case SequencerCommand::kClearFault:
      if (s != S::kFault) return R::kRefusedNotFaulted;
      if (fault_cause_present) return R::kRefusedFaultActive;
      fault_latched_ = false;
      enter(S::kIdle, TransitionReason::kFaultCleared);
      return R::kAccepted;
  }
  return R::kRefusedBusy;
}

const SequencerOutput& Sequencer::step(const SequencerInputs& in) {
  using S = SequencerState;
  // 1. The supervisor's reaction overrides everything; it only ever escalates.
  if (in.fault_reaction == FaultReaction::kCurrentsOff && out_.state != S::kFault) {
    fault_latched_ = true;
    enter(S::kFault, TransitionReason::kFaultCurrentsOff);
  } else if (in.fault_reaction == FaultReaction::kLand && !fault_latched_) {
    fault_latched_ = true;
    const S s = out_.state;
    if (s == S::kLift || s == S::kZLock || s == S::kTiltLock || s == S::kReady) {
      begin_landing(TransitionReason::kFaultLanding);
    } else if (s != S::kLanding) {
      // On rest (or homing): nothing to land; latch with currents off.
      enter(S::kFault, TransitionReason::kFaultLatched);
    }
  }

  ++ticks_in_state_;
  switch (out_.state) {
    case S::kIdle:
    case S::kFault:
      break;
    case S::kHoming:
      if (in.homing_failed) {
        levitate_pending_ = false;
        enter(S::kIdle, TransitionReason::kHomingFailed);
      } else if (in.homing_done) {
        out_.homed = true;
        if (levitate_pending_) {
          levitate_pending_ = false;
          enter(S::kInPlaneLock, TransitionReason::kHomingDone);
        } else {
          enter(S::kIdle, TransitionReason::kHomingDone);
        }
      } else if (ticks_in_state_ >= ticks_.homing_timeout) {
        levitate_pending_ = false;
        enter(S::kIdle, TransitionReason::kHomingTimeout);
      }
      break;
    case S::kInPlaneLock: {
      const bool inside = in.abs_error[0] <= config_.inplane_settle_error_m &&
                          in.abs_error[1] <= config_.inplane_settle_error_m &&
                          in.abs_error[2] <= config_.inplane_settle_error_rad;
      settle_ticks_ = inside ? settle_ticks_ + 1 : 0;
      if (settle_ticks_ >= ticks_.inplane_settle) {
        enter(S::kLift, TransitionReason::kInPlaneSettled);
      } else if (ticks_in_state_ >= ticks_.inplane_timeout) {
        enter(S::kIdle, TransitionReason::kInPlaneTimeout);
      }
      break;
    }
    case S::kLift: {
      // "The control effort in z is increased by repeatedly feedforwarding a
      // constant amount" (paper 000 Sec. IV) -- up while below the capture
      // window, down while above it, held inside it.
      const float step = config_.lift_ramp_rate_per_s * dt_s_;
      const float lo = config_.nominal_height_m - config_.lift_capture_window_m;
      const float hi = config_.nominal_height_m + config_.lift_capture_window_m;
      float ff = out_.feedforward_fraction;
      if (in.z_valid) {
        if (in.z_m < lo) ff = approach(ff, config_.lift_max_fraction, step);
        if (in.z_m > hi) ff = approach(ff, 0.0f, step);
        if (in.z_m > config_.liftoff_height_m) out_.lifted_off = true;
      }
      out_.feedforward_fraction = ff;
      const bool inside = in.z_valid && in.z_m >= lo && in.z_m <= hi;
      settle_ticks_ = inside ? settle_ticks_ + 1 : 0;
      if (settle_ticks_ >= ticks_.lift_capture) {
        enter(S::kZLock, TransitionReason::kNominalHeightReached);
        out_.z_reference_m = in.z_m;  // bumpless: the z loop closes on the measured height
      } else if (ticks_in_state_ >= ticks_.lift_timeout) {
        begin_landing(out_.lifted_off ? TransitionReason::kLiftTimeout : TransitionReason::kNoLiftOff);
      }
      break;
    }
    case S::kZLock: {
      out_.z_reference_m = approach(out_.z_reference_m, config_.nominal_height_m,
                                    config_.z_reference_rate_m_per_s * dt_s_);
      const bool inside = out_.z_reference_m == config_.nominal_height_m &&
                          in.abs_error[3] <= config_.z_settle_error_m;
      settle_ticks_ = inside ? settle_ticks_ + 1 : 0;
      if (settle_ticks_ >= ticks_.z_settle) {
        enter(S::kTiltLock, TransitionReason::kZSettled);
      } else if (ticks_in_state_ >= ticks_.zlock_timeout) {
        begin_landing(TransitionReason::kZLockTimeout);
      }
      break;
    }
    case S::kTiltLock: {
      const bool inside = in.abs_error[4] <= config_.tilt_settle_error_rad &&
                          in.abs_error[5] <= config_.tilt_settle_error_rad && in.tilt_references_in_range;
      settle_ticks_ = inside ? settle_ticks_ + 1 : 0;
      if (settle_ticks_ >= ticks_.tilt_settle) {
        enter(S::kReady, TransitionReason::kTiltSettled);
      } else if (ticks_in_state_ >= ticks_.tiltlock_timeout) {
        begin_landing(TransitionReason::kTiltLockTimeout);
      }
      break;
    }
    case S::kReady:
      break;
    case S::kLanding: {
      // Phase 1: the z reference descends to rest with z (and tilt) closed.
      // Phase 2: z and tilt open (their integrators must not fight the
      // ramp), the feed-forward ramps out; in-plane stays closed until touchdown.
      if (landing_phase_ == LandingPhase::kDescend) {
        if (!in.z_valid) {
          landing_phase_ = LandingPhase::kRampOut;  // no height: skip to open-loop ramp-out
        } else {
          out_.z_reference_m = approach(out_.z_reference_m, 0.0f, config_.landing_z_rate_m_per_s * dt_s_);
          if (out_.z_reference_m == 0.0f) landing_phase_ = LandingPhase::kRampOut;
        }
      } else {
        out_.feedforward_fraction = approach(out_.feedforward_fraction, 0.0f,
                                             config_.landing_ff_ramp_rate_per_s * dt_s_);
        const bool down = out_.feedforward_fraction == 0.0f &&
                          (!in.z_valid || in.z_m <= config_.touchdown_height_m);
        settle_ticks_ = down ? settle_ticks_ + 1 : 0;
      }
      if (settle_ticks_ >= ticks_.touchdown) {
        if (fault_latched_) {
          enter(S::kFault, TransitionReason::kFaultLatched);
        } else {
          enter(S::kIdle, TransitionReason::kTouchdown);
        }
      } else if (ticks_in_state_ >= ticks_.landing_timeout) {
        if (fault_latched_) {
          enter(S::kFault, TransitionReason::kFaultLatched);
        } else {
          enter(S::kIdle, TransitionReason::kLandingTimeout);
        }
      }
      break;
    }
  }
  update_outputs();
  if (!(out_.closed_axes & kAxisBitZ)) {
    // Open z: the reference follows the measurement so closing it is bumpless.
    out_.z_reference_m = in.z_m;
  }
  return out_;
}

void Sequencer::update_outputs() {
  using S = SequencerState;
  std::uint8_t closed = 0;
  bool amp = false;
  switch (out_.state) {
    case S::kIdle:
    case S::kHoming:
    case S::kFault:
      break;
    case S::kInPlaneLock:
    case S::kLift:
      closed = kAxisMaskInPlane;
      amp = true;
      break;
    case S::kZLock:
      closed = kAxisMaskInPlane | kAxisBitZ;
      amp = true;
      break;
    case S::kTiltLock:
    case S::kReady:
      closed = kAxisMaskAll;
      amp = true;
      break;
    case S::kLanding:
      closed = landing_phase_ == LandingPhase::kDescend ? landing_closed_ : kAxisMaskInPlane;
      amp = true;
      break;
  }
  out_.closed_axes = closed;
  out_.amplifier_enable = amp;
  out_.homing_active = out_.state == S::kHoming;
  out_.levitated = (out_.state == S::kLift && out_.lifted_off) || out_.state == S::kZLock ||
                   out_.state == S::kTiltLock || out_.state == S::kReady ||
                   out_.state == S::kLanding;
  out_.motion_allowed = out_.state == S::kReady;
}

MAGLEV_ENUM_TO_STRING(SequencerState, MAGLEV_SEQUENCER_STATES)

MAGLEV_ENUM_TO_STRING(TransitionReason, MAGLEV_TRANSITION_REASONS)

}  // namespace maglev::kernel
