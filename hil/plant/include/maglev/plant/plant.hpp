// The HIL physical plant: the 6-DOF maglev platen over the Halbach magnet
// matrix (paper 000), its eight current amplifiers and its sensors. It talks
// to the controller ONLY through io::SensorSample and io::ActuatorCommand.
//
// Per servo tick (period 1 / servo_rate_Hz) the bench calls, in this order:
//   1. io::SensorSample s = plant.sample();  // sensors at the tick start
//   2. plant.apply(command);                 // DAC codes + enable, held (ZOH)
//   3. plant.advance_tick();                 // = advance(1 / servo_rate_Hz)
// advance(dt) integrates with fixed-step RK4 (IntegrationConfig: one sub-step
// per servo period while levitated, substeps_per_tick near or on the landing
// surface); amplifier currents are integrated in closed form inside it.
// Given (config, seed, command sequence) a run is bit-for-bit deterministic.
//
// Frames (maglev/io/stage_parameters.hpp): world XYZ fixed to the magnets,
// Z up, X/Y origin at a phase zero of the Halbach fundamental; the state's
// position is the platen CoM's (x, y) and z = height above the landed rest
// position (air gap = rest gap + z at the coils). Attitude R = Rz Ry Rx
// (theta_x, theta_y, theta_z about +X, +Y, +Z), kept as a unit quaternion.
#pragma once

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "maglev/plant/amplifier.hpp"
#include "maglev/plant/floor_vibration.hpp"
#include "maglev/plant/halbach_field.hpp"
#include "maglev/plant/plant_config.hpp"
#include "maglev/plant/rng.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::hil {

// Rigid-body state: CoM position relative to its landed-rest position
// (x, y absolute in the magnet frame), world velocity, attitude, body rates.
struct BodyState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_m_per_s = Eigen::Vector3d::Zero();
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();
  Eigen::Vector3d omega_body_rad_per_s = Eigen::Vector3d::Zero();
};

struct BodyDerivative {
  Eigen::Vector3d velocity_m_per_s;
  Eigen::Vector3d acceleration_m_per_s2;       // world
  Eigen::Vector4d attitude_rate;               // d/dt (w, x, y, z)
  Eigen::Vector3d angular_acceleration_body;   // rad/s^2
};

// Force (world frame, at the CoM) and torque (body frame, about the CoM).
struct Wrench {
  Eigen::Vector3d force_world_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_body_Nm = Eigen::Vector3d::Zero();
};

// What the bench and the tests may read; never visible to the controller.
struct PlantState {
  double time_s = 0.0;
  double position_m[3] = {};        // x, y, z (z above landed rest)
  double angles_rad[3] = {};        // theta_x, theta_y, theta_z
  double velocity_m_per_s[3] = {};  // world
  double omega_body_rad_per_s[3] = {};
  double coil_current_A[kCoils] = {};
  double coil_commanded_A[kCoils] = {};  // gain * V_dac, before errors/noise
  bool amplifier_enable = false;
  double contact_force_N = 0.0;  // sum of the corner normal forces
  bool in_contact = true;        // at least one corner touching
  double magnetic_force_world_N[3] = {};
  double magnetic_torque_body_Nm[3] = {};
};

// One straight coil side (effective length p) in the platen frame.
struct CoilSide {
  int coil;                  // 0..7 (coil j+1 of paper 000); -1: no such side (triangle: coils 7, 8)
  int forcer;                // 0..3 (coil pairs 1&2, 3&4, 5&6, 7&8)
  int array_axis;            // 0: sees the X array (side along Y'), 1: the Y array, -1: both (triangle)
  Eigen::Vector3d r_body_m;  // midpoint of the cross-section centre line
  Eigen::Vector3d u_body;    // unit direction of positive coil current
  // Nominal phase offset from the forcer's first side, in quarter pitches
  // (the forcer's sides are L/4 apart): lets the force loop derive every
  // side's sin/cos from one sincos per forcer.
  int quarter_turns;
};

// Rotation and rates evaluated once per derivative (plain arrays: the 3x3
// products stay inlined in the hot loop).
struct Kinematics {
  double r[3][3];
  double p[3];
  double v[3];
  double omega_w[3];
};

class Plant {
 public:
  Plant(const PlantConfig& config, std::uint64_t seed);

  // --- per-tick interface (the only path to/from the controller) ----------
  io::SensorSample sample();
  void apply(const io::ActuatorCommand& command);
  void advance(double dt_s);
  void advance_tick() { advance(tick_s_); }
  // Ground truth. The magnetic/contact wrench fields are derived lazily (the
  // bench's per-tick path never needs them).
  const PlantState& truth() const {
    if (truth_wrench_stale_) RefreshTruthWrench();
    return truth_;
  }

