// Eq (4) and the interaction built on it: force constants against (13), the
// weight check, the damping of (9) and the resistance it implies, the force
// constant over +-1 mm (feeds the gain schedule).
#include <cmath>
#include <cstdio>

#include "maglev/selfstab_plant/force_law.hpp"
#include "maglev/selfstab_plant/params.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::selfstab_plant;

TEST_GROUP(ForceLaw) {
  StageParams p = PrintedParams();
  double m = p.magnet.moment_A_m2();
  const SolenoidParams& op = p.out_of_plane;
  const SolenoidParams& ip = p.in_plane;
  Eq13 e = PrintedEq13();
};

TEST(ForceLaw, TableValuesInSi) {
  DOUBLES_EQUAL(0.680942, m, 1e-6);  // M V = 867000 x 0.7854e-6
  // Table 1 solenoid volume 20.4204 cm^3; Table 2's rounded dimensions give
  // 20.37 (in-plane) and 20.39 (out-of-plane) cm^3.
  const double pi = 3.14159265358979323846;
  const double v_ip = pi * (ip.outer_radius_R_m * ip.outer_radius_R_m - ip.inner_radius_r_m * ip.inner_radius_r_m) * ip.length_l_m;
  const double v_op = pi * (op.outer_radius_R_m * op.outer_radius_R_m - op.inner_radius_r_m * op.inner_radius_r_m) * op.length_l_m;
  std::printf("\n  solenoid volume: in-plane %.3f cm^3, out-of-plane %.3f cm^3 (Table 1: 20.4204)\n", v_ip * 1e6, v_op * 1e6);
  DOUBLES_EQUAL(20.4204e-6, v_ip, 0.005 * 20.4204e-6);
  DOUBLES_EQUAL(20.4204e-6, v_op, 0.005 * 20.4204e-6);
  DOUBLES_EQUAL(4.26e-4, p.inertia_xx_kg_m2, 1e-12);
  DOUBLES_EQUAL(8.18e-4, p.inertia_zz_kg_m2, 1e-12);
}

TEST(ForceLaw, ClosedFormDerivativesMatchNumerical) {
  const double h = 1e-6;
  for (double s : {0.0, 0.008, 0.0164, 0.025}) {
    const double d1 = (FieldOnAxis_T_per_A(op, s + h) - FieldOnAxis_T_per_A(op, s - h)) / (2 * h);
    const double d2 = (FieldGradient_T_per_A_m(op, s + h) - FieldGradient_T_per_A_m(op, s - h)) / (2 * h);
    DOUBLES_EQUAL(d1, FieldGradient_T_per_A_m(op, s), 1e-7 * (std::fabs(d1) + 1));
    DOUBLES_EQUAL(d2, FieldCurvature_T_per_A_m2(op, s), 1e-6 * (std::fabs(d2) + 1));
  }
  // Centre field of a long-ish solenoid: between the thin-shell bounds.
  const double b0 = FieldOnAxis_T_per_A(op, 0.0);
  std::printf("\n  b(0) = %.5f T/A, b(s0) = %.5f T/A (out-of-plane coil)\n", b0, FieldOnAxis_T_per_A(op, op.nominal_position_m));
  DOUBLES_EQUAL(0.03520, b0, 1e-4);
}

TEST(ForceLaw, ForceConstantsFromMidPlaneMatchEq13) {
  // (13): z gain = k_opi / m, x gain = k_ipi / (2 m).
  const double kopi_13 = e[kZ].gain * p.mass_kg;
  const double kipi_13 = 2.0 * e[kX].gain * p.mass_kg;
  const double kopi = ForceConstant_N_per_A(op, m, op.nominal_position_m);
  const double kipi = ForceConstant_N_per_A(ip, m, ip.nominal_position_m);
  // Nominal position read from the coil face instead: s = s0 + l/2.
  const double kopi_face = ForceConstant_N_per_A(op, m, op.nominal_position_m + 0.5 * op.length_l_m);
  std::printf("\n  k_opi: (4) %.4f N/A, (13) %.4f (ratio %.4f); from the face %.4f (ratio %.3f)\n", kopi, kopi_13,
              kopi / kopi_13, kopi_face, kopi_face / kopi_13);
  std::printf("  k_ipi: (4) %.4f N/A, (13) %.4f (ratio %.4f)\n", kipi, kipi_13, kipi / kipi_13);
  DOUBLES_EQUAL(1.0, kopi / kopi_13, 0.005);
  DOUBLES_EQUAL(1.0, kipi / kipi_13, 0.005);
  CHECK(kopi_face / kopi_13 < 0.3);
}

TEST(ForceLaw, WeightCheck) {
  const double kopi = ForceConstant_N_per_A(op, m, op.nominal_position_m);
  const double lift = 3.0 * kopi * op.nominal_current_A;
  const double weight = p.mass_kg * p.gravity_m_per_s2;
  const double lift_13 = 3.0 * e[kZ].gain * p.mass_kg * op.nominal_current_A;
  std::printf("\n  weight check: 3 x %.4f N/A x 0.535 A = %.4f N; m g = %.4f N (ratio %.4f); with (13)'s k: %.4f N\n",
              kopi, lift, weight, lift / weight, lift_13);
  DOUBLES_EQUAL(weight, lift_13, 1e-3);          // (13) itself closes it
  DOUBLES_EQUAL(1.0, lift / weight, 0.005);      // (4) within 0.34 %
}

