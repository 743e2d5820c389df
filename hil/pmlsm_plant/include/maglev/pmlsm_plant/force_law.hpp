#pragma once
// Force laws (1)-(4) of paper 002 for one iron-cored PMLSM, as functions of
// the air gap g and the (i_d, i_q) currents. Cogging is neglected (the paper
// shows it is negligible above 15 mm; the range here is 18..31 mm).
//
// Sign convention (paper): F_V > 0 increases the air gap (pushes the mover
// away from the stator); the PM attraction term -K_v1 L_v1 closes the gap.
// F_H = -K_h L_h i_q acts along the motor's horizontal axis.
#include "maglev/pmlsm_plant/params.hpp"

namespace maglev::pmlsm_plant {

// Gap-independent constants of (3) and (4).
struct ForceConstants {
  double Kv1;  // [N / T^2]
  double Kv2;  // [N / (T A)]
  double Kv3;  // [N / A^2], includes MotorParams::kv3_scale
  double Kh;   // [N / A]
};
ForceConstants ComputeForceConstants(const MotorParams& m);

// Gap functions of (3)-(4).
double Gamma1(const MotorParams& m, double gap_m);
double CarterFactor_Kc(const MotorParams& m, double gap_m);
double Lambda(const MotorParams& m, double gap_m);
// Fundamental of the PM field at the stator (not defined in the paper; the
// form that makes K_h L_h factor through B, with sigma_m = H_c).
double PmField_B_T(const MotorParams& m, double gap_m);
double Lv1(const MotorParams& m, double gap_m);
double Lv2(const MotorParams& m, double gap_m);
double Lv3(const MotorParams& m, double gap_m);
double Lh(const MotorParams& m, double gap_m);

struct MotorForce {
  double horizontal_N;  // F_H, (1)
  double vertical_N;    // F_V, (2)
};
MotorForce ComputeMotorForce(const MotorParams& m, const ForceConstants& k, double gap_m,
                             double i_d_A, double i_q_A);

// Direct current that makes one motor carry weight_N at zero i_q (the larger
// root of (2) = -weight, i.e. the branch through i_d = 0). Returns false when
// no equilibrium exists at this gap.
bool HoverDirectCurrent_A(const MotorParams& m, const ForceConstants& k, double gap_m,
                          double weight_N, double* i_d_A);

}  // namespace maglev::pmlsm_plant
