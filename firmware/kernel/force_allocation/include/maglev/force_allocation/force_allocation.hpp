// force_allocation: control efforts U -> coil currents -> DAC codes.
//
//   eq (18)  A (6 x 8): forcer forces -> platen wrench [Fx Fy Tz Fz Tx Ty]
//   eq (21)  B = pinv(A), computed once per Config (double, no heap)
//   eq (23)  S_xy(x, y): the 8 x 8 commutation matrix WITHOUT its 1/b* factor
//   eq (24)  i = 2 S_xy B U           (U = [ux uy uthz uz uthx uthy], in A)
//   eq (22)  => wrench = 2 b*(z0) U   (b* only converts force <-> effort)
//
// Per tick (AllocateCurrents): G = B U (Scalar), integer commutation phases
// from the int64 pm position, 8 table sin/cos, i_j = 2 (sin psi_j G_h + cos
// psi_j G_z), one common current-limit factor k, constant work.
// docs/EQUATIONS.md explains why the 1/b* of eq (23) cancels.
#pragma once

#include <cstdint>
#include <type_traits>

#include "maglev/io/sensor_sample.hpp"
#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

inline constexpr int kEfforts = 6;                 // U order = maglev::kernel::Axis order
inline constexpr int kForcers = 4;                 // two coils each; forcer k = coils 2k, 2k+1
inline constexpr int kForcerForces = 2 * kForcers;  // [F_h, F_z] per forcer, eq (21) order
// U's first three efforts (x, y, theta_z) are the in-plane ones, the last
// three (z, theta_x, theta_y) the out-of-plane ones. A forcer's F_h enters
// only the first three rows of A and its F_z only the last three (BuildA),
// so A A^T and B = A^T (A A^T)^-1 are block-structured: an F_h row of B is
// zero in efforts 3-5, an F_z row in efforts 0-2. AllocateCurrents sums
// only the non-zero block; ComputeForceAllocationTables checks the zeros.
inline constexpr int kHorizontalEfforts = 3;

enum class ForceLayout : std::uint8_t {
  kCross = 0,       // paper 000 eq (18) (the seed stage); paper 003 Fig. 7
  kSquare = 1,      // paper 003 Fig. 6: forcers at the corners (+-l, +-l)
  kTriangular = 2,  // paper 003 eq (8), Fig. 8 (Y shape, alpha): 3 forcers, coils 7, 8 unused
};

struct ForceAllocationConfig {
  ForceLayout layout;
  double lever_arm_m;         // l
  double triangle_alpha_rad;  // alpha of eq (8) (pi/6 for Fig. 8)
  // Commutation, eqs (19)/(23): coil j's force is b* i_j (sin psi_j, cos psi_j)
  // along (its forcer's horizontal axis, Z) with psi_j = gamma_1 * (base point
  // along that axis) + coil_phase_rad[j]. Coils of one forcer must differ by
  // +-pi/2 (then each 2x2 block is orthogonal and S^-1 = S^T, paper 003).
  double pitch_m;
  double coil_phase_rad[io::kCoils];
  double base_point_x_m;  // x2 - x (platen frame)
  double base_point_y_m;  // y8 - y
  // Each coil's centre from its forcer's centre, platen frame (x, y), m. A
  // forcer's vertical force splits between its two coils by the commutation
  // (cos^2 / sin^2 of the phase), so it acts at a point that moves with the
  // position; eq (18) puts it at the forcer centre (paper 000 neglects the
  // torque). AllocateCurrents cancels that torque when any offset is non-zero.
  double coil_centre_offset_m[io::kCoils][2];
  // b*(z0): eq (20) when magnetization_A_per_m > 0, else the identified
  // 2 b*(z0) of eq (29).
  double two_b_star_identified_N_per_A;
  double magnetization_A_per_m;  // M0 of eq (3); 0 = use the identified value
  double coil_effective_length_m;  // p
  double coil_side_width_m;        // a
  double coil_thickness_m;         // d
  int coil_turns;                  // N
  double magnet_thickness_m;       // Delta
  double nominal_gap_m;            // z0
  // Limits and gravity feed-forward.
  double peak_current_A;
  double mass_kg;
  double payload_kg;
  double gravity_m_per_s2;
  // The platen's moments of inertia about x, y and z (kg m^2): the rotation
  // axes' acceleration feed-forward I a / (2 b*) and the radii of gyration
  // of the coupling correction. A profile's [body] sets them (they used to
  // be the seed stage's constants whatever the profile said).
  double inertia_kgm2[3];
  // Electronics: DAC code = round(i / gain / FS * 32768); monitor A = code * FS / 32768 / gain.
  double amplifier_gain_A_per_V;
  double dac_full_scale_V;
  double current_monitor_gain_V_per_A;
  double adc_full_scale_V;
};