  // --- model access (tests, bench diagnostics) ----------------------------
  const PlantConfig& config() const { return config_; }
  const HalbachField& field() const { return field_; }
  const Amplifiers& amplifiers() const { return amplifiers_; }
  const BodyState& body_state() const { return body_; }
  void set_body_state(const BodyState& state);
  // Force the coil currents (e.g. an equilibrium for a test).
  void set_coil_currents(const std::array<double, kCoils>& currents_A);
  // Manual beam loss (in addition to the configured events).
  void set_beam_loss(int axis, bool lost);
  // A force on the platen's centre of mass from outside (world frame, N):
  // the fault campaign's push and payload change. Zero: none (the default
  // path is untouched, bit for bit).
  void set_external_force(const Eigen::Vector3d& force_world_N);
  // Another integrator from the next advance() on (accuracy comparisons:
  // plant-integrator-accuracy; the servo rate stays).
  void set_integrator(IntegrationConfig::Method method, int substeps_per_tick) {
    config_.integration.method = method;
    config_.integration.substeps_per_tick = substeps_per_tick;
    lane_chain_left_ = 0;  // the next stage 1 from the library
  }

  double mass_kg() const { return mass_; }
  const Eigen::Vector3d& inertia_kgm2() const { return inertia_; }
  double tick_s() const { return tick_s_; }
  double suspension_stiffness_N_per_m() const { return k_susp_; }
  const std::array<CoilSide, 2 * kCoils>& coil_sides() const { return sides_; }

  // Lorentz force of one coil (both sides), world frame, for a given current.
  Eigen::Vector3d CoilForceWorld(const BodyState& state, int coil, double current_A) const;
  // Magnetic wrench of all coils.
  Wrench MagneticWrench(const BodyState& state, const double* currents_A) const;
  // Total wrench: magnetic + suspension + contact + gravity.
  Wrench TotalWrench(const BodyState& state, const double* currents_A) const;
  BodyDerivative Derivative(const BodyState& state, const double* currents_A) const;
  // Kinetic energy (translation + rotation), J.
  double KineticEnergy(const BodyState& state) const;

  static Eigen::Matrix3d RotationFromAngles(double theta_x, double theta_y, double theta_z);
  static Eigen::Vector3d AnglesFromRotation(const Eigen::Matrix3d& r);

 private:
  struct ContactResult {
    Wrench wrench;
    double normal_N;
    bool touching;
  };
  // Force (world) and torque (world, about the CoM) accumulators.
  struct Accum {
    double f[3];
    double t[3];
  };
  void AddMagnetic(const Kinematics& k, const double* currents_A, Accum* acc) const;
  // AddMagnetic's cross/square loop, four forcers at a time (bit-identical);
  // one body compiled for AVX and for the baseline x86-64 (SSE2).
  void AddMagneticLanesAvx(const Kinematics& k, const double* currents_A, Accum* acc) const;
  void AddMagneticLanesBase(const Kinematics& k, const double* currents_A, Accum* acc) const;
  void MagneticLanesBody(const Kinematics& k, const double* currents_A, Accum* acc) const;
  // Triangle layout: every side over both arrays (its own loop, so that the
  // cross and square keep their arithmetic bit for bit).
  void AddMagneticOblique(const Kinematics& k, const double* currents_A, Accum* acc) const;
  void BuildTriangleSides();
  // Cross and square: every side along one array (paper 000 eq (18)).
  void BuildArraySides();
  // Forcer centre and unit thrust axis (platen frame) of the triangle's forcer f.
  void TriangleForcer(int f, double centre[2], double thrust[2]) const;
  void AddSuspension(const Kinematics& k, Accum* acc) const;
  // One suspension spring-damper: its attachment (platen frame, about the
  // CoM) and constants, fixed per run (BuildSprings).
  struct Spring {
    double rb[3];
    double k_N_per_m;
    double c_Ns_per_m;
  };
  void BuildSprings();
  void AddContact(const Kinematics& k, Accum* acc, double* normal_N, bool* touching) const;
  bool ClearOfSurface(double dt_s) const;
  static Wrench ToWrench(const Kinematics& k, const Accum& acc);
  ContactResult ContactWrench(const BodyState& state) const;
  void UpdateTruth();
  void UpdateTruthCurrents();
  void RefreshTruthWrench() const;
  double InterferometerDisplacement(int axis) const;

