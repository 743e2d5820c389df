// Printed (13), the fits of the unprinted parameters, the two parameter sets.
#include "maglev/selfstab_plant/params.hpp"

#include <cmath>

#include "maglev/selfstab_plant/force_law.hpp"

namespace maglev::selfstab_plant {

const char* CoilName(int coil) {
  static const char* const kNames[kCoils] = {"A", "B", "C", "dm", "dn", "em", "en", "fm", "fn"};
  return (coil >= 0 && coil < kCoils) ? kNames[coil] : "?";
}

const char* AxisName(int axis) {
  static const char* const kNames[kAxes] = {"x", "y", "z", "alpha", "beta", "gamma"};
  return (axis >= 0 && axis < kAxes) ? kNames[axis] : "?";
}

double PsdParams::lsb_m() const { return range_m / std::ldexp(1.0, adc_bits); }

Eq13 PrintedEq13() {
  // [P] eq (13). Gains per ampere of the first current of each bracket:
  // x: I_dm, y: I_dm, z: I_A, alpha: I_A, beta: I_B, gamma: I_dm.
  return Eq13{{
      {3.6369, 150.0, 3.4239},
      {3.6369, 150.0, 5.9303},
      {2.8648, 556.6771, 6.1124},
      {1.5286, 150.0, 123.7538},
      {1.5286, 150.0, 106.4245},
      {7.5796, 650.4952, -103.2034},
  }};
}

FittedValues FitToEq13(const StageParams& p, const Eq13& eq) {
  const double m = p.magnet.moment_A_m2();
  const double kappa = p.model.radial_to_axial_ratio_kappa;
  FittedValues f{};
  // R from the z damping row: m c_z = 3 k_dop = 3 k_opi^2 / R, with k_opi
  // from (4) (not from (13)).
  const double kopi = ForceConstant_N_per_A(p.out_of_plane, m, p.out_of_plane.nominal_position_m);
  const double kdop = eq[kZ].damping_per_s * p.mass_kg / 3.0;
  f.resistance_R_ohm = kopi * kopi / kdop;
  // r1 from the alpha damping row of (11): I_xx c_alpha = 1.5 r1^2 k_dop.
  f.r1_m = std::sqrt(eq[kAlpha].damping_per_s * p.inertia_xx_kg_m2 / (1.5 * kdop));
  // Element stiffnesses from the x and z stiffness rows of (11), general kappa:
  //   m k_x = 3 (1 - kappa) k_ip - 3 kappa k_op
  //   m k_z = 3 k_op - 6 kappa k_ip
  const double ax = 3.0 * (1.0 - kappa), bx = -3.0 * kappa, rx = eq[kX].stiffness_per_s2 * p.mass_kg;
  const double az = -6.0 * kappa, bz = 3.0, rz = eq[kZ].stiffness_per_s2 * p.mass_kg;
  const double det = ax * bz - bx * az;
  const double kip = (rx * bz - bx * rz) / det;
  const double kop = (ax * rz - az * rx) / det;
  SolenoidParams ip = p.in_plane, op = p.out_of_plane;
  ip.gradient_stretch_sigma = op.gradient_stretch_sigma = 1.0;
  f.sigma_in_plane = kip / AxialStiffness_N_per_m(ip, m, ip.nominal_position_m, ip.nominal_current_A);
  f.sigma_out_of_plane = kop / AxialStiffness_N_per_m(op, m, op.nominal_position_m, op.nominal_current_A);
  return f;
}

StageParams PrintedParams() {
  StageParams p;
  const FittedValues f = FitToEq13(p, PrintedEq13());
  p.r1_m = f.r1_m;
  p.coil.resistance_R_ohm = f.resistance_R_ohm;
  return p;
}

StageParams BenchParams() {
  StageParams p = PrintedParams();
  const FittedValues f = FitToEq13(p, PrintedEq13());
  p.in_plane.gradient_stretch_sigma = f.sigma_in_plane;
  p.out_of_plane.gradient_stretch_sigma = f.sigma_out_of_plane;
  return p;
}

}  // namespace maglev::selfstab_plant