ForceAllocationConfig DefaultForceAllocationConfig();
// The seed layout's coil centres (stage::kCoilCentreQuarterPitches) at
// c->pitch_m: Fx coils (forcers 1, 3) along x, Fy coils along y.
void SetCoilCentreOffsets(ForceAllocationConfig* c);

// b*(z0) of eq (20) (N/A per coil), from M0 and the coil/magnet geometry.
double BStarFromGeometry(const ForceAllocationConfig& config);

enum class ForceAllocationError : std::uint8_t {
  kOk = 0,
  kBadGeometry,         // l <= 0, pitch <= 0, ...
  kSingularLayout,      // A A^T not invertible
  kPseudoInverseCheck,  // |A B - I| > 1e-9
  kBadCoilPhases,       // a forcer's coils are not +-pi/2 apart
  kBadBStar,
  kBadLimits,
  kScalarRange,         // a B entry (or another constant) does not fit the Scalar
  kBadCoilCentres,      // a coil centre offset not finite or beyond a pitch
};

// Double-precision tables (configuration time; kept for diagnostics/tests).
struct ForceAllocationTablesDouble {
  double a[kEfforts][kForcerForces];  // eq (18) / (6)-(8) in [Fx Fy Tz Fz Tx Ty] row order
  double b[kForcerForces][kEfforts];  // pinv(A)
  double max_abs_ab_minus_i;          // measured |A B - I|_max
  double two_b_star_N_per_A;
  double h_dir[kForcers][2];          // forcer horizontal thrust direction (world XY)
  bool forcer_used[kForcers];
};

ForceAllocationError ComputeForceAllocationTables(const ForceAllocationConfig& config,
                                                  ForceAllocationTablesDouble* out);

// Commutation (shared by every Scalar): per-coil phase, 2^32 = one turn.
struct CommutationTables {
  double inv_pitch_pm;  // 1 / pitch (the pitch in whole pm): the tick's turns (ForcerPhases)
  std::int64_t base_x_pm;
  std::int64_t base_y_pm;
  double h_dir[kForcers][2];  // forcer thrust direction cosines (exactly +-1 / 0 for X/Y axes)
  // Coil 2k's offset; coil 2k+1's is coil 2k's + or - exactly a quarter turn
  // (second_coil_leads[k]): the configuration requires quadrature to 1e-9 rad
  // and the offsets are snapped to it (< 2^-32 turn = 1.5 nrad). So one table
  // sine/cosine per forcer serves both of its coils, bit for bit:
  // sin(p + 2^30) = cos(p), cos(p + 2^30) = -sin(p) with the same table entries.
  std::uint32_t coil_offset_turn[io::kCoils];
  bool second_coil_leads[kForcers];
  // Forcer k's phase is forcer same_as[k]'s (an earlier one, or -1) plus
  // quarter_turns[k] quarter turns, exactly: the same thrust direction (the
  // same turns, bit for bit) and coil offsets a whole number of quarter
  // turns apart. The cross layout's forcers pair up so (1 with 3 along x, 2
  // with 4 along y); the tick then takes their table values rotated instead
  // of looking them up (AllocateCurrents: numeric::rotate_quarters).
  std::int8_t same_as[kForcers];
  std::uint8_t quarter_turns[kForcers];
};

// x, y (pm, magnet frame) -> per-coil phase psi_j (uint32, 2^32 = one turn):
// ForcerPhases, and each forcer's second coil a quarter turn off its first.
void CommutationPhases(std::int64_t x_pm, std::int64_t y_pm, const CommutationTables& tables,
                       std::uint32_t coil_phase_turn[io::kCoils]);
// The tick's form: the phase of each forcer's first coil (coil 2k); the
// second's is a quarter turn off (CommutationTables::second_coil_leads).
// In double, not exact integers: turns = (pos + base) / pitch, projected on
// the forcer's axis, its fraction scaled to 2^32. The fraction and the
// scaling are exact; the one product pos * (1/pitch) is within 2^-53
// relative, so within 2^-46 turn (2^-14 of a phase LSB) anywhere within a
// metre of the base point: the phase is floor(exact) or, when the exact value
// lies within that distance of an integer, one LSB (1.5 nrad) off it. IEEE
// double throughout: host and M7 give the same bits. (The exact integer form
// it replaced took three int64 floor divisions per coordinate.)
// (Defined inline in internal/force_allocation_impl.hpp.)
inline void ForcerPhases(std::int64_t x_pm, std::int64_t y_pm, const CommutationTables& tables,
                         std::uint32_t first_coil_phase_turn[kForcers]);

