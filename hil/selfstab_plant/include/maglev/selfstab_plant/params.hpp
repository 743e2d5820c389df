#pragma once
// Parameters of the self-stabilizing positioner of paper 001 (Jung & Baek
// 2002). Every value says where it comes from:
//   [P]      printed in the paper (Table 1, Table 2 or the text),
//   [D]      derived from printed numbers,
//   (ours)   not given by the paper: our choice, justified in docs/PAPER-001.md,
//   (fitted) not given: fitted to ONE named coefficient of eq (13). A
//            coefficient used for a fit is never reported as agreement.
// SI units throughout; the unit is in the name. Inertias are printed in
// kg cm^2 and converted here.
#include <array>

namespace maglev::selfstab_plant {

// Nine coils: three out-of-plane (A, B, C: vertical axes, carry the weight)
// and six in-plane (dm, dn, em, en, fm, fn: horizontal axes, in pairs on the
// frames D, E, F). The order is used for every 9-vector in this library.
inline constexpr int kCoils = 9;
enum CoilIndex : int { kA = 0, kB, kC, kDm, kDn, kEm, kEn, kFm, kFn };
const char* CoilName(int coil);
inline bool IsOutOfPlane(int coil) { return coil <= kC; }

struct SolenoidParams {
  double inner_radius_r_m;      // r in (4): Table 2 inner diameter / 2
  double outer_radius_R_m;      // R in (4): Table 2 outer diameter / 2
  double length_l_m;            // l in (4)
  double turns_N;               // N in (4)
  // Magnet centre on the coil axis, measured from the coil MID-PLANE [D]:
  // with this reading (4) gives the force constants of (13) within 0.5 %;
  // from the coil face it would give about a quarter of them.
  double nominal_position_m;
  double nominal_current_A;
  // (fitted) Stretch of the axial coordinate about the nominal position:
  // the law is evaluated at s_hat = s0 + sigma (s - s0). sigma = 1 is (4)
  // exactly. The force constant at s0 does not depend on sigma; the axial
  // stiffness scales by sigma. See StageParams::fitted and docs/PAPER-001.md.
  double gradient_stretch_sigma = 1.0;
};

struct MagnetParams {
  double magnetization_M_A_per_m = 867000.0;  // [P] Table 1 (text: "coercive force")
  double volume_m3 = 0.7854e-6;               // [P] Table 1, pi 0.5^2 x 1.0 cm^3
  double radius_m = 0.005;                    // [P] Table 1 (volume formula)
  double length_m = 0.010;                    // [P] Table 1 (volume formula)
  // Dipole moment m_z = M V (the paper's dipole approximation) [D]: 0.68094 A m^2.
  double moment_A_m2() const { return magnetization_M_A_per_m * volume_m3; }
};

// Coil electrics, eq (7): u = R i + L di/dt + d(lambda)/dt.
struct CoilElectrical {
  // (fitted) to the z damping row of (13): R = k_opi^2 / k_dop with k_opi
  // from (4) and k_dop = 2.8648 m / 3. About 6.72 ohm; the text says "about
  // 8 ohm" for the first solenoid model (that would give 16 % less damping).
  double resistance_R_ohm = 6.7223;
  // [P] 0.000673 H, computed in the text for the first solenoid model (the
  // in-plane coil's size); used for all nine coils (ours). tau = L/R ~ 0.1 ms.
  double inductance_L_H = 0.000673;
};

// How the paper's force law is turned into a 6-DOF model.
struct ForceModelOptions {
  // [P] radial stiffness = -0.2 x axial ("all selected into 0.2 times those
  // of the axis direction"; Fig. 3). A field that obeys Maxwell's equations
  // near the axis gives 0.5 (Earnshaw): then x and y are NOT passively
  // stable. The plant keeps the paper's 0.2; docs/PAPER-001.md.
  double radial_to_axial_ratio_kappa = 0.2;
  // (ours, = (11)) false: the nominal force of each coil (its current times
  // the force constant at the nominal position) acts at the magnet's NOMINAL
  // lever and only the change acts at the actual magnet, so the
  // linearization has no prestress (geometric) stiffness, as (11) and (13).
  // true: every force acts at the actual magnet (full rigid-body mechanics);
  // the in-plane pairs push apart with 0.504 N each, which adds ~+177 1/s^2
  // to alpha, beta and ~+185 1/s^2 to gamma (docs/PAPER-001.md).
  bool prestress_lever = false;
  // (ours, = (11)) eq (2)'s torque m x B on each magnet is left out, as (11)
  // does ("assuming that there is no torque"). true adds it (near-axis field).
  bool dipole_torque = false;
};

// PSD sensors (Section 4).
struct PsdParams {
  // [P] three PSDs at 120 deg around the stator's inner ring; the first at
  // 0 deg (ours).
  double first_angle_rad = 0.0;
  double ring_radius_m = 0.100;      // (ours) PSD plane distance from the centre
  double led_radius_m = 0.080;       // (ours) LED projector radius on the rotor
  // [P] 12-bit A/D over ~4.7 mm: 4.7 mm / 4096 = 1.1475 um per count.
  double range_m = 4.7e-3;
  int adc_bits = 12;
  double lsb_m() const;
};

// Eq (13) as printed: per axis  q'' + c q' + k q = b (combination of currents).
// Gains are per ampere of the first current in the bracket of (13).
struct AxisCoefficients {
  double damping_per_s;
  double stiffness_per_s2;
  double gain;  // [m/(s^2 A)] or [rad/(s^2 A)]
};
inline constexpr int kAxes = 6;
enum AxisIndex : int { kX = 0, kY, kZ, kAlpha, kBeta, kGamma };
const char* AxisName(int axis);
using Eq13 = std::array<AxisCoefficients, kAxes>;
Eq13 PrintedEq13();  // [P] the six rows of (13)

// Which parameters were fitted, and to which coefficient of (13).
struct FittedValues {
  double r1_m;                    // to the alpha damping row
  double resistance_R_ohm;        // to the z damping row
  double sigma_out_of_plane;      // to the x and z stiffness rows (jointly)
  double sigma_in_plane;          // to the x and z stiffness rows (jointly)
};

struct StageParams {
  MagnetParams magnet;
  // [P] Table 2 out-of-plane solenoid: 0.016 / 0.0367 / 0.0238 m, 0.0164 m, 0.535 A, 986 turns.
  SolenoidParams out_of_plane{0.008, 0.01835, 0.0238, 986.0, 0.0164, 0.535, 1.0};
  // [P] Table 2 in-plane solenoid: 0.016 / 0.0362 / 0.0246 m, 0.0151 m, 0.4273 A, 996 turns.
  SolenoidParams in_plane{0.008, 0.0181, 0.0246, 996.0, 0.0151, 0.4273, 1.0};
  CoilElectrical coil;
  ForceModelOptions model;
  PsdParams psd;

