// The selfstab kernel from the shipped jb2002-selfstab profile.
#include <cmath>
#include <cstring>

#include "maglev/controller/controller.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/stage_profile/apply_profile.hpp"
#include "maglev/stage_profile/selfstab_config.hpp"

// CppUTest last: its new/delete macros must not meet the STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;
namespace sp = maglev::stage_profile;
namespace ss = maglev::selfstab;

namespace {
sp::StageProfile shipped() {
  const auto p = profile::find_profile("jb2002-selfstab", MAGLEV_PROFILE_DIR);
  CHECK_TEXT(p.ok(), p.ok() ? "" : p.errors.front().c_str());
  return p.profile;
}
ss::SelfstabKernelConfig config() {
  ss::SelfstabKernelConfig c{};
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(shipped(), &c) == sp::ProfileError::kOk);
  return c;
}
// PSD codes of a small pose (the first-order sensor model of the profile's
// three PSDs: tangential -sin x + cos y + Rr gamma, vertical z + Rr (sin
// alpha - cos beta)), rounded to counts.
ss::SelfstabSensorSample codes_of(const double pose[6]) {
  const sp::StageProfile p = shipped();
  ss::SelfstabSensorSample s{};
  for (int k = 0; k < 3; ++k) {
    const double Rr = std::hypot(p.sensors[k].x_m, p.sensors[k].y_m);
    const double psi = std::atan2(p.sensors[k].y_m, p.sensors[k].x_m);
    const double t = -std::sin(psi) * pose[0] + std::cos(psi) * pose[1] + Rr * pose[5];
    const double v = pose[2] + Rr * (std::sin(psi) * pose[3] - std::cos(psi) * pose[4]);
    s.psd_code[2 * k] = static_cast<std::int16_t>(std::lround(t / p.sensors[k].resolution));
    s.psd_code[2 * k + 1] = static_cast<std::int16_t>(std::lround(v / p.sensors[k].resolution));
  }
  s.status = ss::kPsdValid;
  return s;
}
// Ticks until the loops are closed (lift-off ramp + settle), at the pose.
void levitate(ss::SelfstabKernel& k, const double pose[6]) {
  CHECK_TRUE(k.lift_off() == ss::SelfstabResult::kOk);
  for (int i = 0; i < 5000 && k.mode() != ss::SelfstabMode::kLevitated; ++i) k.tick(codes_of(pose));
  CHECK_TRUE(k.mode() == ss::SelfstabMode::kLevitated);
}
}  // namespace

TEST_GROUP(SelfstabKernel){};

TEST(SelfstabKernel, TheProfileMakesXAndZActiveAndTheRestPassive) {
  const ss::SelfstabKernelConfig c = config();
  CHECK_TRUE(c.role[ss::kX] == ss::AxisRole::kActive);
  CHECK_TRUE(c.role[ss::kZ] == ss::AxisRole::kActive);
  for (int a : {ss::kY, ss::kAlpha, ss::kBeta, ss::kGamma}) CHECK_TRUE(c.role[a] == ss::AxisRole::kPassive);
  CHECK_EQUAL(1, c.feedback_filter_enabled);
  CHECK_TRUE(c.loop[ss::kZ].feedback_filter.type == kernel::BiquadType::kLowPass);
  DOUBLES_EQUAL(10.0, c.loop[ss::kZ].feedback_filter.frequency_Hz, 0.0);
  DOUBLES_EQUAL(0.70710678, c.loop[ss::kZ].feedback_filter.q, 1e-6);
  LONGS_EQUAL(5, c.loop[ss::kZ].schedule_points);
  LONGS_EQUAL(2048, c.psd_code_limit);  // 2.35 mm / 1.1475 um
  // W: Table 2's nominal currents.
  DOUBLES_EQUAL(0.535, c.nominal_current_A[0], 1e-7);
  DOUBLES_EQUAL(0.4273, c.nominal_current_A[8], 1e-7);
}

