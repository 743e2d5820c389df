#pragma once
// Three linear current amplifiers per motor, commutated from (i_d, i_q).
//
// Amplitude-invariant Park transform with electrical angle
// theta_e = pi * s / tau (s: mover position along the motor's travel axis), so
// |(i_d, i_q)| equals the peak phase current. Each phase is limited to
// +-phase_peak_A (the "sat_7" of (17)); since the star winding keeps
// i_a + i_b + i_c = 0, saturation scales the whole (i_d, i_q) vector (ours:
// the winding connection is not printed) and the delivered (i_d, i_q) is the
// Park transform of the limited phase currents. Phase R/L and the 28 V rail are not
// printed; the amplifiers are ideal current sources below the clamp (ours).
#include <array>

#include "maglev/pmlsm_plant/params.hpp"

namespace maglev::pmlsm_plant {

struct PhaseCurrents {
  std::array<double, 3> abc_A{};  // phases a, b, c
};

struct DqCurrents {
  double d_A = 0.0;
  double q_A = 0.0;
};

double ElectricalAngle_rad(const MotorParams& m, double position_m);
PhaseCurrents InverseParkClarke(const DqCurrents& dq, double theta_e_rad);
DqCurrents ParkClarke(const PhaseCurrents& abc, double theta_e_rad);

struct AmplifierOutput {
  PhaseCurrents phases;  // after the clamp
  DqCurrents delivered;  // what the motor sees
  bool saturated = false;
};

// Commands one motor's three amplifiers.
AmplifierOutput DriveMotor(const AmplifierParams& a, const DqCurrents& command, double theta_e_rad);

}  // namespace maglev::pmlsm_plant
