// A stage profile: everything the controller and the bench need to know about
// one maglev stage, as plain data (no heap, no pointers, constexpr-able), so
// one firmware image can carry a database of them and the bench can build its
// plant from the very same record. The text form (hil/profiles/*.profile,
// docs/STAGES.md) is parsed on the host into this struct; the firmware gets
// the generated database (stage_database.hpp) and selects one by register.
//
// The format expresses the three seed families -- two-phase Lorentz forcers
// over a Halbach array (paper 000/003), iron-cored PMLSMs with attraction
// (paper 002), solenoids over permanent magnets (paper 001) -- with passive
// axes, several controller structures and gain schedules. Which of them this
// firmware can RUN is a separate question that the validator answers
// (ProfileError::kUnsupportedFamily, ...): never silently.
#pragma once

#include <cstdint>

#include "maglev/io/enum_names.hpp"

namespace maglev::stage_profile {

inline constexpr int kAxes = 6;          // kernel::Axis order: x, y, theta_z, z, theta_x, theta_y
inline constexpr int kMaxActuators = 12;
inline constexpr int kMaxSensors = 12;
inline constexpr int kMaxFilters = 2;
inline constexpr int kMaxSchedulePoints = 8;
inline constexpr int kMaxStartupSteps = 8;
inline constexpr int kNameLength = 24;
inline constexpr int kTitleLength = 96;

// Every value crosses a register or the generated database: explicit values.
enum class AxisMode : std::uint8_t {
  kActive = 0,   // closed loop
  kPassive = 1,  // left to the stage's own stiffness and damping (paper 001)
  kAbsent = 2,   // not a degree of freedom of this stage (constrained by guides)
};

enum class ActuatorFamily : std::uint8_t {
  kHalbachLorentz = 0,  // two-phase Lorentz forcer over a linear Halbach array (paper 000, 003)
  kIronCorePmlsm = 1,   // iron-cored PM linear synchronous motor, attraction + thrust (paper 002)
  kSolenoidMagnet = 2,  // air-core solenoid over a permanent magnet (paper 001)
};

// Placement of the Halbach family's four forcers (paper 003 eqs (6)-(8)).
enum class ForcerLayout : std::uint8_t { kCross = 0, kSquare = 1, kTriangle = 2, kCustom = 3 };

enum class SensorKind : std::uint8_t {
  kInterferometer = 0,     // counts; resolution = m per count
  kLaserDisplacement = 1,  // volts on the ADC; resolution = m per volt
  kHall = 2,               // coarse absolute position (homing)
  kLinearEncoder = 3,      // quadrature counts (paper 002: 10 um, 20 urad)
  kPsd = 4,                // position-sensitive detector on the ADC (paper 001)
};

enum class ControllerKind : std::uint8_t {
  kPid2Dof = 0,        // 2-DOF PID + biquads/notches (paper 000 eqs (27)-(33))
  kInternalModel = 1,  // internal-model regulator with anti-windup (paper 002 (14)-(17))
  kStateFeedback = 2,  // LQR-placed state feedback (paper 002)
  kNone = 3,           // a passive axis: no loop
};

enum class StartupStep : std::uint8_t {
  kEnd = 0,
  kCloseInPlane = 1,        // x, y, theta_z loops closed (paper 000 Sec. V)
  kLiftFeedforward = 2,     // feed-forward lift to the nominal height
  kCloseVertical = 3,       // z at low bandwidth
  kCloseTilts = 4,          // theta_x, theta_y
  kReady = 5,
  kLiftOffFromDock = 6,     // paper 001: ramp the nominal currents from the docking position
};

enum class FilterKind : std::uint8_t { kNone = 0, kNotch = 1, kLowPass = 2, kLeadLag = 3, kButterworth2 = 4 };

struct Filter {
  FilterKind kind;
  double frequency_Hz;
  double q;
  double depth_dB;
  double pole_Hz;
};

// One operating point of a gain schedule: gains = base gains * scale at the
// axis position `at` (m or rad); linear interpolation between points.
struct SchedulePoint {
  double at;
  double kp_scale;
  double kd_scale;
};

struct AxisController {
  ControllerKind kind;
  // 2-DOF PID (A of effort per m or rad).
  double kp, ki, kd, derivative_filter_Hz, setpoint_weight_p;
  double effort_limit_A;  // clamp of the loop output (A of effort)
  // Internal-model regulator (paper 002): omega0 and the anti-windup gain E.
  double imr_omega0_rad_per_s;
  // The Halbach family's internal-model regulator, designed by pole
  // placement on the axis plant: the closed loop's plant pole pair (w_c / 2
  // pi) and the internal model's poles (w_im / 2 pi), Hz; 0 = the family's
  // (20 Hz, 30 Hz on theta_z; 1.5 Hz). They were the seed's whatever the
  // profile said.
  double imr_bandwidth_Hz;
  double imr_model_bandwidth_Hz;
  double antiwindup_gain;
  bool feedback_linearization;
  // LQR weights of the internal-model design plant z = [e e' xi1 xi2 xi3]
  // (paper 002): Q = h' h (rank one), R = 1. The host solves the Riccati
  // equation (host-tools/control_design); the firmware receives gains.
  double lqr_weight_h[5];
  std::uint8_t filter_count;
  Filter filters[kMaxFilters];
  std::uint8_t schedule_points;
  SchedulePoint schedule[kMaxSchedulePoints];
};

struct Axis {
  AxisMode mode;
  double travel_min;  // m or rad (reference limits; the supervisor window adds a margin)
  double travel_max;
  double max_velocity;      // m/s or rad/s
  double max_acceleration;  // m/s^2 or rad/s^2
  // The stage's own linearized stiffness and damping per unit inertia on this
  // axis (1/s^2, 1/s): y'' + c y' + k y = g u. Paper 000 eqs (29)-(31) for z
  // and the tilts; paper 001 eq (13) for its passive axes. The checker's
  // passive eigenvalues and loop margins use them.
  double open_loop_stiffness_per_s2;
  double open_loop_damping_per_s;
  AxisController controller;
};

// One actuator (coil, motor, solenoid): centre in the platen frame, the
// direction of its horizontal thrust, and its electrical phase offset.
struct Actuator {
  double x_m, y_m, z_m;
  double thrust_direction_rad;  // 0 = +x
  double phase_rad;             // commutation offset (Halbach: 0 or +-pi/2 within a forcer)
};

struct Sensor {
  SensorKind kind;
  double x_m, y_m, z_m;
  double direction_rad;  // measuring direction in the plane (interferometers, encoders)
  double resolution;     // kind-specific unit (see SensorKind)
  double noise;          // rms, same unit as the measured quantity (m or rad)
  // A sensor that reads one axis directly (an encoder on a guide, paper
  // 002): that axis' index; kGeometricSensor = placed by its geometry.
  std::uint8_t measured_axis;
  // Hall sensors only (0 = the family's: the seed stage's 20 V/T at 1.6 mm).
  // ADC volts per tesla of each field component, and the sensor's height
  // above the magnets' surface with the platen at rest. With the array's
  // strength (two_b_star_N_per_A) they set the Hall ADC's swing, which
  // CheckStageProfile keeps off the rails (kHallSignalRange).
  double sensitivity_V_per_T;
  double height_m;
};
inline constexpr std::uint8_t kGeometricSensor = 255;

struct Body {
  double mass_kg;
  double inertia_kgm2[3];  // about x, y, z
  // Separate mover masses per axis (paper 002: guides carry extra masses);
  // 0 = the body's mass / inertia.
  double effective_mass_kg[kAxes];
  double gravity_m_per_s2;
};

// Halbach-family force law parameters (paper 000 eqs (1)-(20)).
struct HalbachParameters {
  ForcerLayout layout;
  double lever_arm_m;
  double triangle_alpha_rad;
  double pitch_m;
  double magnet_thickness_m;
  double two_b_star_N_per_A;  // identified 2 b*(z0), eq (29)
  double coil_effective_length_m, coil_side_width_m, coil_thickness_m;
  int coil_turns;
  double rest_gap_m;
};

// Iron-cored PMLSM force law parameters (paper 002 (1)-(4), Table I).
struct PmlsmParameters {
  double slot_width_m, slot_pitch_m, pole_pitch_m, magnet_height_m, coercivity_A_per_m;
  int turns_per_phase, magnets_per_motor, pole_pairs;
  double nominal_gap_m, min_gap_m, max_gap_m;
  double vertical_attraction_scale;  // K_v3 correction (NOTES-002-001), marked as ours in the profile
  // Added with paper 002's stage on the bench: the force law needs the
  // magnets' length and width, the winding factor and the recoil
  // permeability; (5)-(7) need the radius to the movers; the guides resist
  // the two tilts differently (the paper's ranges: 3 mrad about X, 14 about
  // Z), so one torsional stiffness could not describe them. Per unit
  // inertia (k_s of (7)), as the paper writes it.
  double magnet_length_m, magnet_width_m;
  double winding_factor, recoil_permeability;
  double radius_to_movers_m;
  double guide_torsion_phi_per_s2, guide_torsion_theta_per_s2;
};

// Solenoid-magnet force law parameters (paper 001 (1)-(9), Tables 1-2).
struct SolenoidParameters {
  double magnetization_A_per_m, magnet_volume_m3, solenoid_volume_m3, length_m;
  double radius_r1_m, radius_r2_m;
  double nominal_current_in_plane_A, nominal_current_out_of_plane_A;
  int turns_in_plane, turns_out_of_plane;
  double coil_resistance_Ohm;
  // Force per ampere of one coil on its magnet at the nominal position
  // (eq (13)'s k_ipi, k_opi): the controller's dynamic transform T and its
  // loop gains need them.
  double force_constant_in_plane_N_per_A, force_constant_out_of_plane_N_per_A;
};

struct Limits {
  double peak_current_A;        // per actuator
  double rms_current_A;         // thermal
  double hardware_current_A;    // what the amplifiers can do at all (profiles must stay inside)
  double landing_speed_m_per_s; // touchdown speed bound of the controlled landing
  double nominal_height_m;      // levitated operating point above rest (z)
};

struct StageProfile {
  char name[kNameLength];
  char title[kTitleLength];
  std::uint8_t paper;  // seed paper number (0, 1, 2, 3), 255 = a lab's own stage
  double servo_rate_Hz;
  Axis axis[kAxes];
  Body body;
  ActuatorFamily family;
  std::uint8_t actuator_count;
  Actuator actuators[kMaxActuators];
  HalbachParameters halbach;
  PmlsmParameters pmlsm;
  SolenoidParameters solenoid;
  std::uint8_t sensor_count;
  Sensor sensors[kMaxSensors];
  Limits limits;
  StartupStep startup[kMaxStartupSteps];
};

// Why a profile cannot run on this controller: value and text of each,
// defined once (the enum and to_string() are generated). The values cross
// Modbus (status.profile_error) and the fault record: append only.
#define MAGLEV_PROFILE_ERRORS(X) \
  X(kOk, 0, "ok") \
  X(kBadName, 1, "bad name") \
  X(kBadServoRate, 2, "servo rate outside 500..20000 Hz") \
  X(kNoActiveAxis, 3, "no active axis") \
  X(kAxisWithoutSensor, 4, "an active axis has no sensor that observes it") \
  X(kAllocationRank, 5, "allocation rank-deficient on the active axes") \
  X(kAllocationCondition, 6, "allocation ill-conditioned on the active axes") /* cond > 1e3 */ \
  X(kLimitsOutsideHardware, 7, "limits outside the hardware") /* current / travel / rate */ \
  X(kBadBody, 8, "mass or inertia not positive") \
  X(kUnsupportedFamily, 9, "actuator family not supported by this firmware") \
  X(kUnsupportedController, 10, "controller structure not supported by this firmware") \
  X(kBadStartup, 11, "start-up sequence not supported") \
  X(kUnstableLoop, 12, "a default loop is unstable") /* the loop check */ \
  X(kChecksum, 13, "checksum mismatch") /* the stored record's CRC */ \
  X(kUnknownProfile, 14, "no such profile") /* the selected index is not in the database */ \
  X(kUnsupportedSensors, 15, "sensor set not supported by this firmware's pose solver") \
  X(kBadActuatorParameters, 16, "actuator parameters missing or not positive") \
  X(kKernelRefused, 17, "the kernel refuses the configuration it yields") /* measurement or loop design */ \
  X(kHallSignalRange, 18, "a Hall sensor's signal would rail the ADC or is too weak") /* homing */ \
  X(kRegisterRange, 19, "a value outside the register map's range") /* the board's envelope: it could not be saved */ \
  X(kCount, 20, "?")

enum class ProfileError : std::uint8_t {
  MAGLEV_PROFILE_ERRORS(MAGLEV_ENUMERATOR)
};
const char* to_string(ProfileError e);

}  // namespace maglev::stage_profile
