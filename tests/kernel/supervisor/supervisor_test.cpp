// Every supervisor fault path, the reaction choice and first-fault latching.
#include "maglev/supervisor/supervisor.hpp"

#include <cmath>
#include <cstdint>
#include <initializer_list>

#include "maglev/numeric/int64_double.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::kernel;

namespace {

constexpr float kRate = 2500.0f;

struct Rig {
  Supervisor sup;
  io::SensorSample sample{};
  SupervisorInputs in{};
  float coil_current_cmd_A[io::kCoils] = {};  // in.coil_current_cmd_A points here
  // The pose and the following errors in SI, as a test states them; tick()
  // hands them over as the controller does, in pm / prad (nearest).
  double pose_m[kSequencedAxes] = {};
  double error_m[kSequencedAxes] = {};
  std::int64_t pose_pico[kSequencedAxes] = {};
  std::int64_t reference_pico[kSequencedAxes] = {};
  Rig() {
    SupervisorConfig c;
    CHECK(validate(c, kRate) == SupervisorConfigError::kOk);
    sup.configure(c, kRate);
    sup.reset();
    in.sample = &sample;
    in.coil_current_cmd_A = coil_current_cmd_A;
    in.positions_valid = true;
    in.envelope_active = true;
    in.closed_axes = kAxisMaskAll;
    in.pose_pico = pose_pico;
    in.reference_pico = reference_pico;
    pose_m[3] = 30e-6;
  }
  bool live = true;  // one LSB of Hall noise per tick, as live sensors have
  const SupervisorStatus& tick() {
    for (int a = 0; a < kSequencedAxes; ++a) {
      pose_pico[a] = std::llround(pose_m[a] * 1e12);
      reference_pico[a] = pose_pico[a] + std::llround(error_m[a] * 1e12);
    }
    return tick_pico();
  }
  // One tick on pose_pico / reference_pico as they are.
  const SupervisorStatus& tick_pico() {
    ++in.tick;
    if (live) sample.hall_adc[0] = static_cast<std::int16_t>(in.tick & 1u);
    return sup.step(in);
  }
};

}  // namespace

TEST_GROUP(Supervisor){};

TEST(Supervisor, NominalTicksRaiseNothing) {
  Rig r;
  for (int n = 0; n < 1000; ++n) {
    r.sample.interferometer_counts[0] += 100;  // 62 nm per tick = 0.15 m/s
    const auto& s = r.tick();
    CHECK(s.active == FaultCode::kNone);
  }
  CHECK(r.sup.status().reaction == FaultReaction::kNone);
  CHECK(r.sup.status().first_fault.code == FaultCode::kNone);
}

TEST(Supervisor, TravelWindowLatchesWithAxisAndValueAndLands) {
  Rig r;
  r.tick();
  r.pose_m[0] = 0.0295;  // window: 28 mm travel + 1 mm
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kTravelX);
  LONGS_EQUAL(2, s.first_fault.tick);
  LONGS_EQUAL(0, s.first_fault.axis);
  DOUBLES_EQUAL(0.0295, s.first_fault.value, 1e-7);
  CHECK(s.reaction == FaultReaction::kLand);
  // A later, different fault does not overwrite the first-fault record.
  r.pose_m[1] = -0.02;
  r.tick();
  CHECK(r.sup.status().first_fault.code == FaultCode::kTravelX);
  CHECK(r.sup.status().active == FaultCode::kTravelX);
  LONGS_EQUAL(2, r.sup.status().fault_count);
}

TEST(Supervisor, TravelYAndThetaZ) {
  Rig r;
  r.pose_m[1] = 0.019;  // window: 17.5 mm travel + 1 mm
  CHECK(r.tick().first_fault.code == FaultCode::kTravelY);
  Rig r2;
  r2.pose_m[2] = -6e-3;
  CHECK(r2.tick().first_fault.code == FaultCode::kTravelThetaZ);
  // Not homed: positions mean nothing, the travel check is off.
  Rig r3;
  r3.in.positions_valid = false;
  r3.pose_m[0] = 1.0;
  CHECK(r3.tick().active == FaultCode::kNone);
}

TEST(Supervisor, ZAndTiltEnvelopeOnlyWhileZClosed) {
  Rig r;
  r.pose_m[3] = 45e-6;
  r.in.envelope_active = false;
  CHECK(r.tick().active == FaultCode::kNone);
  r.in.envelope_active = true;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kZEnvelope);
  LONGS_EQUAL(3, s.first_fault.axis);
  Rig t;
  t.pose_m[5] = -400e-6;
  const auto& st = t.tick();
  CHECK(st.first_fault.code == FaultCode::kTiltEnvelope);
  LONGS_EQUAL(5, st.first_fault.axis);
  CHECK(st.reaction == FaultReaction::kLand);
}

