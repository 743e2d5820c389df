#pragma once
// Solenoid field and the force on a permanent magnet, eqs (1)-(9) of paper 001.
//
// b(s): axial field per ampere on the axis of a multi-layer air-core
// solenoid, eq (4), s measured from the coil mid-plane along its axis [T/A].
// The magnet is a dipole of moment m_z pointing AGAINST the coil field
// (repulsion: the rotor floats above / beside its coils).
//
// One scalar function carries the whole interaction: the mutual flux linkage
// of the coil with the magnet (eq (6), by reciprocity the same function as
// (4) times m_z), extended off the axis to second order in the radial offset rho:
//   lambda(s, rho) = -m_z [ b(s_hat)/sigma - (kappa/2) sigma rho^2 b''(s_hat) ]
// with s_hat = s0 + sigma (s - s0) (sigma = 1 is (4) itself) and kappa the
// radial/axial ratio. Then, with the coil current i,
//   force on the magnet   F = i grad(lambda)                  (1), (10)
//     axial  F_s = -m_z i b'(s_hat)            (+ O(rho^2))
//     radial F_rho = kappa k_s rho, k_s = m_z i sigma b''(s_hat) = axial stiffness
//   back-emf in the coil  e = d(lambda)/dt = grad(lambda) . v   (5)-(7)
// so, with a voltage-driven coil, u = R i + L di/dt + e, and the damping of
// (9) is k_d = k_i^2 / R (k_i = -m_z b'), which a current amplifier removes.
// kappa = 0.5 would be the harmonic (Maxwell) field; the paper uses 0.2.
#include "maglev/selfstab_plant/params.hpp"

namespace maglev::selfstab_plant {

// Eq (4) per ampere and its derivatives in s, all at the true coordinate
// (no stretch): [T/A], [T/(A m)], [T/(A m^2)], [T/(A m^3)].
double FieldOnAxis_T_per_A(const SolenoidParams& c, double s_m);
double FieldGradient_T_per_A_m(const SolenoidParams& c, double s_m);
double FieldCurvature_T_per_A_m2(const SolenoidParams& c, double s_m);
double FieldThirdDerivative_T_per_A_m3(const SolenoidParams& c, double s_m);

// The coil-magnet interaction at axial position s and radial offset rho.
struct PairInteraction {
  double flux_linkage_Wb;   // lambda
  double dlambda_ds_Wb_per_m;      // axial force per ampere [N/A]
  // d(lambda)/d(rho) / rho, so the radial force vector is i * this * rho_vec
  // (finite at rho = 0) [N/(A m)].
  double dlambda_drho_over_rho_Wb_per_m2;
  double field_axial_T_per_A;      // b(s_hat), for eq (2)
  double field_gradient_T_per_A_m; // sigma b'(s_hat), for eq (2) off the axis
};
PairInteraction ComputePair(const SolenoidParams& c, double moment_A_m2, double kappa,
                            double s_m, double rho_m);

// Force constant k_i = dF_s/di at axial position s (rho = 0) [N/A].
double ForceConstant_N_per_A(const SolenoidParams& c, double moment_A_m2, double s_m);
// Axial stiffness k = -dF_s/ds at s with current i [N/m]; > 0 is a spring.
double AxialStiffness_N_per_m(const SolenoidParams& c, double moment_A_m2, double s_m,
                              double current_A);
// Passive damping of (9) with a voltage-driven coil, k_d = k_i^2 / R [N s/m].
double EmfDamping_N_s_per_m(const SolenoidParams& c, double moment_A_m2, double s_m,
                            double resistance_ohm);
// k_i(s0 + offset) / k_i(s0): how the force constant moves with the gap
// (feeds the gain schedule). 1 at offset 0.
double ForceConstantRatio(const SolenoidParams& c, double moment_A_m2, double offset_m);

}  // namespace maglev::selfstab_plant