  double mass_kg = 0.173;                 // [P] Table 1
  double inertia_xx_kg_m2 = 4.26e-4;      // [P] Table 1, 4.26 kg cm^2
  double inertia_yy_kg_m2 = 4.29e-4;      // [P] Table 1, 4.29 kg cm^2
  double inertia_zz_kg_m2 = 8.18e-4;      // [P] Table 1, 8.18 kg cm^2
  double gravity_m_per_s2 = 9.81;         // (ours) the value that closes the weight check of the notes
  double L_m = 0.05;                      // [P] Table 1, distance from frame D to magnet dm
  double r2_m = 0.0715;                   // [P] Table 2, stator centre to frames D, E, F
  // r1, stator centre to the out-of-plane coils, is NOT printed. 0.0499 m
  // follows from the alpha/beta force rows of (13), 0.0513 m from the
  // alpha/beta damping and stiffness rows [D]. Default: fitted to the alpha
  // damping row (FitToEq13 recomputes it).
  double r1_m = 0.05126;
  // (ours, from the signs of (11)) angles of A, B, C: 90, 210, 330 deg;
  // frames D, E, F at 150, 270, 30 deg; in-plane coil axes along the
  // clockwise tangent; magnets dm/dn at frame +- L along that tangent, pushed
  // outward (the pair pulls apart, like a string in tension).
  // Docking stop (ours): the rotor rests at z = -2.5 mm (below the +-2 mm
  // operating range), all other coordinates held at 0, when its net vertical
  // force does not lift it.
  double dock_z_m = -2.5e-3;
};

// The printed set: Table 1 and 2 values, (4) unscaled (sigma = 1), with the
// r1 and R fits (they are needed to have a model at all).
StageParams PrintedParams();

// Fits r1, R and the two sigmas to the named rows of (13) (see FittedValues)
// and returns them; the bench set BenchParams() uses them.
FittedValues FitToEq13(const StageParams& printed, const Eq13& eq13);

// The bench set: PrintedParams() with FitToEq13 applied.
StageParams BenchParams();

}  // namespace maglev::selfstab_plant