TEST(Supervisor, FollowingErrorOnlyOnClosedAxes) {
  Rig r;
  r.in.closed_axes = kAxisMaskInPlane;
  r.error_m[3] = 1e-3;  // z open: ignored
  CHECK(r.tick().active == FaultCode::kNone);
  r.error_m[1] = -250e-6;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kFollowingError);
  LONGS_EQUAL(1, s.first_fault.axis);
  DOUBLES_EQUAL(-250e-6, s.first_fault.value, 1e-10);
}

// The checks compare pm / prad with integer thresholds (PicoFirstAbove /
// PicoFirstAtOrAbove). Held here to the float comparison they replace, at
// the exact boundary found by a plain scan (not by the bisection): the last
// value inside each limit does not trip, the first one beyond it does.
TEST(Supervisor, IntegerLimitsTripAtTheFirstPicoWhoseFloatValueIsBeyondTheLimit) {
  const SupervisorConfig c;
  using maglev::numeric::PicoToSi;
  // First v from start upwards with beyond(v) (a linear scan: the float
  // ulp at these limits is at most ~4e3 pm).
  auto first = [](std::int64_t start, auto beyond) {
    std::int64_t v = start;
    while (!beyond(v)) ++v;
    return v;
  };
  struct Case {
    int axis;
    bool upper;  // the max side (v >= T trips) or the min side (v < T trips)
    float limit;
  };
  const Case cases[] = {{0, true, c.x_max_m},  {0, false, c.x_min_m}, {1, true, c.y_max_m},
                        {1, false, c.y_min_m}, {2, true, c.theta_z_limit_rad}, {2, false, -c.theta_z_limit_rad},
                        {3, true, c.z_max_m},  {3, false, c.z_min_m}, {4, true, c.tilt_limit_rad},
                        {5, false, -c.tilt_limit_rad}};
  for (const Case& k : cases) {
    const auto start = std::llround(static_cast<double>(k.limit) * 1e12) - 10000;
    // Upper: the first v with f(v) > max trips, v - 1 does not. Lower: the
    // first v with f(v) >= min does not trip, v - 1 does.
    const std::int64_t edge = k.upper ? first(start, [&](std::int64_t v) { return PicoToSi(v) > k.limit; })
                                      : first(start, [&](std::int64_t v) { return PicoToSi(v) >= k.limit; });
    for (std::int64_t v : {edge - 1, edge}) {
      Rig r;
      r.tick();
      for (int a = 0; a < kSequencedAxes; ++a) r.reference_pico[a] = r.pose_pico[a];
      r.pose_pico[k.axis] = v;
      r.reference_pico[k.axis] = v;
      const bool trips = r.tick_pico().active != FaultCode::kNone;
      CHECK_EQUAL(k.upper ? v == edge : v == edge - 1, trips);
    }
  }
  // The following error, both signs, every axis.
  for (int axis = 0; axis < kSequencedAxes; ++axis) {
    const float lim = c.following_error_limit[axis];
    const std::int64_t edge = first(std::llround(static_cast<double>(lim) * 1e12) - 10000,
                                    [&](std::int64_t v) { return PicoToSi(v) > lim; });
    for (std::int64_t e : {edge - 1, edge, -(edge - 1), -edge}) {
      Rig r;
      r.tick();
      for (int a = 0; a < kSequencedAxes; ++a) r.reference_pico[a] = r.pose_pico[a];
      r.reference_pico[axis] = r.pose_pico[axis] + e;
      const auto& s = r.tick_pico();
      CHECK_EQUAL(e == edge || e == -edge, s.active == FaultCode::kFollowingError);
      if (s.active == FaultCode::kFollowingError) {
        LONGS_EQUAL(axis, s.first_fault.axis);
        CHECK_EQUAL(PicoToSi(e), s.first_fault.value);
      }
    }
  }
}

