// PmlsmController: states, refusals, supervision, and the command never
// beyond the amplifiers, driven against the pmlsm_plant physics.
#include <cmath>
#include <memory>

#include "maglev/control_design/pmlsm_kernel_config.hpp"
#include "maglev/pmlsm_plant/plant.hpp"
#include "maglev/pmlsm_stage/pmlsm_controller.hpp"
#include "maglev/profile/profile_text.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

namespace cd = maglev::control_design;
namespace ps = maglev::pmlsm_stage;
namespace pp = maglev::pmlsm_plant;
using maglev::kernel::CommandResult;
using maglev::kernel::FaultCode;

namespace {

// Plant + kernel in lockstep, with a hook that may corrupt the sample.
struct Loop {
  cd::PmlsmStage stage;
  cd::PmlsmDesign design;
  std::unique_ptr<pp::Plant> plant;
  ps::PmlsmController ctl;
  ps::ActuatorCommand last{};
  double peak_A = 0.0;
  std::int32_t count_offset[5] = {};
  std::uint16_t flags = 0;

  bool Init() {
    const auto parsed = maglev::profile::find_profile("fmp2009-pmlsm", MAGLEV_PROFILE_DIR);
    std::string why;
    if (!parsed.ok() || !cd::PmlsmStageFromProfile(parsed.profile, &stage, &why) ||
        !cd::BuildPmlsmKernelConfig(parsed.profile, &design, &why)) {
      return false;
    }
    plant = std::make_unique<pp::Plant>(stage.stage, stage.amplifier, stage.encoder);
    pp::State x0{};
    x0[0] = stage.stage.gap_max_m;
    plant->Reset(x0);
    return ctl.apply_config(design.config) == ps::PmlsmConfigError::kOk;
  }
  void Tick() {
    const auto c = plant->EncoderCounts();
    ps::SensorSample s{};
    for (int a = 0; a < 5; ++a) s.encoder_counts[a] = c[static_cast<std::size_t>(a)] + count_offset[a];
    s.status_flags = flags;
    last = ctl.step(s);
    std::array<pp::PhaseCurrents, 4> ph{};
    if (last.amplifier_enable) {
      const double k = static_cast<double>(design.config.amps_per_dac_code);
      for (std::size_t m = 0; m < 4; ++m) {
        const double ia = last.dac_code[2 * m] * k, ib = last.dac_code[2 * m + 1] * k;
        ph[m].abc_A = {ia, ib, -(ia + ib)};
        for (double i : ph[m].abc_A) peak_A = std::fmax(peak_A, std::fabs(i));
      }
    }
    plant->StepPhases(ph, 1e-3);
  }
  void Run(int ticks) {
    for (int i = 0; i < ticks; ++i) Tick();
  }
  bool Levitate() {
    Tick();
    ps::MotionCommand m;
    m.type = ps::MotionType::kLevitate;
    if (ctl.command(m) != CommandResult::kAccepted) return false;
    for (int i = 0; i < 10000 && ctl.status().state != ps::StageState::kReady; ++i) Tick();
    Run(3000);  // the internal models' slow poles (~2.6 rad/s) settle
    return ctl.status().state == ps::StageState::kReady;
  }
  CommandResult Step(ps::Axis a, float d) {
    ps::MotionCommand m;
    m.type = ps::MotionType::kStep;
    m.axis = a;
    m.delta = d;
    return ctl.command(m);
  }
};

}  // namespace

TEST_GROUP(PmlsmController) {
  Loop loop;
  void setup() override { CHECK_TRUE(loop.Init()); }
};

TEST(PmlsmController, LandedUntilToldAndLiftsOffToTheNominalGap) {
  loop.Run(100);
  CHECK_TRUE(!loop.last.amplifier_enable);
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kLanded);
  DOUBLES_EQUAL(31e-3, loop.plant->state()[0], 1e-9);
  CHECK_TRUE(loop.Levitate());
  DOUBLES_EQUAL(25e-3, loop.plant->state()[0], 20e-6);
  CHECK_TRUE(loop.last.amplifier_enable);
}

TEST(PmlsmController, MotionBeforeReadyIsRefused) {
  loop.Tick();
  LONGS_EQUAL(static_cast<int>(CommandResult::kRefusedNotReady), static_cast<int>(loop.Step(ps::Axis::kX, 1e-3f)));
}

