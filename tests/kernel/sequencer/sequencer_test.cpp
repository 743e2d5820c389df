// Every sequencer transition, timeout and fault path, with its reason code.
#include <CppUTest/TestHarness.h>

#include "maglev/sequencer/sequencer.hpp"

using namespace maglev::kernel;

namespace {

constexpr float kRate = 2500.0f;

struct Rig {
  Sequencer seq;
  SequencerInputs in;
  Rig() {
    SequencerConfig c;
    CHECK(validate(c, kRate) == SequencerConfigError::kOk);
    seq.configure(c, kRate);
    seq.reset();
    in.z_valid = true;
  }
  // A crude lift model: the platen floats once the feed-forward exceeds the
  // weight, and rises 100 um per unit fraction beyond it.
  void lift_model() {
    const float ff = seq.output().feedforward_fraction;
    in.z_m = ff > 1.0f ? (ff - 1.0f) * 100e-6f : 0.0f;
  }
  // check_unread: every step in a state that Sequencer::ReadsFollowingErrors
  // excludes is also taken by a copy with absurd errors, and must give the
  // same output (the controller leaves those errors unformed there).
  bool check_unread = false;
  int unread_checked = 0;
  void step() {
    if (!check_unread || Sequencer::ReadsFollowingErrors(seq.output().state)) {
      seq.step(in);
      return;
    }
    Sequencer other = seq;
    SequencerInputs wild = in;
    for (float& e : wild.abs_error) e = 1e30f;
    const SequencerOutput& b = other.step(wild);
    const SequencerOutput& a = seq.step(in);
    CHECK(a.state == b.state && a.last_reason == b.last_reason && a.closed_axes == b.closed_axes &&
          a.amplifier_enable == b.amplifier_enable && a.feedforward_fraction == b.feedforward_fraction &&
          a.z_reference_m == b.z_reference_m && a.homing_active == b.homing_active && a.homed == b.homed &&
          a.lifted_off == b.lifted_off && a.levitated == b.levitated && a.motion_allowed == b.motion_allowed &&
          seq.ticks_in_state() == other.ticks_in_state());
    ++unread_checked;
  }
  int run_until(SequencerState s, int max_ticks, bool model = false) {
    for (int n = 1; n <= max_ticks; ++n) {
      if (model) lift_model();
      step();
      if (seq.output().state == s) return n;
    }
    return -1;
  }
  void go_ready() {
    CHECK(seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kAccepted);
    in.homing_done = true;
    CHECK(run_until(SequencerState::kInPlaneLock, 10) > 0);
    in.homing_done = false;
    CHECK(run_until(SequencerState::kLift, 1000) > 0);
    CHECK(run_until(SequencerState::kZLock, 20000, true) > 0);
    CHECK(run_until(SequencerState::kTiltLock, 20000, true) > 0);
    CHECK(run_until(SequencerState::kReady, 2000, true) > 0);
  }
};

}  // namespace

TEST_GROUP(Sequencer){};

TEST(Sequencer, PowerOnIsIdleWithAmplifiersOff) {
  Rig r;
  const auto& o = r.seq.output();
  CHECK(o.state == SequencerState::kIdle);
  CHECK(o.last_reason == TransitionReason::kPowerOn);
  CHECK_FALSE(o.amplifier_enable);
  LONGS_EQUAL(0, o.closed_axes);
  DOUBLES_EQUAL(0.0, o.feedforward_fraction, 0.0);
  CHECK_FALSE(o.homed);
}

TEST(Sequencer, HomeThenDoneReturnsToIdleHomed) {
  Rig r;
  CHECK(r.seq.command(SequencerCommand::kHome, false) == SequencerCommandResult::kAccepted);
  CHECK(r.seq.output().state == SequencerState::kHoming);
  CHECK(r.seq.output().last_reason == TransitionReason::kHomeCommand);
  CHECK(r.seq.output().homing_active);
  CHECK_FALSE(r.seq.output().amplifier_enable);  // Hall readings without coil fields
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kHoming);
  r.in.homing_done = true;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kIdle);
  CHECK(r.seq.output().last_reason == TransitionReason::kHomingDone);
  CHECK(r.seq.output().homed);
}

