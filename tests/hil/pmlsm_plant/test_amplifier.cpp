// Three-phase commutation and amplifier saturation.
#include <cmath>

#include "maglev/pmlsm_plant/amplifier.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::pmlsm_plant;

TEST_GROUP(Amplifier){};

TEST(Amplifier, ParkRoundTripAndBalancedPhases) {
  for (double th = -3.0; th < 3.0; th += 0.37) {
    const DqCurrents dq{1.3, -2.1};
    const PhaseCurrents p = InverseParkClarke(dq, th);
    DOUBLES_EQUAL(0.0, p.abc_A[0] + p.abc_A[1] + p.abc_A[2], 1e-12);
    // Amplitude-invariant: peak phase equals |(i_d, i_q)| over a period.
    const DqCurrents back = ParkClarke(p, th);
    DOUBLES_EQUAL(dq.d_A, back.d_A, 1e-12);
    DOUBLES_EQUAL(dq.q_A, back.q_A, 1e-12);
  }
  const PhaseCurrents p0 = InverseParkClarke({2.0, 0.0}, 0.0);
  DOUBLES_EQUAL(2.0, p0.abc_A[0], 1e-12);
  DOUBLES_EQUAL(-1.0, p0.abc_A[1], 1e-12);
}

TEST(Amplifier, ElectricalAngleAdvancesPiPerPolePitch) {
  MotorParams m;
  DOUBLES_EQUAL(M_PI, ElectricalAngle_rad(m, m.pole_pitch_tau_m), 1e-12);
}

TEST(Amplifier, BelowLimitPassesThrough) {
  const AmplifierOutput o = DriveMotor({}, {3.0, 4.0}, 0.4);
  CHECK_FALSE(o.saturated);
  DOUBLES_EQUAL(3.0, o.delivered.d_A, 1e-12);
  DOUBLES_EQUAL(4.0, o.delivered.q_A, 1e-12);
}

TEST(Amplifier, SaturatesAtSevenAmpsKeepingDirection) {
  // Direct current alone at theta_e = 0: phase a carries i_d, so i_d saturates at 7 A.
  AmplifierOutput o = DriveMotor({}, {12.0, 0.0}, 0.0);
  CHECK(o.saturated);
  DOUBLES_EQUAL(7.0, o.delivered.d_A, 1e-12);
  DOUBLES_EQUAL(0.0, o.delivered.q_A, 1e-12);
  o = DriveMotor({}, {-9.0, 9.0}, 1.1);
  CHECK(o.saturated);
  double peak = 0;
  for (double i : o.phases.abc_A) peak = std::fmax(peak, std::fabs(i));
  DOUBLES_EQUAL(7.0, peak, 1e-12);
  DOUBLES_EQUAL(-1.0, o.delivered.d_A / o.delivered.q_A, 1e-12);
}