TEST(Supervisor, RmsCurrentFollowsTheThermalTimeConstant) {
  Rig r;
  // 3.5 A dc on coil 4: filtered i^2 crosses 9 A^2 when 1 - exp(-t/tau) = 9/12.25,
  // t = -10 s * ln(1 - 0.7347) = 13.27 s = 33170 ticks.
  r.coil_current_cmd_A[4] = 3.5f;
  r.in.coil_current_measured_A[4] = 3.5f;  // the amplifier follows
  int n = 0;
  while (r.tick().active == FaultCode::kNone && n < 100000) ++n;
  DOUBLES_EQUAL(33170.0, n, 60.0);
  CHECK(r.sup.status().first_fault.code == FaultCode::kRmsCurrent);
  LONGS_EQUAL(4, r.sup.status().first_fault.axis);
  CHECK(r.sup.status().reaction == FaultReaction::kLand);
  DOUBLES_EQUAL(3.0, r.sup.rms_current_A(4), 0.01);
}

TEST(Supervisor, PeakCurrentCommandedLandsMeasuredCutsCurrents) {
  Rig r;
  r.coil_current_cmd_A[2] = -4.2f;
  CHECK(r.tick().first_fault.code == FaultCode::kPeakCurrentCommanded);
  CHECK(r.sup.status().reaction == FaultReaction::kLand);
  Rig m;
  m.in.coil_current_measured_A[7] = 4.6f;  // beyond 4.0 + 0.5 margin
  const auto& s = m.tick();
  CHECK(s.first_fault.code == FaultCode::kPeakCurrentMeasured);
  LONGS_EQUAL(7, s.first_fault.axis);
  CHECK(s.reaction == FaultReaction::kCurrentsOff);
  Rig ok;
  ok.in.coil_current_measured_A[7] = 4.4f;  // inside the margin
  CHECK(ok.tick().active == FaultCode::kNone);
}

// The coil checks compare maxima over the coils on a normal tick (one
// compare per check, not per coil); the fault still names the first coil in
// coil order, with its own value, and a NaN current trips nothing (as the
// per-coil compare it replaced: NaN > limit is false).
TEST(Supervisor, CoilChecksNameTheFirstTrippingCoilAndIgnoreNaN) {
  Rig r;
  r.coil_current_cmd_A[6] = 4.3f;
  r.coil_current_cmd_A[3] = -4.1f;
  r.coil_current_cmd_A[5] = 4.9f;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kPeakCurrentCommanded);
  LONGS_EQUAL(3, s.first_fault.axis);
  DOUBLES_EQUAL(-4.1, s.first_fault.value, 1e-6);
  Rig m;
  m.in.coil_current_measured_A[1] = -4.8f;
  m.coil_current_cmd_A[1] = -4.8f;
  m.in.coil_current_measured_A[0] = 4.7f;
  m.coil_current_cmd_A[0] = 4.7f;
  const auto& sm = m.tick();
  CHECK(sm.first_fault.code == FaultCode::kPeakCurrentMeasured);  // before the commanded one
  LONGS_EQUAL(0, sm.first_fault.axis);
  DOUBLES_EQUAL(4.7, sm.first_fault.value, 1e-6);
  Rig n;
  n.coil_current_cmd_A[2] = __builtin_nanf("");
  n.in.coil_current_measured_A[2] = __builtin_nanf("");
  n.in.coil_current_measured_A[4] = 4.4f;  // inside the margin
  n.coil_current_cmd_A[4] = 4.0f;         // at the peak, not beyond
  CHECK(n.tick().active == FaultCode::kNone);
  n.coil_current_cmd_A[7] = 4.2f;  // a real one beside the NaN still trips
  const auto& sn = n.tick();
  CHECK(sn.active == FaultCode::kPeakCurrentCommanded);
  LONGS_EQUAL(7, sn.first_fault.axis);
}

TEST(Supervisor, TickOverrunAfterConsecutiveLimit) {
  Rig r;
  r.in.tick_overrun = true;
  CHECK(r.tick().active == FaultCode::kNone);
  CHECK(r.tick().active == FaultCode::kNone);
  r.in.tick_overrun = false;  // a good tick resets the run
  r.tick();
  r.in.tick_overrun = true;
  r.tick();
  r.tick();
  CHECK(r.sup.status().active == FaultCode::kNone);
  CHECK(r.tick().first_fault.code == FaultCode::kTickOverrun);
  CHECK(r.sup.status().reaction == FaultReaction::kLand);
}

TEST(Supervisor, BeamLossCutsCurrents) {
  Rig r;
  r.sample.status_flags = io::kBeamLoss2;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kBeamLoss);
  LONGS_EQUAL(2, s.first_fault.axis);
  CHECK_FALSE(s.in_plane_sensors_valid);
  CHECK(s.reaction == FaultReaction::kCurrentsOff);
}