  PlantConfig config_;
  HalbachField field_;
  Amplifiers amplifiers_;
  Rng rng_;
  BodyState body_;
  mutable PlantState truth_;
  mutable bool truth_wrench_stale_ = true;
  std::array<CoilSide, 2 * kCoils> sides_{};
  // The same sides as flat constants for the force loop: no Eigen, no
  // branches (the quarter-turn rotation as exact 0/+-1 factors).
  struct SideConstants {
    double rb[3];        // r_body_m
    double ux, uy;       // u_body (u_z = 0)
    double qc, qs;       // cos, sin of q_half_pi (exactly 0 or +-1 for whole quarter turns)
    double q_half_pi;    // phase offset from the reference side: quarter_turns * pi/2, or
                         // gamma_1 (rb - rb_ref) along the array where they differ
    double sel_x, sel_y;      // 1 for the tangential axis (X' or Y'), else 0
    double eps_t_x, eps_t_y;  // the forcer's paper-003 tangential error on X' / Y'
    double eps_z;             // its off-axis vertical error
    double gain;              // as built: 1 + the forcer's b* error
    double roll;              // as built: the coil's roll (turns (F_t, F_z))
    int ax;
    int coil;
  };
  std::array<SideConstants, 2 * kCoils> side_constants_{};
  // The same 16 sides as 4 lanes (one per forcer) x 4 positions (the
  // forcer's reference side first): the force loop evaluates the four
  // forcers' sides together in SIMD registers, lane by lane the same
  // operations in the same order as the one-side-at-a-time loop, so the
  // results are identical bit for bit (plant.cpp, MagneticLanes).
  struct SideLanes {
    double rb0[4], rb1[4], rb2[4];
    double ux[4], uy[4];
    double qc[4], qs[4], q_half_pi[4];
    double sel_x[4], sel_y[4], eps_t_x[4], eps_t_y[4], eps_z[4];
    double gain[4], roll[4];
    int coil[4];
  };
  std::array<SideLanes, 4> side_lanes_{};
  // kFast (advance): the reference sides' values at RK4 stage 1, from which
  // stages 2-4 derive theirs (MagneticLanesBody). kLibrary everywhere else.
  // Stage 1 itself: kStore (the library) or kChain (derived from the stored
  // previous stage 1, then stored), IntegrationConfig::field_chain_substeps.
  enum class LaneRefMode { kLibrary, kStore, kFromStore, kChain };
  int lane_chain_left_ = 0;  // stage 1s left to derive before the library again
  // A chain's countdown (lane_chain_left_, hall_chain_.left): true when this
  // value comes from the library (and the count restarts), false when it is
  // derived from the previous one (IntegrationConfig::field_chain_substeps).
  bool ChainAnchor(int* left) const;
  mutable LaneRefMode lane_ref_mode_ = LaneRefMode::kLibrary;
  struct LaneRefStore {
    double s[4], gap[4], sin[4], cos[4], exp[4];
  };
  mutable LaneRefStore lane_ref_store_{};
  std::array<Spring, 4> springs_{};
  int spring_count_ = 0;
  // The four springs (cross / square) by field, one lane per spring:
  // rb[0], rb[1], rb[2], k, c (AddSuspension's vector form).
  double spring_lanes_[5][4] = {};
  int lane_axis_[4] = {};      // array axis of forcer f (lane f)
  bool lanes_ok_ = false;      // four sides per forcer on one array axis, 4 harmonics
  bool lanes_avx_ = false;     // the CPU has AVX: 4 lanes per instruction (else 2 x SSE2)
  // Triangle layout: the 12 oblique sides of coils 1-6.
  struct ObliqueSide {
    double rb[3];                // midpoint, platen frame
    double ux, uy;               // positive current direction, platen frame
    double hx, hy;               // the forcer's thrust axis (tangential errors act along it)
    ObliqueSideAmplitudes amp;   // both arrays' side-averaged harmonics for this direction
    double eps_t, eps_z;         // the forcer's paper-003 errors
    int coil;
  };
  static constexpr int kTriangleForcers = 3;
  std::array<ObliqueSide, 2 * 2 * kTriangleForcers> oblique_sides_{};
  bool triangle_ = false;
  bool forcer_errors_active_ = false;
  // As built (config_.as_built.active): the branches below are taken only
  // then, so the nominal and default plants keep their arithmetic bit for bit.
  bool as_built_ = false;
  bool full_inertia_ = false;
  Eigen::Matrix3d inertia_matrix_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d inertia_inverse_ = Eigen::Matrix3d::Zero();
  double interferometer_zero_[io::kInterferometerAxes] = {};
  double target_home_m_[io::kDisplacementSensors] = {};
  double AsBuiltInterferometer(int axis) const;
  double TargetHeight(double x_m, double y_m) const;

  double mass_;
  Eigen::Vector3d external_force_N_ = Eigen::Vector3d::Zero();
  bool external_force_active_ = false;
  // Floor vibration (config.floor): the base's motion as the inertial force
  // -m u'' on the CoM (x, y, world), held over each tick.
  FloorVibration floor_;
  double floor_force_N_[FloorVibration::kAxes] = {};
  Eigen::Vector3d inertia_;
  double tick_s_;
  double side_force_per_A_;  // N * p
  double k_susp_;
  double com_arm_m_;

  // Interferometer counters.
  double lsb_m_;
  std::int64_t counter_adjust_[io::kInterferometerAxes] = {};
  // The Hall sensors' field phases (sensor A, B; along x, y) and decays at
  // the last sample: sample() derives the next ones by angle addition
  // (IntegrationConfig::field_chain_substeps samples, then the library).
  struct HallChain {
    double th[2][2], sin[2][2], cos[2][2];  // gamma_1 s and its sin/cos
    double height[2], decay[2];              // exp(-gamma_1 height)
    int left = 0;                            // samples left to derive
  };
  HallChain hall_chain_{};
  std::int64_t last_count_[io::kInterferometerAxes] = {};
  bool lost_prev_[io::kInterferometerAxes] = {};
  bool manual_loss_[io::kInterferometerAxes] = {};
};

}  // namespace maglev::hil