TEST(Sequencer, HomingTimeoutAfterExactlyTheConfiguredTicks) {
  Rig r;
  r.seq.command(SequencerCommand::kHome, false);
  const int n = r.run_until(SequencerState::kIdle, 10000);
  LONGS_EQUAL(2500, n);  // 1.0 s at 2.5 kHz
  CHECK(r.seq.output().last_reason == TransitionReason::kHomingTimeout);
  CHECK_FALSE(r.seq.output().homed);
}

TEST(Sequencer, HomingFailed) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_failed = true;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kIdle);
  CHECK(r.seq.output().last_reason == TransitionReason::kHomingFailed);
}

TEST(Sequencer, FullStartUpSequenceInPaperOrder) {
  Rig r;
  CHECK(r.seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kAccepted);
  CHECK(r.seq.output().state == SequencerState::kHoming);  // not homed yet: home first
  CHECK(r.seq.output().last_reason == TransitionReason::kLevitateCommand);
  r.in.homing_done = true;
  r.seq.step(r.in);
  r.in.homing_done = false;
  CHECK(r.seq.output().state == SequencerState::kInPlaneLock);
  CHECK(r.seq.output().last_reason == TransitionReason::kHomingDone);
  LONGS_EQUAL(kAxisMaskInPlane, r.seq.output().closed_axes);
  CHECK(r.seq.output().amplifier_enable);
  DOUBLES_EQUAL(0.0, r.seq.output().feedforward_fraction, 0.0);
  // Settle: 0.1 s inside the window.
  LONGS_EQUAL(250, r.run_until(SequencerState::kLift, 1000));
  CHECK(r.seq.output().last_reason == TransitionReason::kInPlaneSettled);
  LONGS_EQUAL(kAxisMaskInPlane, r.seq.output().closed_axes);
  // Lift: ramp 0.5/s; floats above 1.0; capture window 26..34 um -> ff 1.26..
  const int lift_ticks = r.run_until(SequencerState::kZLock, 20000, true);
  CHECK(lift_ticks > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kNominalHeightReached);
  DOUBLES_EQUAL(1.26, r.seq.output().feedforward_fraction, 0.002);
  // 1.26 / 0.5 per s = 2.52 s = 6300 ticks, + 0.04 s capture = 100 ticks.
  DOUBLES_EQUAL(6400.0, lift_ticks, 5.0);
  LONGS_EQUAL(kAxisMaskInPlane | kAxisBitZ, r.seq.output().closed_axes);
  CHECK(r.seq.output().levitated);
  CHECK(r.seq.output().lifted_off);
  // Bumpless: z reference starts at the measured height, then ramps to 30 um.
  DOUBLES_EQUAL(r.in.z_m, r.seq.output().z_reference_m, 1e-9);
  CHECK(r.run_until(SequencerState::kTiltLock, 5000, true) > 0);
  DOUBLES_EQUAL(30e-6, r.seq.output().z_reference_m, 1e-12);
  CHECK(r.seq.output().last_reason == TransitionReason::kZSettled);
  LONGS_EQUAL(kAxisMaskAll, r.seq.output().closed_axes);
  CHECK_FALSE(r.seq.output().motion_allowed);
  LONGS_EQUAL(250, r.run_until(SequencerState::kReady, 1000, true));
  CHECK(r.seq.output().last_reason == TransitionReason::kTiltSettled);
  CHECK(r.seq.output().motion_allowed);
  CHECK(r.seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kAlreadyThere);
}

TEST(Sequencer, InPlaneTimeout) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  r.seq.step(r.in);
  r.in.abs_error[0] = 10e-6f;  // x never settles
  LONGS_EQUAL(5000, r.run_until(SequencerState::kIdle, 10000));
  CHECK(r.seq.output().last_reason == TransitionReason::kInPlaneTimeout);
  CHECK_FALSE(r.seq.output().amplifier_enable);
}

