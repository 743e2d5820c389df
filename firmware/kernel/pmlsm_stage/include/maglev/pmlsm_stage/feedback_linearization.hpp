// Feedback linearization (12) of paper 002 with the input transformation (8):
// the regulators' demanded accelerations w = [y'' x'' z'' phi'' theta''] ->
// (i_d, i_q) per motor, on the simplified model (11) whose terms are
// evaluated from the force-law tables at the measured pose. Float, no libm
// (sin of the small tilts by its series, the 3x3 solve in closed form).
#pragma once

#include "maglev/pmlsm_stage/pmlsm_stage.hpp"

namespace maglev::pmlsm_stage {

// Gap functions at one gap, linearly interpolated (clamped to the table).
struct GapTerms {
  float attraction_N, direct_N_per_A, quadratic_N_per_A2, thrust_N_per_A;
};
GapTerms LookUpGapTerms(const ForceLawTable& t, float gap_m);

// Air gaps g_1..g_4 of (5) at pose y.
void AirGaps(const PmlsmKernelConfig& c, const float y[kAxes], float gaps_m[kMotors]);

struct LinearizedCurrents {
  float i_d_A[kMotors];
  float i_q_A[kMotors];
  float u_x_raw_A, u_z_raw_A;  // before sat_7 (the anti-windup's input)
  float u_x_A, u_z_A;          // after sat_7
};

// rotation_loops: false zeroes v_phi, v_theta (the 3-DOF test).
LinearizedCurrents FeedbackLinearize(const PmlsmKernelConfig& c, const float y[kAxes], const float w[kAxes],
                                     bool rotation_loops);

}  // namespace maglev::pmlsm_stage
