#pragma once
// Parameters of the 5-DOF PMLSM stage of paper 002 (Fulford, Maggiore &
// Apkarian 2009). Every value says where it comes from:
//   [P]    printed in the paper (Table I or the text),
//   [D]    derived from printed numbers,
//   (ours) not given by the paper: our choice, justified in docs/PAPER-002.md.
// SI units throughout; the unit is in the name.

namespace maglev::pmlsm_plant {

struct MotorParams {
  double slot_width_b0_m = 12.7e-3;      // [P] Table I, b_0
  double slot_pitch_t1_m = 19.05e-3;     // [P] Table I, t_1
  double turns_per_phase_W = 900.0;      // [P] Table I, W
  double pole_pairs_p = 3.0;             // [P] Table I, p
  double pm_height_hm_m = 5e-3;          // [P] Table I, h_m
  double pm_length_LA_m = 50e-3;         // [P] Table I, L_A
  double pm_count_pm = 4.0;              // [P] Table I, p_m
  double pole_pitch_tau_m = 57.15e-3;    // [P] Table I, tau
  double pm_width_taup_m = 28.58e-3;     // [P] Table I, tau_p
  double pm_coercivity_Hc_A_per_m = 875400.0;  // [P] Table I, H_c; sigma_m = H_c (ours)
  double winding_factor_kw1 = 1.0;       // [D] one slot per pole per phase, coil pitch = tau
  double pm_recoil_permeability_mu_rec = 1.05;  // (ours) typical sintered NdFeB (N35)
  // K_v3 as printed leaves no equilibrium below ~28 mm (docs/PAPER-002.md);
  // any factor <= 0.154 restores one at 18 mm. 0.05 (ours) keeps the hover
  // direct current within the 5 A continuous rating over 18..31 mm.
  double kv3_scale = 0.05;
};

struct StageParams {
  MotorParams motor;
  double gravity_G_m_per_s2 = 9.81;      // G in (6)
  double mass_x_kg = 10.6;               // [P] Table I, M_x (on the X guides)
  double mass_z_kg = 8.6;                // [P] Table I, M_z
  double mass_y_kg = 6.9;                // [P] Table I, M_y (levitated part)
  double inertia_x_kg_m2 = 0.5268;       // [P] Table I, I_x
  double inertia_z_kg_m2 = 0.5268;       // [P] Table I, I_z
  double radius_to_movers_r_m = 0.397;   // [P] Table I, r
  double motor_pair_separation_m = 0.400;  // [P] Table I; not used by (5)-(7)
  // Torsional stiffness of the vertical guides divided by inertia, k_s in (7)
  // [1/s^2]. Not given. Must exceed the magnetic negative rotational stiffness
  // (~1.1e3..2.1e3 1/s^2 over 30..20 mm [D]) so the 3-DOF test with rotation
  // loops off is stable. theta (Z rotation): 3.0e3 (ours). phi (X rotation):
  // larger by the range ratio 14 mrad / 3 mrad (ours), i.e. 1.4e4.
  double guide_torsion_phi_per_s2 = 1.4e4;
  double guide_torsion_theta_per_s2 = 3.0e3;
  // Guide viscous friction, per axis [1/s] (ours; paper gives none): 0 = ideal guides.
  double guide_damping_per_s = 0.0;
  // Mechanical stops [P]: air gap 18..31 mm, X/Z +-50 mm.
  double gap_min_m = 18e-3;
  double gap_max_m = 31e-3;
  double horizontal_range_m = 50e-3;
};

struct AmplifierParams {
  double phase_peak_A = 7.0;         // [P] 7 A peak per linear amplifier
  double phase_continuous_A = 5.0;   // [P] 5 A continuous (reported, not enforced)
};

struct EncoderParams {
  double translation_resolution_m = 10e-6;  // [P] 10 um
  double rotation_resolution_rad = 20e-6;   // [P] ~20 urad
};

}  // namespace maglev::pmlsm_plant