TEST(SelfstabKernel, TheOtherKernelAndThisOneRefuseEachOthersFamily) {
  // The paper-000 kernel (the Modbus app's) keeps refusing this profile
  // (its checker stops at the PSDs, which its pose solver does not read,
  // before it reaches the family) and its family.
  CHECK_TRUE(sp::CheckStageProfile(shipped()).error != sp::ProfileError::kOk);
  kernel::KernelConfig kc = kernel::default_kernel_config();
  CHECK_TRUE(sp::MakeKernelConfig(shipped(), &kc).error != sp::ProfileError::kOk);
  CHECK(kernel::same_config(kernel::default_kernel_config(), kc));  // untouched
  const auto cross = profile::find_profile("nk2017-cross", MAGLEV_PROFILE_DIR);
  ss::SelfstabKernelConfig c{};
  c.servo_rate_Hz = 123.0f;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(cross.profile, &c) == sp::ProfileError::kUnsupportedFamily);
  DOUBLES_EQUAL(123.0, c.servo_rate_Hz, 0.0);  // nothing written
}

TEST(SelfstabKernel, ProfilesItCannotRunAreRefusedWithTheReason) {
  ss::SelfstabKernelConfig c{};
  sp::StageProfile p = shipped();
  p.sensor_count = 2;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kUnsupportedSensors);
  p = shipped();
  p.solenoid.force_constant_out_of_plane_N_per_A = 0;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kBadActuatorParameters);
  p = shipped();
  p.axis[3].controller.kind = sp::ControllerKind::kStateFeedback;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kUnsupportedController);
  p = shipped();
  p.axis[3].controller.effort_limit_A = 1.2;  // 0.535 + 1.2 A above the 1.5 A peak
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kLimitsOutsideHardware);
  p = shipped();
  p.startup[0] = sp::StartupStep::kCloseInPlane;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kBadStartup);
  p = shipped();
  p.axis[0].mode = sp::AxisMode::kPassive;
  p.axis[3].mode = sp::AxisMode::kPassive;
  CHECK_TRUE(sp::MakeSelfstabKernelConfig(p, &c) == sp::ProfileError::kNoActiveAxis);
}

TEST(SelfstabKernel, TheKinematicTransformRecoversThePose) {
  ss::SelfstabKernel k;
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  const double pose[6] = {50e-6, -30e-6, 100e-6, 0.2e-3, -0.1e-3, 0.15e-3};
  k.tick(codes_of(pose));
  const ss::SelfstabTelemetry& t = k.telemetry();
  for (int a = 0; a < 3; ++a) DOUBLES_EQUAL(pose[a], t.pose[a], 1.2e-6);      // one count
  for (int a = 3; a < 6; ++a) DOUBLES_EQUAL(pose[a], t.pose[a], 1.2e-5);      // one count over 0.1 m
}

TEST(SelfstabKernel, DockedItCommandsNothingAndLiftOffRampsTheNominalCurrents) {
  ss::SelfstabKernel k;
  const ss::SelfstabKernelConfig c = config();
  CHECK_TRUE(k.configure(c) == ss::SelfstabConfigError::kOk);
  const double dock[6] = {0, 0, -2.5e-3, 0, 0, 0};
  ss::SelfstabCoilCommand o = k.tick(codes_of(dock));
  CHECK_EQUAL(0, o.enable);
  for (int j = 0; j < ss::kCoils; ++j) CHECK_EQUAL(0, o.dac_code[j]);
  CHECK_TRUE(k.lift_off() == ss::SelfstabResult::kOk);
  CHECK_TRUE(k.lift_off() == ss::SelfstabResult::kWrongMode);
  const int half = static_cast<int>(c.liftoff_ramp_s * c.servo_rate_Hz / 2);
  for (int i = 0; i < half; ++i) o = k.tick(codes_of(dock));
  CHECK_EQUAL(1, o.enable);
  for (int j = 0; j < ss::kCoils; ++j) {
    const float i = 0.5f * c.nominal_current_A[j];
    LONGS_EQUAL(std::lround(i / c.dac_A_per_code), o.dac_code[j]);
  }
  CHECK_TRUE(k.mode() == ss::SelfstabMode::kLifting);
  // Commands to the loops wait for them.
  CHECK_TRUE(k.move_to(ss::kZ, 10e-6f) == ss::SelfstabResult::kWrongMode);
}