TEST(Sequencer, LiftNoLiftOffLandsWithReason) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  r.run_until(SequencerState::kLift, 1000);
  r.in.z_m = 0.0f;  // never floats
  LONGS_EQUAL(15000, r.run_until(SequencerState::kLanding, 20000));
  CHECK(r.seq.output().last_reason == TransitionReason::kNoLiftOff);
  DOUBLES_EQUAL(1.5, r.seq.output().feedforward_fraction, 1e-3);  // held at the cap
  // Ramp-out at 1.0/s, then touchdown dwell: back to Idle.
  CHECK(r.run_until(SequencerState::kIdle, 5000) > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kTouchdown);
}

TEST(Sequencer, LiftTimeoutWhenNeverCaptured) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  r.run_until(SequencerState::kLift, 1000);
  r.in.z_m = 10e-6f;  // floats but sticks below the window
  CHECK(r.run_until(SequencerState::kLanding, 20000) > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kLiftTimeout);
}

TEST(Sequencer, ZLockTimeout) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  CHECK(r.run_until(SequencerState::kZLock, 20000, true) > 0);
  r.in.abs_error[3] = 5e-6f;
  LONGS_EQUAL(7500, r.run_until(SequencerState::kLanding, 10000, true));
  CHECK(r.seq.output().last_reason == TransitionReason::kZLockTimeout);
}

TEST(Sequencer, TiltLockTimeout) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  CHECK(r.run_until(SequencerState::kTiltLock, 30000, true) > 0);
  r.in.abs_error[5] = 100e-6f;
  LONGS_EQUAL(5000, r.run_until(SequencerState::kLanding, 10000, true));
  CHECK(r.seq.output().last_reason == TransitionReason::kTiltLockTimeout);
}

// A tilt reference captured beyond the reference range (the controller ramps
// it in): TiltLock waits for it however small the errors are, then settles
// in tilt_settle_time_s.
TEST(Sequencer, TiltLockWaitsForTheTiltReferencesInRange) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  CHECK(r.run_until(SequencerState::kTiltLock, 30000, true) > 0);
  r.in.tilt_references_in_range = false;
  LONGS_EQUAL(-1, r.run_until(SequencerState::kReady, 1000, true));
  r.in.tilt_references_in_range = true;
  LONGS_EQUAL(250, r.run_until(SequencerState::kReady, 1000, true));
}

TEST(Sequencer, LandDescendsThenRampsOutThenTouchdown) {
  Rig r;
  r.go_ready();
  const float ff0 = r.seq.output().feedforward_fraction;
  CHECK(r.seq.command(SequencerCommand::kLand, false) == SequencerCommandResult::kAccepted);
  CHECK(r.seq.output().last_reason == TransitionReason::kLandCommand);
  // Phase 1: z stays closed, the reference descends 60 um/s, ff unchanged.
  r.in.z_m = 20e-6f;
  for (int n = 0; n < 100; ++n) r.seq.step(r.in);
  LONGS_EQUAL(kAxisMaskAll, r.seq.output().closed_axes);
  DOUBLES_EQUAL(30e-6 - 100 * 60e-6 / 2500.0, r.seq.output().z_reference_m, 1e-9);
  DOUBLES_EQUAL(ff0, r.seq.output().feedforward_fraction, 0.0);
  // The reference reaches 0 after 30 um / 60 um/s = 0.5 s = 1250 ticks.
  int n = 100;
  while (r.seq.output().closed_axes == kAxisMaskAll && n < 5000) {
    r.seq.step(r.in);
    ++n;
  }
  DOUBLES_EQUAL(1251.0, n, 2.0);  // phase 2 begins the tick after the reference hits 0
  // z is open again: its reference follows the measurement (bumpless re-close).
  DOUBLES_EQUAL(20e-6, r.seq.output().z_reference_m, 1e-12);
  LONGS_EQUAL(kAxisMaskInPlane, r.seq.output().closed_axes);
  LONGS_EQUAL(kAxisMaskInPlane, r.seq.output().closed_axes);
  r.seq.step(r.in);
  CHECK(r.seq.output().feedforward_fraction < ff0);
  r.in.z_m = 0.0f;
  CHECK(r.run_until(SequencerState::kIdle, 5000) > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kTouchdown);
  CHECK_FALSE(r.seq.output().amplifier_enable);
  CHECK(r.seq.output().homed);  // a normal landing keeps the interferometer zero
}