// Section IV-A (1): gap 20..30 mm, X and Z +-30 mm, theta +-10 mrad; a
// refused command changes nothing.
TEST(PmlsmController, SetPointsOutsideTheOperatingRangeAreRefusedAndChangeNothing) {
  CHECK_TRUE(loop.Levitate());
  const ps::PmlsmStatus before = loop.ctl.status();
  const int out = static_cast<int>(CommandResult::kRefusedOutOfRange);
  LONGS_EQUAL(out, static_cast<int>(loop.Step(ps::Axis::kGap, -8e-3f)));   // 17 mm: below the stops
  LONGS_EQUAL(out, static_cast<int>(loop.Step(ps::Axis::kGap, -5.5e-3f)));  // 19.5 mm: outside (1)
  LONGS_EQUAL(out, static_cast<int>(loop.Step(ps::Axis::kX, 31e-3f)));
  LONGS_EQUAL(out, static_cast<int>(loop.Step(ps::Axis::kTheta, -10.5e-3f)));
  LONGS_EQUAL(out, static_cast<int>(loop.Step(ps::Axis::kZ, NAN)));
  LONGS_EQUAL(out, static_cast<int>(loop.Step(static_cast<ps::Axis>(7), 1e-3f)));
  ps::MotionCommand fast;
  fast.type = ps::MotionType::kMoveTo;
  fast.axis = ps::Axis::kX;
  fast.target = 10e-3f;
  fast.velocity = 10.0f;
  LONGS_EQUAL(static_cast<int>(CommandResult::kRefusedBadProfile), static_cast<int>(loop.ctl.command(fast)));
  loop.Run(200);
  for (int a = 0; a < 5; ++a) {
    DOUBLES_EQUAL(static_cast<double>(before.reference[a]), static_cast<double>(loop.ctl.status().reference[a]), 0.0);
  }
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kReady);
  // The edges themselves are accepted (20 mm despite float rounding).
  LONGS_EQUAL(static_cast<int>(CommandResult::kAccepted), static_cast<int>(loop.Step(ps::Axis::kGap, -5e-3f)));
}

// Amplifiers off is not this stage's safe state at 25 mm (the magnets
// would pull the platen up onto the 18 mm stops): with the gap encoder
// good, a fault lands it under control, then cuts the amplifiers.
TEST(PmlsmController, AnEncoderLossLandsThePlatenUnderControlAndLatches) {
  CHECK_TRUE(loop.Levitate());
  loop.flags = ps::kEncoderLoss2;  // Z
  loop.Tick();
  LONGS_EQUAL(static_cast<int>(FaultCode::kBeamLoss), static_cast<int>(loop.ctl.status().fault));
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kFault);
  CHECK_TRUE(loop.last.amplifier_enable);  // landing
  ps::MotionCommand clear;
  clear.type = ps::MotionType::kClearFault;
  LONGS_EQUAL(static_cast<int>(CommandResult::kRefusedBusy), static_cast<int>(loop.ctl.command(clear)));
  loop.flags = 0;
  double v_contact = 0.0;
  for (int i = 0; i < 6000; ++i) {
    const double v = loop.plant->state()[1];
    loop.Tick();
    if (loop.plant->state()[0] >= 31e-3 && v > 0.0 && v_contact == 0.0) v_contact = v;
  }
  CHECK_TRUE(!loop.last.amplifier_enable);             // landed, then off
  DOUBLES_EQUAL(31e-3, loop.plant->state()[0], 1e-9);  // on its lower stops
  CHECK_TRUE(v_contact > 0.0 && v_contact < 2.2e-3);
  ps::MotionCommand lev;
  lev.type = ps::MotionType::kLevitate;
  LONGS_EQUAL(static_cast<int>(CommandResult::kRefusedFaultLatched), static_cast<int>(loop.ctl.command(lev)));
  LONGS_EQUAL(static_cast<int>(CommandResult::kAccepted), static_cast<int>(loop.ctl.command(clear)));
  CHECK_TRUE(loop.Levitate());
}

// Without the gap nothing can be controlled: amplifiers off at once.
TEST(PmlsmController, LosingTheGapEncoderCutsTheAmplifiersAtOnce) {
  CHECK_TRUE(loop.Levitate());
  loop.flags = ps::kEncoderLoss0;
  loop.Tick();
  LONGS_EQUAL(static_cast<int>(FaultCode::kBeamLoss), static_cast<int>(loop.ctl.status().fault));
  CHECK_TRUE(!loop.last.amplifier_enable);
  loop.Run(1000);
  CHECK_TRUE(!loop.last.amplifier_enable);
  // At 25 mm the attraction wins: the platen ends on the upper (18 mm) stops.
  DOUBLES_EQUAL(18e-3, loop.plant->state()[0], 1e-9);
}

TEST(PmlsmController, ACountJumpBeyondThePlausibleSpeedIsAFault) {
  CHECK_TRUE(loop.Levitate());
  loop.count_offset[1] = 150;  // 1.5 mm in one tick: 1.5 m/s, still plausible
  loop.Tick();
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kReady);
  loop.count_offset[1] = 500;  // another 3.5 mm: 3.5 m/s
  loop.Tick();
  LONGS_EQUAL(static_cast<int>(FaultCode::kCounterJump), static_cast<int>(loop.ctl.status().fault));
  // X is suspect: its loop opens, the gap lands under control.
  CHECK_TRUE(loop.last.amplifier_enable);
  LONGS_EQUAL(0, static_cast<int>(loop.ctl.status().i_q_A[1] * 1e6f));
  loop.Run(6000);
  CHECK_TRUE(!loop.last.amplifier_enable);
  DOUBLES_EQUAL(31e-3, loop.plant->state()[0], 1e-9);
}