TEST(Supervisor, CounterJumpIsWrapSafeAndCutsCurrents) {
  Rig r;
  r.sample.interferometer_counts[1] = 0xFFFFFF00u;
  r.tick();
  r.sample.interferometer_counts[1] = 0x00000100u;  // +512 counts through the wrap: fine
  CHECK(r.tick().active == FaultCode::kNone);
  // 0.5 m/s / 2500 Hz / 0.618 nm = 323 624 counts per tick is the limit.
  r.sample.interferometer_counts[1] += 400000u;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kCounterJump);
  LONGS_EQUAL(1, s.first_fault.axis);
  DOUBLES_EQUAL(400000 * 0.618e-9, s.first_fault.value, 1e-6);
  CHECK(s.reaction == FaultReaction::kCurrentsOff);
}

TEST(Supervisor, StaleFramesAfterConsecutiveLimit) {
  Rig r;
  r.sample.status_flags = io::kStaleFrame;
  CHECK(r.tick().active == FaultCode::kNone);
  CHECK(r.tick().active == FaultCode::kNone);
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kStaleFrames);
  DOUBLES_EQUAL(3.0, s.first_fault.value, 0.0);
  CHECK(s.reaction == FaultReaction::kCurrentsOff);
}

// The supervisor takes sensors_to_pose's verdict on each reading (its status
// bit or its ADC code at a rail: SensorsToPose.ValidityFlags tests both) and
// records the code.
TEST(Supervisor, DisplacementOutOfRangeLandsWithoutZ) {
  Rig r;
  r.sample.displacement_adc[1] = 32767;  // at the rail
  r.in.displacement_bad = 2;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kDisplacementOutOfRange);
  LONGS_EQUAL(1, s.first_fault.axis);
  DOUBLES_EQUAL(32767.0, s.first_fault.value, 0.0);
  CHECK_FALSE(s.z_sensors_valid);
  CHECK(s.in_plane_sensors_valid);
  CHECK(s.reaction == FaultReaction::kLand);
  Rig b;
  b.in.displacement_bad = 1;
  CHECK(b.tick().first_fault.code == FaultCode::kDisplacementOutOfRange);
  // Bits beyond the three sensors are not sensors.
  Rig c;
  c.in.displacement_bad = 0xF8;
  CHECK(c.tick().active == FaultCode::kNone);
}

TEST(Supervisor, AdcFaultAndCurrentMonitorRail) {
  Rig r;
  r.sample.status_flags = io::kAdcFault;
  CHECK(r.tick().first_fault.code == FaultCode::kAdcFault);
  CHECK(r.sup.status().reaction == FaultReaction::kLand);
  Rig m;
  m.sample.coil_current_adc[5] = -32768;
  const auto& s = m.tick();
  CHECK(s.first_fault.code == FaultCode::kCurrentMonitorOutOfRange);
  LONGS_EQUAL(5, s.first_fault.axis);
}

TEST(Supervisor, SensorCauseOutranksItsSymptoms) {
  Rig r;
  r.sample.status_flags = io::kBeamLoss0;
  r.error_m[0] = 1e-3;  // a lost beam also looks like a following error
  CHECK(r.tick().first_fault.code == FaultCode::kBeamLoss);
}

TEST(Supervisor, LandingEscalatesToCurrentsOffNeverBack) {
  Rig r;
  r.pose_m[0] = 0.03;
  r.tick();
  CHECK(r.sup.status().reaction == FaultReaction::kLand);
  r.sample.status_flags = io::kBeamLoss0;
  r.tick();
  CHECK(r.sup.status().reaction == FaultReaction::kCurrentsOff);
  CHECK(r.sup.status().first_fault.code == FaultCode::kTravelX);
  r.sample.status_flags = 0;
  r.tick();
  CHECK(r.sup.status().reaction == FaultReaction::kCurrentsOff);
}

TEST(Supervisor, ClearOnlyWhenTheCauseIsGone) {
  Rig r;
  r.pose_m[0] = 0.03;
  r.tick();
  CHECK_FALSE(r.sup.clear_fault());
  CHECK(r.sup.status().first_fault.code == FaultCode::kTravelX);
  r.pose_m[0] = 0.0;
  r.tick();
  CHECK(r.sup.cause_present() == false);
  CHECK(r.sup.clear_fault());
  CHECK(r.sup.status().first_fault.code == FaultCode::kNone);
  CHECK(r.sup.status().reaction == FaultReaction::kNone);
}