TEST(SelfstabKernel, BadCommandsAreRefusedWithTheirReasonAndChangeNothing) {
  ss::SelfstabKernel k;
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  k.tick(codes_of(home));
  const float ref_z = k.telemetry().reference[ss::kZ];
  CHECK_TRUE(k.move_to(ss::kY, 10e-6f) == ss::SelfstabResult::kAxisPassive);
  CHECK_TRUE(k.move_to(ss::kGamma, 1e-4f) == ss::SelfstabResult::kAxisPassive);
  CHECK_TRUE(k.move_to(ss::kAlpha, 1e-4f) == ss::SelfstabResult::kAxisPassive);
  CHECK_TRUE(k.move_to(ss::kZ, 2.1e-3f) == ss::SelfstabResult::kOutsideSchedule);  // travel is +-2.2 mm
  CHECK_TRUE(k.move_to(ss::kZ, -2.05e-3f) == ss::SelfstabResult::kOutsideSchedule);
  CHECK_TRUE(k.move_to(ss::kX, 3e-3f) == ss::SelfstabResult::kOutsideTravel);
  CHECK_TRUE(k.move_to(ss::kZ, NAN) == ss::SelfstabResult::kBadValue);
  CHECK_TRUE(k.move_to(6, 0.0f) == ss::SelfstabResult::kBadAxis);
  CHECK_TRUE(k.move_to(-1, 0.0f) == ss::SelfstabResult::kBadAxis);
  k.tick(codes_of(home));
  DOUBLES_EQUAL(ref_z, k.telemetry().reference[ss::kZ], 0.0);
  STRCMP_CONTAINS("passive", ss::to_string(ss::SelfstabResult::kAxisPassive));
  STRCMP_CONTAINS("schedule", ss::to_string(ss::SelfstabResult::kOutsideSchedule));
  // Inside: accepted, the reference steps at once.
  CHECK_TRUE(k.move_to(ss::kZ, 2e-3f) == ss::SelfstabResult::kOk);
  k.tick(codes_of(home));
  DOUBLES_EQUAL(2e-3, k.telemetry().reference[ss::kZ], 1e-9);
  // A configuration while levitated is refused.
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kNotDocked);
}