TEST(PmlsmController, AGapCountJumpCutsTheAmplifiersAtOnce) {
  CHECK_TRUE(loop.Levitate());
  loop.count_offset[0] = -400;  // 4 mm in one tick
  loop.Tick();
  LONGS_EQUAL(static_cast<int>(FaultCode::kCounterJump), static_cast<int>(loop.ctl.status().fault));
  CHECK_TRUE(!loop.last.amplifier_enable);
}

// Saturation is the anti-windup's business, not a fault, and the command
// never exceeds the amplifiers.
TEST(PmlsmController, SaturationIsNotAFaultAndStaysInsideTheAmplifiers) {
  CHECK_TRUE(loop.Levitate());
  LONGS_EQUAL(static_cast<int>(CommandResult::kAccepted), static_cast<int>(loop.Step(ps::Axis::kX, 30e-3f)));
  int clamped = 0;
  for (int i = 0; i < 5000; ++i) {
    loop.Tick();
    clamped += loop.ctl.status().phase_clamped;
  }
  CHECK_TRUE(clamped > 0);
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kReady);
  CHECK_TRUE(loop.peak_A <= 7.0 + 2.0 * static_cast<double>(loop.design.config.amps_per_dac_code));
}

// Saturation that persists (1 s) is a fault: a stage whose amplifiers
// cannot carry it to its set-point (0.9 A, the 25 mm hover needs 1.05 A).
TEST(PmlsmController, SaturationThatPersistsIsAFault) {
  ps::PmlsmKernelConfig weak = loop.design.config;
  weak.phase_peak_A = 0.9f;
  CHECK_TRUE(loop.ctl.apply_config(weak) == ps::PmlsmConfigError::kOk);
  loop.Tick();
  ps::MotionCommand m;
  m.type = ps::MotionType::kLevitate;
  CHECK_TRUE(loop.ctl.command(m) == CommandResult::kAccepted);
  int first_clamp = -1, fault_at = -1;
  for (int i = 0; i < 10000 && fault_at < 0; ++i) {
    loop.Tick();
    if (first_clamp < 0 && loop.ctl.status().phase_clamped) first_clamp = i;
    if (loop.ctl.status().state == ps::StageState::kFault) fault_at = i;
  }
  LONGS_EQUAL(static_cast<int>(FaultCode::kCurrentSaturation), static_cast<int>(loop.ctl.status().fault));
  CHECK_TRUE(first_clamp >= 0 && fault_at - first_clamp >= 1000);
  CHECK_TRUE(loop.peak_A <= 0.9 + 2.0 * static_cast<double>(loop.design.config.amps_per_dac_code));
}

TEST(PmlsmController, TheConfigurationIsLockedWhileLevitatedAndBadOnesAreRefused) {
  ps::PmlsmKernelConfig bad = loop.design.config;
  bad.axis[1].Ks[0] = NAN;
  LONGS_EQUAL(static_cast<int>(ps::PmlsmConfigError::kBadGains), static_cast<int>(loop.ctl.apply_config(bad)));
  bad = loop.design.config;
  bad.phase_peak_A = 12.0f;  // beyond the DAC's 10 A full scale
  LONGS_EQUAL(static_cast<int>(ps::PmlsmConfigError::kBadLimits), static_cast<int>(loop.ctl.apply_config(bad)));
  CHECK_TRUE(loop.Levitate());
  LONGS_EQUAL(static_cast<int>(ps::PmlsmConfigError::kLockedWhileLevitated),
              static_cast<int>(loop.ctl.apply_config(loop.design.config)));
}

TEST(PmlsmController, LandsOnItsStopsBelowTheLandingSpeed) {
  CHECK_TRUE(loop.Levitate());
  ps::MotionCommand land;
  land.type = ps::MotionType::kLand;
  LONGS_EQUAL(static_cast<int>(CommandResult::kAccepted), static_cast<int>(loop.ctl.command(land)));
  double v_contact = 0.0;
  for (int i = 0; i < 8000 && loop.ctl.status().state != ps::StageState::kLanded; ++i) {
    const double v = loop.plant->state()[1];
    loop.Tick();
    if (loop.plant->state()[0] >= 31e-3 && v > 0.0 && v_contact == 0.0) v_contact = v;
  }
  CHECK_TRUE(loop.ctl.status().state == ps::StageState::kLanded);
  CHECK_TRUE(!loop.last.amplifier_enable);
  // The profile's landing speed (2 mm/s) is the ramp's: contact below it.
  CHECK_TRUE(v_contact > 0.0 && v_contact < 2e-3);
}