template <typename Scalar>
struct ForceAllocationState {
  // The tick's fields first: a VFP load reaches 1020 bytes past its base, and
  // the configuration-time double tables (~1 KB) ahead of them cost an
  // address computation before nearly every load in AllocateCurrents
  // (issue 16; docs/PERFORMANCE.md, "Session of 2026-11-28").
  Scalar b[kForcerForces][kEfforts];
  // The coil-centre correction's arithmetic (AllocateCurrents): float for the
  // float kernel, double for fixed point.
  using CorrectionScalar = std::conditional_t<numeric::ScalarTraits<Scalar>::kIsFixed, double, Scalar>;
  // Torque arms (m) of each coil's vertical force about its forcer centre:
  // row 0 -> theta_x (+dy), row 1 -> theta_y (-dx).
  CorrectionScalar coil_torque_arm[2][io::kCoils];
  CorrectionScalar b_tilt_columns[2][kForcerForces];  // B's theta_x, theta_y columns
  bool coil_centres_active;  // any offset non-zero: AllocateCurrents corrects
  // Fixed point: every |B| entry below 32 (raw below 2^29), so a sum of three
  // B x signal products stays below 2^62 and needs no saturating add
  // (AllocateCurrents). True for every shipped layout (largest |B| 9.6).
  bool b_below_32;
  // Per row, the forcers with a non-zero arm on either coil: the only ones
  // whose terms the correction sums.
  bool arm_active[2][kForcers];
  Scalar peak_current_A;
  Scalar half_peak_current_A;
  Scalar gravity_effort_A;  // (m + payload) g / (2 b*)
  Scalar inv_two_b_star_A_per_N;
  double two_b_star_N_per_A;
  // DAC / monitor scaling
  double dac_codes_per_A;
  std::int64_t dac_q32_per_raw;    // Fixed only: codes per raw LSB, Q32
  double monitor_A_per_code;
  std::int64_t monitor_raw_per_code_q16;  // Fixed only
  bool configured;
  CommutationTables commutation;
  ForceAllocationTablesDouble tables;
};

template <typename Scalar>
struct AllocationOutput {
  Scalar current_A[io::kCoils];
  Scalar applied_effort_A[kEfforts];  // k * U: what the loops' anti-windup must see
  Scalar scale_k;                     // 1 when not limited
  bool saturated;
};

// ---- configuration ------------------------------------------------------------
template <typename Scalar>
ForceAllocationError ApplyForceAllocationConfig(const ForceAllocationConfig& config,
                                                ForceAllocationState<Scalar>* state);

// ---- per tick -------------------------------------------------------------------
// x_pm, y_pm: magnet-frame position (after homing) for the commutation.
// Q7.24 headroom: |G| = |B U| and |i|/2 must stay < 128 A; with the seed
// layout that holds for |U_axis| <= 20 A (the loops saturate U well below).
template <typename Scalar>
void AllocateCurrents(const Scalar effort_A[kEfforts], std::int64_t x_pm, std::int64_t y_pm,
                      const ForceAllocationState<Scalar>& state, AllocationOutput<Scalar>* out);

// U_z,ff = ramp_fraction * (m + payload) g / (2 b*)  (ramp in [0, 1], set by the sequencer).
template <typename Scalar>
Scalar GravityFeedForward_A(Scalar ramp_fraction, const ForceAllocationState<Scalar>& state);

// Feed-forward conversion: force (N) or torque (N*m) -> effort (A): U = F / (2 b*).
template <typename Scalar>
Scalar EffortFromForce_A(Scalar force, const ForceAllocationState<Scalar>& state);

// Coil current (A) -> AD5764 code, round half away from zero, saturated to int16.
template <typename Scalar>
std::int16_t CurrentToDacCode(Scalar current_A, const ForceAllocationState<Scalar>& state);

// Amplifier current-monitor ADC code -> A.
template <typename Scalar>
Scalar MonitorCodeToCurrent_A(std::int16_t code, const ForceAllocationState<Scalar>& state);

// The same in float for either kernel (the supervisor works in float): the
// float kernel's MonitorCodeToCurrent_A is this.
inline float MonitorCodeToCurrentFloat_A(std::int16_t code, double monitor_A_per_code) {
  return static_cast<float>(static_cast<double>(code) * monitor_A_per_code);
}

}  // namespace maglev::kernel

#include "maglev/force_allocation/internal/force_allocation_impl.hpp"