TEST(SelfstabKernel, ThePassiveAxesGetNoEffort) {
  ss::SelfstabKernel k;
  const ss::SelfstabKernelConfig c = config();
  CHECK_TRUE(k.configure(c) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  // y, alpha, beta, gamma far off: no current changes but the W currents
  // (x and z read 0, so their loops ask for nothing either).
  const double off[6] = {0, 200e-6, 0, 1e-3, -1e-3, 2e-3};
  for (int i = 0; i < 200; ++i) k.tick(codes_of(off));
  const ss::SelfstabTelemetry& t = k.telemetry();
  for (int a : {ss::kY, ss::kAlpha, ss::kBeta, ss::kGamma}) DOUBLES_EQUAL(0.0, t.effort_A[a], 0.0);
  for (int j = 0; j < ss::kCoils; ++j) {
    double expect = static_cast<double>(c.nominal_current_A[j]);
    for (int a : {ss::kX, ss::kZ}) expect += static_cast<double>(c.coil_per_effort[j][a] * t.effort_A[a]);
    DOUBLES_EQUAL(expect, t.current_A[j], 1e-6);
  }
  // The pose measured x and z at (nearly) 0 whatever the other axes do.
  DOUBLES_EQUAL(0.0, t.pose[ss::kX], 1.2e-6);
  DOUBLES_EQUAL(0.0, t.pose[ss::kZ], 1.2e-6);
}

TEST(SelfstabKernel, TheZGainsFollowTheScheduleAtTheMeasuredHeight) {
  ss::SelfstabKernel k;
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  const double high[6] = {0, 0, 1.5e-3, 0, 0, 0};
  for (int i = 0; i < 1000; ++i) k.tick(codes_of(high));  // the 10 Hz filter settles
  // Between the 1 mm and 2 mm points of the table, linearly, at the
  // measured height (1.5 mm: 1307 counts, 1.49974 mm).
  const ss::SelfstabLoopConfig& l = k.config().loop[ss::kZ];
  DOUBLES_EQUAL(1e-3, l.schedule_at[3], 1e-9);
  const double y = static_cast<double>(k.telemetry().feedback[ss::kZ]);
  DOUBLES_EQUAL(1307 * 1.1474609375e-6, y, 2e-8);  // R in float32
  const double w = (y - 1e-3) / 1e-3;
  auto lerp = [&](const float* s) {
    return static_cast<double>(s[3]) + w * static_cast<double>(s[4] - s[3]);
  };
  DOUBLES_EQUAL(lerp(l.kp_scale), k.telemetry().kp_scale[ss::kZ], 1e-5);
  DOUBLES_EQUAL(lerp(l.kd_scale), k.telemetry().kd_scale[ss::kZ], 1e-5);
  CHECK_TRUE(k.telemetry().kp_scale[ss::kZ] < 0.93f && k.telemetry().kp_scale[ss::kZ] > 0.84f);
  DOUBLES_EQUAL(1.0, k.telemetry().kp_scale[ss::kX], 0.0);  // x has no schedule
}

TEST(SelfstabKernel, TheFeedbackFilterIsTheTenHertzButterworthAndSwitchable) {
  ss::SelfstabKernel k;
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  // A 100 um step in the measured z: filtered, the loop sees it slowly
  // (2nd-order 10 Hz: ~ 4 % after 5 ms), unfiltered at once.
  const double up[6] = {0, 0, 100e-6, 0, 0, 0};
  for (int i = 0; i < 5; ++i) k.tick(codes_of(up));
  CHECK_TRUE(k.telemetry().feedback[ss::kZ] < 10e-6f);
  for (int i = 0; i < 300; ++i) k.tick(codes_of(up));
  DOUBLES_EQUAL(k.telemetry().pose[ss::kZ], k.telemetry().feedback[ss::kZ], 0.02e-6);
  CHECK_TRUE(k.set_feedback_filter(false) == ss::SelfstabResult::kOk);
  k.tick(codes_of(home));
  DOUBLES_EQUAL(0.0, k.telemetry().feedback[ss::kZ], 0.0);
}

TEST(SelfstabKernel, LandingRampsTheCurrentsToZeroAndDocks) {
  ss::SelfstabKernel k;
  const ss::SelfstabKernelConfig c = config();
  CHECK_TRUE(k.configure(c) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  CHECK_TRUE(k.land() == ss::SelfstabResult::kOk);
  CHECK_TRUE(k.move_to(ss::kZ, 0.0f) == ss::SelfstabResult::kWrongMode);
  ss::SelfstabCoilCommand o{};
  const int n = static_cast<int>(c.land_ramp_s * c.servo_rate_Hz);
  for (int i = 0; i < n / 2; ++i) o = k.tick(codes_of(home));
  CHECK_EQUAL(1, o.enable);
  CHECK_TRUE(o.dac_code[0] > 0 && o.dac_code[0] < std::lround(0.6f * c.nominal_current_A[0] / c.dac_A_per_code));
  for (int i = 0; i < n; ++i) o = k.tick(codes_of(home));
  CHECK_TRUE(k.mode() == ss::SelfstabMode::kDocked);
  CHECK_EQUAL(0, o.enable);
}

TEST(SelfstabKernel, LosingTheSensorsWhileLevitatedFaultsWithTheCurrentsOff) {
  ss::SelfstabKernel k;
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  const double home[6] = {};
  levitate(k, home);
  ss::SelfstabSensorSample s = codes_of(home);
  s.status = 0;
  const ss::SelfstabCoilCommand o = k.tick(s);
  CHECK_TRUE(k.mode() == ss::SelfstabMode::kFault);
  CHECK_EQUAL(0, o.enable);
  for (int j = 0; j < ss::kCoils; ++j) CHECK_EQUAL(0, o.dac_code[j]);
  CHECK_TRUE(k.lift_off() == ss::SelfstabResult::kWrongMode);
  // The way out: a configuration (the rotor is on the dock), then lift-off.
  CHECK_TRUE(k.configure(config()) == ss::SelfstabConfigError::kOk);
  CHECK_TRUE(k.mode() == ss::SelfstabMode::kDocked);
  // A spot off the PSD (the A/D at its end) as well.
  ss::SelfstabKernel k2;
  CHECK_TRUE(k2.configure(config()) == ss::SelfstabConfigError::kOk);
  levitate(k2, home);
  s = codes_of(home);
  s.psd_code[1] = 2048;
  k2.tick(s);
  CHECK_TRUE(k2.mode() == ss::SelfstabMode::kFault);
}
