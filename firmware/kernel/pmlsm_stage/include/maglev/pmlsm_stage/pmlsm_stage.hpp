// Paper 002's stage family (iron-cored PMLSMs, Fulford, Maggiore & Apkarian
// 2009) in the firmware kernel: its inputs, outputs and configuration.
//
// Data path of one tick (pmlsm_controller.hpp):
//   encoder counts -> pose y = [x1 x3 x5 x7 x9] -> five internal-model
//   regulators (14)-(16) -> w -> feedback linearization (12) + input
//   transformation (8) -> (i_d, i_q) per motor -> commutation (inverse Park)
//   -> phase currents -> DAC codes.
//
// Axis order is the paper's output order of (13): the air gap x1 (what the
// vertical encoders read), X x3, Z x5, the rotation about X (phi, x7) and
// about Z (theta, x9). A stage profile names them z, x, y, theta_x, theta_y
// (docs/STAGES.md, "Paper 002's axes"); yaw is blocked by the guides.
//
// Everything here is plain data: the configuration arrives computed (the
// LQR gains, the internal model's ZOH matrices and the force-law tables are
// solved on the host from the profile, host-tools/control_design), so the
// tick needs no libm and runs bit for bit alike on the host and the M7.
#pragma once

#include <cstdint>

namespace maglev::pmlsm_stage {

inline constexpr int kAxes = 5;
enum class Axis : std::uint8_t { kGap = 0, kX = 1, kZ = 2, kPhi = 3, kTheta = 4 };
inline constexpr int kMotors = 4;
// Two DAC channels per motor: phases a and b. The windings are star
// connected (docs/PAPER-002.md), so phase c carries -(a + b): the amplifier
// board drives it as the return. Channel 2m is motor m+1's phase a, 2m+1 its b.
inline constexpr int kDacChannels = 8;

// status_flags: a set bit means "this input is NOT trustworthy".
enum SensorStatusBit : std::uint16_t {
  kEncoderLoss0 = 1u << 0,  // gap encoder: signal / index lost
  kEncoderLoss1 = 1u << 1,  // X
  kEncoderLoss2 = 1u << 2,  // Z
  kEncoderLoss3 = 1u << 3,  // phi
  kEncoderLoss4 = 1u << 4,  // theta
  kStaleFrame = 1u << 7,    // transport: the sample repeats the previous one
};
inline constexpr std::uint16_t kAnyEncoderLoss = 0x1Fu;

struct SensorSample {
  // Quadrature counts of the linear encoders (x1, x3, x5) and of the rotation
  // outputs (x7, x9), zeroed so that count 0 is the pose 0 of (13) (the gap
  // encoder reads the air gap itself). 10 um / 20 urad per count on the rig.
  std::int32_t encoder_counts[kAxes];
  std::uint16_t status_flags;
};

struct ActuatorCommand {
  std::int16_t dac_code[kDacChannels];
  bool amplifier_enable;
};
inline constexpr ActuatorCommand kSafeActuatorCommand{{0, 0, 0, 0, 0, 0, 0, 0}, false};

// Per-motor gap functions of (2)-(4), sampled on a uniform grid of the air
// gap and interpolated linearly in the tick. Computed on the host in double
// from the profile's [pmlsm] section. The functions fall off with a length
// scale of tau / (2 pi) = 9 mm, so linear interpolation errs by about
// h^2 / 8 / (9 mm)^2. The table spans every gap a motor can see (the
// stops, widened by the tilts: 12.4-36.6 mm for paper 002); at 481 points
// (0.05 mm) the error is below 1e-5 relative (the unit test asserts it).
// 7.7 kB of configuration.
inline constexpr int kGapTablePoints = 481;
struct ForceLawTable {
  float gap0_m;            // gap of point 0
  float step_m;            // grid spacing
  float attraction_N[kGapTablePoints];        // K_v1 L_v1(g): PM attraction (closes the gap)
  float direct_N_per_A[kGapTablePoints];      // K_v2 L_v2(g): vertical force per unit i_d
  float quadratic_N_per_A2[kGapTablePoints];  // K_v3 L_v3(g): attraction per (i_d^2 + i_q^2)
  float thrust_N_per_A[kGapTablePoints];      // K_h L_h(g): horizontal force per unit i_q
};

// One internal-model regulator (14)-(16): w = Ks [e e' xi1 xi2 xi3] + xi1.
struct RegulatorConfig {
  float Ks[5];
  float E[3];       // anti-windup (17): xi' += E (sat(u) - u); zero = none
  bool closed;      // false: w = 0 on this axis (the paper's 3-DOF test runs phi, theta open)
  std::uint8_t reserved[3];
};

struct PmlsmKernelConfig {
  float servo_rate_Hz;
  float encoder_resolution[kAxes];  // m or rad per count
  ForceLawTable force;
  // Rigid body (5)-(7): levitated mass, mover masses on the X / Z guides,
  // inertias, radius to the movers, guide torsion per inertia, gravity.
  float mass_gap_kg, mass_x_kg, mass_z_kg;
  float inertia_phi_kgm2, inertia_theta_kgm2;
  float radius_m;
  float torsion_phi_per_s2, torsion_theta_per_s2;
  float gravity_m_per_s2;
  // Commutation: electrical turn fraction per encoder count of the X and Z
  // axes, theta_e = pi s / tau -> phase = s / (2 tau) * 2^32.
  std::uint32_t phase_per_count_x;
  std::uint32_t phase_per_count_z;
  // Internal model xi' = Phi xi + input, ZOH over one period:
  // xi_{k+1} = xi_k + (Ad - I) xi_k + Bd input_k, input = N e + E (sat(u) - u),
  // N = [0 0 1]. Stored as Ad - I: Ad's diagonal is 1 - O((w0 T)^2), and
  // float cannot hold 1 - 1e-5 to better than 0.5 %, which would move the
  // resonator off w0 (measured: 2.6 um instead of 0.5 um X tracking error
  // at 1 kHz, 18 um at 5 kHz); the small increments keep full precision.
  float xi_Ad_minus_I[3][3];
  float xi_Bd[3][3];
  RegulatorConfig axis[kAxes];
  // Derivative estimate e' = wf (e - f), f += alpha (e - f) (the paper's
  // "linear filter" on the error).
  float derivative_filter_rad_per_s;
  float derivative_filter_alpha;
  // Ours, off in the paper's reproduction: invert (2) with its i_d^2 term
  // instead of (11)'s linear model (the i_d^2 terms (11) drops dominate the
  // bench's gap tracking error, docs/PAPER-002.md).
  bool exact_vertical_inverse;
  std::uint8_t reserved[3];
  float horizontal_limit_A;  // sat_7 of (17) on u_x, u_z
  float phase_peak_A;        // every commanded phase current stays inside (vector scaled)
  float amps_per_dac_code;   // amplifier transconductance x DAC LSB
  // References: the operating range (1) of Section IV-A; commands outside are refused.
  float reference_min[kAxes];
  float reference_max[kAxes];
  float rest_gap_m;          // the platen rests on its stops here (amplifiers off)
  float nominal_gap_m;       // lift-off ends here
  float lift_speed_m_per_s;  // lift-off / landing ramp of the gap reference
  float max_ramp_speed[kAxes];  // kMoveTo's speed bound (m/s, rad/s)
  // Supervision.
  float max_speed[kAxes];        // a count step implying more than this is a sensor fault
  float window_min[kAxes];       // pose outside [min, max] while levitated: fault
  float window_max[kAxes];
  std::uint32_t max_saturated_ticks;  // the phase clamp acting this long in a row: fault
  std::uint32_t max_stale_ticks;
};

}  // namespace maglev::pmlsm_stage