TEST(ForceLaw, DampingOfEq9ImpliesResistance) {
  // k_d = k_i^2 / R. What R do the damping rows of (13) imply (with (13)'s k)?
  const double kopi_13 = e[kZ].gain * p.mass_kg, kipi_13 = 2.0 * e[kX].gain * p.mass_kg;
  const double R_z = kopi_13 * kopi_13 / (e[kZ].damping_per_s * p.mass_kg / 3.0);
  const double R_x = kipi_13 * kipi_13 / (e[kX].damping_per_s * p.mass_kg / 3.0);
  std::printf("\n  R implied by (13): z row %.3f ohm, x row %.3f ohm; text: 'about 8 ohm'; plant (fitted, z row, (4)'s k) %.4f\n",
              R_z, R_x, p.coil.resistance_R_ohm);
  DOUBLES_EQUAL(6.77, R_z, 0.01);
  DOUBLES_EQUAL(6.69, R_x, 0.01);
  DOUBLES_EQUAL(6.722, p.coil.resistance_R_ohm, 0.001);
  const double kd = EmfDamping_N_s_per_m(op, m, op.nominal_position_m, p.coil.resistance_R_ohm);
  DOUBLES_EQUAL(e[kZ].damping_per_s * p.mass_kg / 3.0, kd, 1e-9);
  // Time constant L/R of the text: 0.1 ms.
  DOUBLES_EQUAL(1.0e-4, p.coil.inductance_L_H / p.coil.resistance_R_ohm, 0.05e-4);
}

TEST(ForceLaw, InteractionIsOnePotential) {
  // Force per ampere = grad(lambda): the emf and the force use the same
  // function, so the electromechanical coupling is lossless.
  const StageParams b = BenchParams();
  for (const SolenoidParams* c : {&b.out_of_plane, &b.in_plane}) {
    const double s = c->nominal_position_m + 0.3e-3, rho = 0.8e-3, h = 1e-7;
    const PairInteraction pi = ComputePair(*c, m, 0.2, s, rho);
    const double ds = (ComputePair(*c, m, 0.2, s + h, rho).flux_linkage_Wb - ComputePair(*c, m, 0.2, s - h, rho).flux_linkage_Wb) / (2 * h);
    const double dr = (ComputePair(*c, m, 0.2, s, rho + h).flux_linkage_Wb - ComputePair(*c, m, 0.2, s, rho - h).flux_linkage_Wb) / (2 * h);
    DOUBLES_EQUAL(ds, pi.dlambda_ds_Wb_per_m, 1e-7 * std::fabs(ds));
    DOUBLES_EQUAL(dr, pi.dlambda_drho_over_rho_Wb_per_m2 * rho, 1e-6 * std::fabs(dr));
    // Radial force = 0.2 x axial stiffness x rho (the paper's radial rule).
    const double k = AxialStiffness_N_per_m(*c, m, s, 1.0);
    DOUBLES_EQUAL(0.2 * k * rho, pi.dlambda_drho_over_rho_Wb_per_m2 * rho, 1e-12);
  }
}

TEST(ForceLaw, ForceConstantOverPlusMinusOneMillimetre) {
  std::printf("\n  k_i(s0 + d) / k_i(s0)        d: -2mm    -1mm   -100um  +100um    +1mm    +2mm\n");
  const double ds[6] = {-2e-3, -1e-3, -1e-4, 1e-4, 1e-3, 2e-3};
  double r[2][2][6];
  const StageParams sets[2] = {PrintedParams(), BenchParams()};
  for (int s = 0; s < 2; ++s) {
    for (int c = 0; c < 2; ++c) {
      const SolenoidParams& sol = c == 0 ? sets[s].out_of_plane : sets[s].in_plane;
      std::printf("  %-8s %-14s", s == 0 ? "(4)" : "bench", c == 0 ? "out-of-plane" : "in-plane");
      for (int k = 0; k < 6; ++k) {
        r[s][c][k] = ForceConstantRatio(sol, m, ds[k]);
        std::printf(" %7.4f", r[s][c][k]);
      }
      std::printf("\n");
    }
  }
  // Notes: < 1 % over +-100 um, ~+-8 % over +-1 mm for (4) (out-of-plane).
  for (int s = 0; s < 2; ++s)
    for (int c = 0; c < 2; ++c) {
      CHECK(std::fabs(r[s][c][2] - 1.0) < 0.01);
      CHECK(std::fabs(r[s][c][3] - 1.0) < 0.01);
    }
  DOUBLES_EQUAL(1.0794, r[0][0][1], 0.001);  // -1 mm: closer to the coil, stronger
  DOUBLES_EQUAL(0.9142, r[0][0][4], 0.001);  // +1 mm
  DOUBLES_EQUAL(1.0476, r[0][1][1], 0.001);
  DOUBLES_EQUAL(0.9361, r[0][1][4], 0.001);
}
