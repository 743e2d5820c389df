// Configuration of the HIL physical plant: the 6-DOF platen over the Halbach
// magnet matrix, its eight linear current amplifiers and its sensors.
//
// Every default comes from maglev/io/stage_parameters.hpp (the one source of
// truth shared with the controller kernel) or from papers 000 / 003; values
// marked "(ours)" are modelling choices the papers do not state. docs/PLANT.md
// lists every element with its source.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/plant/floor_vibration.hpp"
#include "maglev/plant/rng.hpp"

namespace maglev::hil {

inline constexpr int kForcers = 4;
inline constexpr int kCoils = io::kCoils;

// --- Halbach field and coils, paper 000 eqs (1)-(11), (20) -----------------
struct FieldConfig {
  double pitch_m = io::stage::kPitch_m;
  double magnet_thickness_m = io::stage::kMagnetThickness_m;
  // Peak magnetization M0 [A/m]. <= 0 means "calibrate": choose M0 so that the
  // model's 2 b*(z0) at the rest gap equals two_b_star_N_per_A (eq 29).
  double peak_magnetization_A_per_m = 0.0;
  // The identified 2 b*(z0) the calibration meets: the seed's, or a profile's
  // `two_b_star_N_per_A` (the plant used the seed's whatever the profile said,
  // while the kernel allocated with the profile's).
  double two_b_star_N_per_A = io::stage::kTwoBStarIdentified_N_per_A;
  // Harmonics n = 4k+1 used in (1)-(2): 1 -> n=1 only; 4 -> n = 1,5,9,13.
  int harmonics = 4;
  double coil_effective_length_m = io::stage::kCoilEffectiveLength_m;  // p
  double coil_side_width_m = io::stage::kCoilSideWidth_m;              // a
  double coil_thickness_m = io::stage::kCoilThickness_m;               // d
  int coil_turns = io::stage::kCoilTurns;                              // N
  double rest_gap_m = io::stage::kRestGap_m;                           // z0
};

// --- Platen geometry and rigid body, paper 000 Sec. III, eqs (16)-(18) -----
struct BodyConfig {
  double mass_kg = io::stage::kMass_kg;
  double inertia_kgm2[3] = {io::stage::kIx_kgm2, io::stage::kIy_kgm2, io::stage::kIz_kgm2};
  // Added payload (Fig. 9: 539.6 g). (ours) Modelled as a thin square plate of
  // side payload_side_m whose centre of mass coincides with the platen's, so it
  // adds m_p s^2/12 to Ix, Iy and m_p s^2/6 to Iz and does not move the CoM.
  double payload_kg = 0.0;
  double payload_side_m = 0.10;
  double lever_arm_m = io::stage::kLeverArm_m;  // l of eq (18)
  // Where the forcers sit (paper 003 eqs (6)-(8)): cross (paper 000,
  // forcers on the axes) or square (at the corners (+-l, +-l)): the coils of
  // x-thrust forcers lie along the x array, of y-thrust forcers along y.
  // Triangle (eq (8), Fig. 8): three forcers in a Y, coils 1-6 (7, 8 absent),
  // 1&2 at l(cos a, sin a) thrusting along (-sin a, cos a), 3&4 at
  // l(-cos a, sin a) along (-sin a, -cos a), 5&6 at (0, -l) along X, with
  // a = triangle_alpha_rad: the kernel's geometry (force_allocation). The
  // oblique coil sides see both arrays (docs/PLANT.md, "Triangle layout").
  enum class Layout : std::uint8_t { kCross = 0, kSquare = 1, kTriangle = 2 } layout = Layout::kCross;
  double triangle_alpha_rad = io::stage::kPi / 6.0;
  // (ours) height of the CoM above the coils' mid-plane. 0 = the paper's A
  // matrix (in-plane forces produce no tilt torque); > 0 adds the physical
  // tilt torque of in-plane thrust.
  double com_above_coil_midplane_m = 0.0;
  double gravity_m_per_s2 = io::stage::kGravity_m_per_s2;
  bool gravity_enabled = true;
};

// --- Per-forcer imperfections, paper 003 eqs (11)-(13), (17)-(19) ----------
// Forcer f (0: coils 1&2, 1: 3&4, 2: 5&6, 3: 7&8).
struct ForcerErrors {
  double epsilon_tangential[kForcers] = {0, 0, 0, 0};  // F_t -> F_t (1 + eps), eqs (17)-(19)
  double epsilon_off_axis_z[kForcers] = {0, 0, 0, 0};  // dF_z = eps F_t, eqs (11)-(13)
  double misalignment_rad[kForcers] = {0, 0, 0, 0};    // in-plane rotation of the coil pair
};

// --- Out-of-plane suspension, eqs (29)-(31) --------------------------------
// Four vertical spring-dampers (k/4, c/4) at the forcer centres (+-l, 0),
// (0, +-l): exactly the paper's "four parallel supports", which gives
// k_torsional = (k/2) l^2 and c_torsional = (c/2) l^2 (eq 31).
struct SuspensionConfig {
  bool enabled = true;
  double stiffness_N_per_m = io::stage::kZStiffness_N_per_m;
  double damping_Ns_per_m = io::stage::kZDamping_Ns_per_m;
  double neutral_height_m = io::stage::kNominalHeight_m;  // zero spring force here
  // (ours) The identified k is the TOTAL z stiffness at the levitated point,
  // which physically includes the magnetic gradient of the levitating force
  // (dF/dz = -gamma_1 m g, i.e. +gamma_1 m g of stiffness). If true the spring
  // is softened by gamma_1 * m * g so that the linearized plant equals (29)-(31).
  bool subtract_magnetic_stiffness = true;
};

// --- Landing contact (ours) ------------------------------------------------
// One-sided stiff damped contacts at the 4 frame corners (143 mm frame),
// with regularized Coulomb friction in the plane.
struct ContactConfig {
  bool enabled = true;
  double corner_half_size_m = 0.0715;
  double stiffness_N_per_m = 5.0e6;  // per corner
  double damping_Ns_per_m = 1.0e3;   // per corner
  double friction_coefficient = 0.1;
  double friction_velocity_m_per_s = 1e-3;  // tanh-like regularization speed
};

// --- Amplifiers: 8 linear current amplifiers (PA12A-like) ------------------
struct AmplifierConfig {
  double dac_full_scale_V = io::stage::kDacFullScale_V;
  double gain_A_per_V = io::stage::kAmplifierGain_A_per_V;
  double coil_resistance_Ohm = io::stage::kCoilResistance_Ohm;
  double coil_inductance_H = io::stage::kCoilInductance_H;
  // (ours) PI current loop whose zero cancels the coil pole R/L; the closed
  // loop is first order with bandwidth K/(2 pi L), K = loop transresistance.
  // 1.8535 V/A -> 5.0 kHz.
  double loop_transresistance_V_per_A = 1.8535;
  double supply_voltage_V = 24.0;   // (ours) +-24 V rails
  double output_dropout_V = 4.0;    // (ours) PA12A output swing: rails - 4 V
  double current_limit_A = 5.0;     // (ours) = DAC full scale * gain
  double gain_error[kCoils] = {0, 0, 0, 0, 0, 0, 0, 0};  // fraction
  double offset_A[kCoils] = {0, 0, 0, 0, 0, 0, 0, 0};
  // As built (docs/PLANT.md "Error sets"): per-amplifier current-loop
  // bandwidth error, fraction (the loop's RC parts' tolerance). 0 = nominal.
  double bandwidth_error[kCoils] = {0, 0, 0, 0, 0, 0, 0, 0};
  // --- Noise (docs/BENCH.md "Amplifier current noise") --------------------
  // Two separate things, because paper 003 Table 1 reports the std of the
  // MEASURED current (monitor chain included, bandwidth unknown), while what
  // moves the platen is only the force-producing, in-band current noise.
  //
  // Force-producing current noise: white, additive (independent of the
  // current), one sample per servo tick (zero-order hold, then the current
  // loop), std = density * sqrt(bandwidth) * scale. The density is an
  // IDENTIFICATION: the value that gives paper 000's measured 3 nm rms x
  // rest noise under the paper's gains (eq 27) on this bench.
  double current_noise_density_A_per_rtHz = 10.0e-6;
  double current_noise_bandwidth_Hz = 0.5 * io::stage::kServoRate_Hz;  // one-sided band of per-tick samples
  double current_noise_scale = 1.0;  // multiplier on the density (scenario key; 0 = off)
  double monitor_gain_V_per_A = io::stage::kCurrentMonitorGain_V_per_A;
  // Current MONITOR channel: the reported current's std about the command
  // reproduces paper 003 Table 1 (interpolated at |commanded|): the monitor
  // chain adds sqrt(Table1^2 - force-noise std^2) of its own white noise.
  bool monitor_reproduces_table1 = true;
  double monitor_noise_A = 0.0;  // extra rms monitor noise (used on top; 0 by default)
};

// --- Sensors ---------------------------------------------------------------
struct BeamLossEvent {
  int axis = 0;          // 0: x, 1: y1, 2: y2
  double start_s = 0.0;  // loss for start_s <= t < end_s
  double end_s = 0.0;
};

// One kind of sensor's noise, rms per sample, white (the interferometers'
// beams, the laser displacement sensors' heights): noise_m is the kind's
// figure, every sensor's unless sensor_noise_m gives the sensor its own.
template <std::size_t kSensors, double kDefaultNoise_m>
struct SensorNoise {
  double noise_m = kDefaultNoise_m;
  // The stage's own sensors' figures, sensor by sensor (a profile's `noise`,
  // each kind's sensors in order), rms per sample; 0 = not given. The
  // component noise models (nominal, as-built: ApplyComponentNoise) use them,
  // else the seed's parts' datasheet figure (docs/PLANT.md section 11).
  double component_noise_m[kSensors] = {};
  // Sensor k's rms per sample where > 0, else noise_m: the component models
  // set it sensor by sensor; set_noise_m() (one figure for the kind: the
  // `interferometer_noise_m` / `displacement_noise_m` keys, noise = fitted)
  // clears it.
  double sensor_noise_m[kSensors] = {};
  double noise_of(int k) const { return sensor_noise_m[k] > 0.0 ? sensor_noise_m[k] : noise_m; }
  void set_noise_m(double v) {
    noise_m = v;
    for (double& n : sensor_noise_m) n = 0.0;
  }
  // The component noise models' figures: each sensor's own where the profile
  // gives it, else the seed's part's (part_m); noise_m, what metrics.json
  // reports for the kind, is the largest of them.
  void use_component_figures(double part_m) {
    noise_m = 0.0;
    for (std::size_t k = 0; k < kSensors; ++k) {
      sensor_noise_m[k] = component_noise_m[k] > 0.0 ? component_noise_m[k] : part_m;
      noise_m = sensor_noise_m[k] > noise_m ? sensor_noise_m[k] : noise_m;
    }
  }
};

// noise_m: (ours) 0.5 nm rms per sample.
struct InterferometerConfig : SensorNoise<std::size_t{io::kInterferometerAxes}, 0.5e-9> {
  double wavelength_m = io::stage::kWavelength_m;
  int fold = io::stage::kInterferometerFold;
  int interpolation = io::stage::kInterferometerInterpolation;
  // Where the beams run (world frame): the x beam along X at y = x_beam_y_m,
  // the y1 and y2 beams along Y at x = y_beam_x_m[0], [1] (a profile's
  // interferometers, as the kernel's pose solver reads them), and the sign
  // each counts with (-1: a beam looking along -X or -Y counts down as the
  // stage moves +).
  double x_beam_y_m = 0.0;
  double y_beam_x_m[2] = {-io::stage::kYBeamSeparation_m / 2, +io::stage::kYBeamSeparation_m / 2};
  int sign[io::kInterferometerAxes] = {1, 1, 1};
  double mirror_distance_m = 0.0715;  // (ours) mirror faces at the frame edge
  // (ours) beam height above the platen CoM (Abbe arm for tilts).
  double beam_height_m = 0.0;
  // Counter values at the reference pose (x = y = theta = 0): arbitrary,
  // chosen next to the unsigned and signed 32-bit wraps.
  std::uint32_t start_count[io::kInterferometerAxes] = {4294967040u, 2147483520u, 123456789u};
  std::vector<BeamLossEvent> beam_loss_events;
};

// noise_m: (ours) 5 nm rms per sample.
struct DisplacementConfig : SensorNoise<std::size_t{io::kDisplacementSensors}, 5e-9> {
  double scale_m_per_V = io::stage::kDisplacementScale_m_per_V;
  double zero_height_m = io::stage::kDisplacementZeroHeight_m;
  double sensor_x_m[io::kDisplacementSensors] = {io::stage::kDisplacementSensorX_m[0],
                                                 io::stage::kDisplacementSensorX_m[1],
                                                 io::stage::kDisplacementSensorX_m[2]};
  double sensor_y_m[io::kDisplacementSensors] = {io::stage::kDisplacementSensorY_m[0],
                                                 io::stage::kDisplacementSensorY_m[1],
                                                 io::stage::kDisplacementSensorY_m[2]};
};

struct HallConfig {
  double a_x_m = io::stage::kHallAX_m;
  double a_y_m = io::stage::kHallAY_m;
  double b_x_m = io::stage::kHallBX_m;
  double b_y_m = io::stage::kHallBY_m;
  double height_above_magnets_m = io::stage::kHallHeightAboveMagnets_m;  // at rest
  double sensitivity_V_per_T = io::stage::kHallSensitivity_V_per_T;
  // (ours) 0.3 mT rms: the 6 um rms Hall position noise of paper 000's
  // ref. [18] at gamma_1 * c_1 = 51 T/m.
  double noise_T = 0.3e-3;
};

struct AdcConfig {
  double full_scale_V = io::stage::kAdcFullScale_V;
};

// --- As-built geometry (docs/PLANT.md "Error sets") -----------------------
// How the built stage differs from the geometry the kernel assumes. Every
// field 0 = the nominal stage (and the plant's arithmetic is then exactly
// that of the nominal stage: the terms are applied only when `active`).
// Drawn from an error set by DrawAsBuilt (as_built.hpp), never hand-set to a
// result.
struct AsBuiltConfig {
  bool active = false;
  // Coils (cross and square layouts).
  double coil_shift_m[kCoils] = {};         // along its array axis: a commutation phase error
  double coil_roll_rad[kCoils] = {};        // about the side's length: turns (F_t, F_z)
  double forcer_lever_offset_m[kForcers] = {};  // forcer centre, away from the platen centre
  double forcer_bstar_error[kForcers] = {};     // b* of the forcer, fraction (both components)
  // Platen: CoM offset from the geometric centre (x, y; the height is
  // BodyConfig::com_above_coil_midplane_m) and the products of inertia.
  double com_offset_m[2] = {};
  double products_of_inertia_kgm2[3] = {};  // Ixy, Ixz, Iyz
  // Magnet array: pitch error, fraction (the plant's field pitch vs the kernel's).
  double magnet_pitch_error = 0.0;
  // Metrology: mirror normals in the platen frame turn by these angles.
  double x_mirror_yaw_rad = 0.0;    // in-plane: orthogonality to the y mirror
  double x_mirror_pitch_rad = 0.0;  // out of plane
  double y_mirror_roll_rad = 0.0;   // out of plane
  double mirror_bow_m = 0.0;        // flatness: bow at the mirror's ends (+-half length)
  double mirror_half_length_m = 0.05;
  double y_beam_separation_error_m = 0.0;
  // Laser displacement sensors' target (the magnet matrix top): a height
  // offset per 12.7 mm square cell, from a hash of (target_seed, i, j),
  // uniform in +-target_cell_height_m. Zeroed at the home pose (the sensors
  // are set at their working distance on the stage as built).
  double target_cell_height_m = 0.0;
  double target_cell_m = 12.7e-3;
  std::uint64_t target_seed = 0;
};

// --- Integration -------------------------------------------------------------
struct IntegrationConfig {
  double servo_rate_Hz = io::stage::kServoRate_Hz;
  int substeps_per_tick = 2;  // RK4 sub-steps inside each servo tick (200 us at 2.5 kHz)
  // kFast (issue 16, docs/PERFORMANCE.md "Bench speed"): RK4 with the
  // amplifier's closed-form current integrated exactly (Amplifiers::
  // RkCurrent) and one sub-step per tick while the platen's corners are
  // clear of the landing surface by more than they can close in two ticks;
  // substeps_per_tick otherwise (the landed contact, 5 MN/m per corner, needs
  // the 200 us step: its tilt mode is outside RK4's stability region at
  // 400 us). kClassic: substeps_per_tick everywhere with the currents sampled
  // at 0, h/2, h (the integrator before; with substeps_per_tick = 64 the
  // accuracy reference).
  enum class Method { kFast, kClassic };
  Method method = Method::kFast;
  // kFast, forcer-lane field (Plant::MagneticLanesBody): RK4 stage 1 takes
  // its reference sides' sin/cos/exp from the previous sub-step's stage 1 by
  // angle addition (the platen moves < 0.2 mm a sub-step: gamma_1 ds < 0.02,
  // the Taylor branch; further, the library's sin/cos of the step), and from
  // the library once every field_chain_substeps sub-steps, which bounds the
  // round-off carried along the chain (~3e-16 relative a link: < 2e-14
  // after 64). 1: the library at every stage 1 (the form before). The Hall
  // sensors' field (Plant::sample) the same way, from the previous sample,
  // the library every field_chain_substeps samples.
  int field_chain_substeps = 64;
};

// Initial state (world frame fixed to the magnets; z above landed rest).
struct InitialState {
  double position_m[3] = {0, 0, 0};
  double angles_rad[3] = {0, 0, 0};  // theta_x, theta_y, theta_z
};

struct PlantConfig {
  FieldConfig field;
  BodyConfig body;
  ForcerErrors forcer_errors;
  SuspensionConfig suspension;
  ContactConfig contact;
  AmplifierConfig amplifier;
  InterferometerConfig interferometer;
  DisplacementConfig displacement;
  HallConfig hall;
  AdcConfig adc;
  IntegrationConfig integration;
  InitialState initial;
  AsBuiltConfig as_built;
  // The floor under the stage's base (floor_vibration.hpp; `[plant] floor`);
  // none by default.
  FloorVibrationConfig floor;
  bool sensor_noise_enabled = true;
  // How the noise's normal draws are made (rng.hpp; `[plant] noise_generator`):
  // kZiggurat (issue 16, 4x cheaper) or kPolar (std::normal_distribution,
  // the realization of every seed before; the pinned pre-issue-15 digests).
  NormalMethod noise_generator = NormalMethod::kZiggurat;

  // The bench default: ideal + small realistic imperfections (docs/PLANT.md).
  static PlantConfig Default();
  // Paper-ideal: no noise, no amplifier/forcer errors (tests, linearization).
  static PlantConfig Ideal();
  // A stage's plant as drawn: without Default()'s hand-set forcer and
  // amplifier errors and without the as-built block; its noise as it was.
  // For a profile's plant before any error set is drawn (DrawAsBuilt also
  // moves geometry -- sensor places, Abbe offsets -- which this keeps).
  static PlantConfig AsDrawn(const PlantConfig& stage);
  // Ideal() for a stage's own plant (its profile's geometry and sensors):
  // `[plant] model = ideal` / `--plant ideal` on any stage. Ideal() is
  // IdealOf(PlantConfig{}).
  static PlantConfig IdealOf(const PlantConfig& stage);
};

}  // namespace maglev::hil