TEST(Supervisor, ConfigValidation) {
  SupervisorConfig c;
  CHECK(validate(c, kRate) == SupervisorConfigError::kOk);
  SupervisorConfig b = c;
  b.x_min_m = 0.03f;
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadTravel);
  b = c;
  b.z_max_m = 1.5e-3f;  // beyond the 1 mm sanity bound (a stage's own comes from its profile)
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadEnvelope);
  b = c;
  b.following_error_limit[4] = -1.0f;
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadFollowingError);
  b = c;
  b.rms_current_A = 4.5f;  // above peak
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadCurrentLimit);
  b = c;
  b.thermal_time_constant_s = 0.0f;
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadThermal);
  b = c;
  b.interferometer_lsb_m = 0.0f;
  CHECK(validate(b, kRate) == SupervisorConfigError::kBadPlausibility);
}

// Issue 17: the current limit acting without pause is a fault at once after
// max_saturated_ticks (50 ms): a stiff-gain attack once let z sag for 8 s
// with the status Ready. A gap in the saturation restarts the count.
TEST(Supervisor, PersistentCurrentSaturationIsAFault) {
  Rig r;
  r.in.current_limited = true;
  for (int n = 0; n < 124; ++n) CHECK(r.tick().active == FaultCode::kNone);
  r.in.current_limited = false;
  CHECK(r.tick().active == FaultCode::kNone);
  r.in.current_limited = true;
  for (int n = 0; n < 124; ++n) CHECK(r.tick().active == FaultCode::kNone);
  const SupervisorStatus& s = r.tick();
  CHECK(s.active == FaultCode::kCurrentSaturation);
  CHECK(s.first_fault.code == FaultCode::kCurrentSaturation);
  CHECK(s.reaction == FaultReaction::kLand);
  STRCMP_EQUAL("CurrentSaturation", to_string(FaultCode::kCurrentSaturation));
}

TEST(Supervisor, AnAmplifierThatDoesNotFollowItsCommandCutsTheCurrents) {
  // Coil 2 shorted to its rail: 4 A measured while 0.5 A is commanded. The
  // mismatch must persist current_mismatch_ticks (10) before it trips (the
  // monitor is held between frames), and the reaction is currents off: an
  // actuator that does not follow cannot land the stage.
  Rig r;
  r.coil_current_cmd_A[2] = 0.5f;
  r.in.coil_current_measured_A[2] = 4.0f;
  int n = 1;
  while (r.tick().active == FaultCode::kNone && n < 100) ++n;
  LONGS_EQUAL(10, n);
  CHECK(r.sup.status().first_fault.code == FaultCode::kCurrentMismatch);
  LONGS_EQUAL(2, r.sup.status().first_fault.axis);
  CHECK(r.sup.status().reaction == FaultReaction::kCurrentsOff);
  // A brief disagreement (a step the amplifier is still following) does not trip.
  Rig q;
  q.coil_current_cmd_A[5] = 2.0f;
  q.in.coil_current_measured_A[5] = 0.0f;
  for (int k = 0; k < 9; ++k) CHECK(q.tick().active == FaultCode::kNone);
  q.in.coil_current_measured_A[5] = 1.9f;
  for (int k = 0; k < 50; ++k) CHECK(q.tick().active == FaultCode::kNone);
}

// The mismatch runs are counted per coil only on ticks where the largest
// |measured - commanded| is beyond the limit or a run is going: each coil
// still keeps its own run. Coil 3 is off for 7 ticks and recovers (its run
// restarts from zero), coil 6 goes off on tick 5 and trips on its own 10th
// tick, and coil 1's NaN monitor beside them is off on no tick.
TEST(Supervisor, MismatchRunsAreCountedPerCoilAndANaNIsNeverOff) {
  Rig r;
  r.in.coil_current_measured_A[1] = __builtin_nanf("");
  r.coil_current_cmd_A[3] = 1.0f;
  r.in.coil_current_measured_A[3] = -1.0f;  // 2 A off
  int n = 1;
  for (; n <= 20; ++n) {
    if (n == 5) r.in.coil_current_measured_A[6] = 1.6f;   // 1.6 A off its 0 A command
    if (n == 8) r.in.coil_current_measured_A[3] = 0.9f;   // coil 3 back after 7 ticks
    if (n == 10) r.in.coil_current_measured_A[3] = -1.0f; // and off again: a new run
    if (r.tick().active != FaultCode::kNone) break;
  }
  LONGS_EQUAL(14, n);  // coil 6's 10th tick off (5..14); coil 3's new run is at 5
  CHECK(r.sup.status().first_fault.code == FaultCode::kCurrentMismatch);
  LONGS_EQUAL(6, r.sup.status().first_fault.axis);
  DOUBLES_EQUAL(1.6, r.sup.status().first_fault.value, 1e-6);
  // With only the NaN coil, nothing is off however long it lasts.
  Rig q;
  q.in.coil_current_measured_A[1] = __builtin_nanf("");
  q.coil_current_cmd_A[1] = 2.0f;
  for (int k = 0; k < 40; ++k) CHECK(q.tick().active == FaultCode::kNone);
}