TEST(Sequencer, LandingTimeoutWhenTouchdownNeverSeen) {
  Rig r;
  r.go_ready();
  r.seq.command(SequencerCommand::kLand, false);
  r.in.z_m = 20e-6f;  // the platen "sticks" up
  LONGS_EQUAL(12500, r.run_until(SequencerState::kIdle, 20000));
  CHECK(r.seq.output().last_reason == TransitionReason::kLandingTimeout);
}

TEST(Sequencer, LandingWithoutHeightSensorSkipsDescent) {
  Rig r;
  r.go_ready();
  r.seq.command(SequencerCommand::kStop, false);
  CHECK(r.seq.output().last_reason == TransitionReason::kStopCommand);
  r.in.z_valid = false;
  r.seq.step(r.in);
  LONGS_EQUAL(kAxisMaskInPlane, r.seq.output().closed_axes);
  CHECK(r.run_until(SequencerState::kIdle, 5000) > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kTouchdown);
}

TEST(Sequencer, FaultLandingEndsLatchedAndNeedsClear) {
  Rig r;
  r.go_ready();
  r.in.fault_reaction = FaultReaction::kLand;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kLanding);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultLanding);
  r.in.z_m = 0.0f;
  CHECK(r.run_until(SequencerState::kFault, 10000) > 0);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultLatched);
  CHECK_FALSE(r.seq.output().amplifier_enable);
  CHECK_FALSE(r.seq.output().homed);
  CHECK(r.seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kRefusedFaultLatched);
  CHECK(r.seq.command(SequencerCommand::kHome, false) == SequencerCommandResult::kRefusedFaultLatched);
  CHECK(r.seq.command(SequencerCommand::kClearFault, true) == SequencerCommandResult::kRefusedFaultActive);
  CHECK(r.seq.output().state == SequencerState::kFault);
  r.in.fault_reaction = FaultReaction::kNone;
  CHECK(r.seq.command(SequencerCommand::kClearFault, false) == SequencerCommandResult::kAccepted);
  CHECK(r.seq.output().state == SequencerState::kIdle);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultCleared);
}

TEST(Sequencer, CurrentsOffFromAnyLevitatedState) {
  Rig r;
  r.go_ready();
  r.in.fault_reaction = FaultReaction::kCurrentsOff;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kFault);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultCurrentsOff);
  CHECK_FALSE(r.seq.output().amplifier_enable);
  LONGS_EQUAL(0, r.seq.output().closed_axes);
  DOUBLES_EQUAL(0.0, r.seq.output().feedforward_fraction, 0.0);
}

TEST(Sequencer, EscalationDuringFaultLanding) {
  Rig r;
  r.go_ready();
  r.in.fault_reaction = FaultReaction::kLand;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kLanding);
  r.in.fault_reaction = FaultReaction::kCurrentsOff;  // then the beams go
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kFault);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultCurrentsOff);
}

TEST(Sequencer, FaultOnRestLatchesWithoutLanding) {
  Rig r;
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kInPlaneLock);
  r.in.fault_reaction = FaultReaction::kLand;
  r.seq.step(r.in);
  CHECK(r.seq.output().state == SequencerState::kFault);
  CHECK(r.seq.output().last_reason == TransitionReason::kFaultLatched);
}