TEST(Supervisor, AFrozenSampleWhileALoopIsClosedCutsTheCurrents) {
  // A sensor node that freezes without its transport flagging the repeat
  // (campaign seed 1, run 1747): everything, the current monitor included,
  // reads the same bits. 10 identical ticks pass; the 11th is a fault.
  Rig r;
  r.tick();
  r.live = false;
  for (int n = 0; n < 10; ++n) CHECK(r.tick().active == FaultCode::kNone);
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kFrozenSample);
  DOUBLES_EQUAL(11.0, s.first_fault.value, 0.0);
  CHECK(s.reaction == FaultReaction::kCurrentsOff);
  CHECK(!s.in_plane_sensors_valid);
}

TEST(Supervisor, AStillSampleWithNoLoopClosedIsNoFault) {
  // A landed stage's sensors may sit still; the check arms with the loops.
  Rig r;
  r.live = false;
  r.in.closed_axes = 0;
  for (int n = 0; n < 100; ++n) CHECK(r.tick().active == FaultCode::kNone);
  r.in.closed_axes = kAxisMaskAll;
  for (int n = 0; n < 10; ++n) CHECK(r.tick().active == FaultCode::kNone);
  CHECK(r.tick().active == FaultCode::kFrozenSample);
}

TEST(Supervisor, OneChangedBitAnywhereResetsTheFrozenCount) {
  Rig r;
  r.live = false;
  for (int n = 0; n < 200; ++n) {
    if (n % 10 == 0) r.sample.coil_current_adc[7] = static_cast<std::int16_t>(n);
    CHECK(r.tick().active == FaultCode::kNone);
  }
}

TEST(Supervisor, TheFrozenSampleCheckCanBeSwitchedOff) {
  Rig r;
  SupervisorConfig c;
  c.max_identical_samples = 0;
  r.sup.configure(c, kRate);
  r.live = false;
  for (int n = 0; n < 100; ++n) CHECK(r.tick().active == FaultCode::kNone);
}

TEST(Supervisor, ACounterGlitchThatSensorsToPoseRepairedLatchesAndLands) {
  Rig r;
  for (int n = 0; n < 5; ++n) CHECK(r.tick().active == FaultCode::kNone);
  // sensors_to_pose replaced beam 1's step (a -22 um jump, campaign seed 1,
  // run 5693): the pose is still valid, so the stage lands on its in-plane
  // loops rather than dropping with the currents off.
  r.in.beam_glitch = 1u << 1;
  r.in.beam_glitch_m[1] = -22.2e-6f;
  const auto& s = r.tick();
  CHECK(s.first_fault.code == FaultCode::kCounterGlitch);
  LONGS_EQUAL(1, s.first_fault.axis);
  DOUBLES_EQUAL(-22.2e-6, s.first_fault.value, 1e-9);
  CHECK(s.reaction == FaultReaction::kLand);
  CHECK(s.in_plane_sensors_valid);
  STRCMP_EQUAL("CounterGlitch", to_string(FaultCode::kCounterGlitch));
  LONGS_EQUAL(21, static_cast<int>(FaultCode::kCounterGlitch));
  // The glitch is one tick: the cause is gone on the next, and the latch can be cleared.
  r.in.beam_glitch = 0;
  CHECK(r.tick().active == FaultCode::kNone);
  CHECK(r.sup.clear_fault());
  // A jump beyond the plausible speed in the same tick is the more fundamental
  // cause: CounterJump first, and the in-plane sensors are gone (currents off).
  Rig j;
  j.tick();
  j.sample.interferometer_counts[1] += 300000;  // 185 um in one tick
  j.in.beam_glitch = 1u << 1;
  const auto& sj = j.tick();
  CHECK(sj.first_fault.code == FaultCode::kCounterJump);
  CHECK(sj.reaction == FaultReaction::kCurrentsOff);
}