TEST(Sequencer, StopAndCommandRefusals) {
  Rig r;
  CHECK(r.seq.command(SequencerCommand::kLand, false) == SequencerCommandResult::kRefusedNotLevitated);
  CHECK(r.seq.command(SequencerCommand::kClearFault, false) == SequencerCommandResult::kRefusedNotFaulted);
  CHECK(r.seq.command(SequencerCommand::kStop, false) == SequencerCommandResult::kAlreadyThere);
  r.seq.command(SequencerCommand::kLevitate, false);
  r.in.homing_done = true;
  r.seq.step(r.in);
  CHECK(r.seq.command(SequencerCommand::kHome, false) == SequencerCommandResult::kRefusedBusy);
  CHECK(r.seq.command(SequencerCommand::kStop, false) == SequencerCommandResult::kAccepted);
  CHECK(r.seq.output().state == SequencerState::kIdle);
  CHECK(r.seq.output().last_reason == TransitionReason::kStopCommand);
  r.go_ready();
  r.seq.command(SequencerCommand::kLand, false);
  CHECK(r.seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kRefusedBusy);
  CHECK(r.seq.command(SequencerCommand::kLand, false) == SequencerCommandResult::kAlreadyThere);
}

TEST(Sequencer, ConfigValidation) {
  SequencerConfig c;
  CHECK(validate(c, kRate) == SequencerConfigError::kOk);
  CHECK(validate(c, 10.0f) == SequencerConfigError::kBadServoRate);
  SequencerConfig bad = c;
  bad.lift_timeout_s = 0.0f;
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadTimeout);
  bad = c;
  bad.z_settle_time_s = 5.0f;  // longer than its timeout
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadTimeout);
  bad = c;
  bad.lift_ramp_rate_per_s = -1.0f;
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadRampRate);
  bad = c;
  bad.nominal_height_m = 1.5e-3f;  // beyond the 1 mm sanity bound (a stage's own comes from its profile)
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadHeight);
  bad = c;
  bad.tilt_settle_error_rad = 0.0f / 0.0f;
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadThreshold);
  bad = c;
  bad.tilt_reference_rate_rad_per_s = 0.0f;
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadRampRate);
  bad.tilt_reference_rate_rad_per_s = 1.0f;  // 1 rad/s: no levelling ramp
  CHECK(validate(bad, kRate) == SequencerConfigError::kBadRampRate);
}

// The controller forms SequencerInputs::abs_error only in the states
// Sequencer::ReadsFollowingErrors names: every other state's step must not
// read them. A start-up, a landing and a fault landing, with absurd errors
// in a copy at every such tick.
TEST(Sequencer, OnlyTheLockStatesReadTheFollowingErrors) {
  Rig r;
  r.check_unread = true;
  r.go_ready();
  for (int n = 0; n < 100; ++n) r.step();  // Ready
  CHECK(r.seq.command(SequencerCommand::kLand, false) == SequencerCommandResult::kAccepted);
  r.in.z_m = 0.0f;
  CHECK(r.run_until(SequencerState::kIdle, 10000) > 0);
  r.go_ready();
  r.in.fault_reaction = FaultReaction::kLand;
  r.step();
  CHECK(r.seq.output().state == SequencerState::kLanding);
  r.in.z_m = 0.0f;
  CHECK(r.run_until(SequencerState::kFault, 20000) > 0);
  for (int n = 0; n < 10; ++n) r.step();
  CHECK(r.unread_checked > 1000);
  // The lock states do read them: absurd errors keep InPlaneLock from settling.
  Rig q;
  CHECK(q.seq.command(SequencerCommand::kLevitate, false) == SequencerCommandResult::kAccepted);
  q.in.homing_done = true;
  CHECK(q.run_until(SequencerState::kInPlaneLock, 10) > 0);
  q.in.homing_done = false;
  for (float& e : q.in.abs_error) e = 1e30f;
  CHECK(q.run_until(SequencerState::kLift, 1000) < 0);
}
