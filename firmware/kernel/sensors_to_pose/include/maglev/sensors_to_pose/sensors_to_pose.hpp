// sensors_to_pose: raw per-tick sensor bits -> 64-bit fixed-point pose.
//
//   interferometer counts (3 x wrapping uint32) -> int64 counts -> pm
//       -> beam-layout solve (x, y, theta_z, with Abbe/cosine terms)
//   laser displacement ADC codes (3 x int16)   -> heights (pm)
//       -> plane fit (z, theta_x, theta_y)
//   Hall ADC codes (4 x int16)                 -> in-plane phase (homing only)
//   status bits / rail codes                   -> validity per pose axis
//
// Every per-tick operation is integer (int64 with 32-bit-limb wide products,
// see wide_math.hpp): the pose is bit-identical on host and target, in the
// float and in the Q7.24 kernel. Constants are precomputed in double when a
// Config is applied, never per tick.
//
// Sign conventions (world XYZ fixed to the magnet matrix, Z up; rotations
// right-handed about +X, +Y, +Z):
//   * a point of the platen at platen-frame (px, py) is at height
//     z + theta_x * py - theta_y * px          (small angles)
//   * a point of the platen at platen-frame (px, py) is at world
//     (x - theta_z * py, y + theta_z * px)     (small angles)
#pragma once

#include <cstdint>

#include "maglev/io/axis.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::kernel {

// A pose: 1 pm per LSB for lengths, 1 prad per LSB for angles, indexed by
// the one Axis order (io/axis.hpp): pose[Axis::kZ].
struct Pose64 {
  std::int64_t pico[kAxisCount];
  constexpr std::int64_t& operator[](Axis a) { return pico[axis_index(a)]; }
  constexpr const std::int64_t& operator[](Axis a) const { return pico[axis_index(a)]; }
};

// Validity bit i <-> maglev::kernel::Axis i: x, y, theta_z, z, theta_x,
// theta_y (the order of U in eq (21); same bits as the sequencer's kAxisBit*).
inline constexpr std::uint8_t kPoseValidX = 1u << 0;
inline constexpr std::uint8_t kPoseValidY = 1u << 1;
inline constexpr std::uint8_t kPoseValidThetaZ = 1u << 2;
inline constexpr std::uint8_t kPoseValidZ = 1u << 3;
inline constexpr std::uint8_t kPoseValidThetaX = 1u << 4;
inline constexpr std::uint8_t kPoseValidThetaY = 1u << 5;
inline constexpr std::uint8_t kPoseValidInPlane = kPoseValidX | kPoseValidY | kPoseValidThetaZ;
inline constexpr std::uint8_t kPoseValidOutOfPlane = kPoseValidZ | kPoseValidThetaX | kPoseValidThetaY;
inline constexpr std::uint8_t kPoseValidAll = kPoseValidInPlane | kPoseValidOutOfPlane;

// ---------------------------------------------------------------------------
// Configuration (plain SI, what Modbus / persistence see)
// ---------------------------------------------------------------------------
enum class BeamAxis : std::uint8_t { kX = 0, kY = 1 };

// One interferometer beam. Beams are fixed in the world; the plane mirror is
// on the platen. A beam along X at world Y = perpendicular_m reads
//   sign * m = x - (perpendicular_m - y) * theta_z + d * theta_z^2 / 2
// and a beam along Y at world X = perpendicular_m reads
//   sign * m = y + (perpendicular_m - x) * theta_z + d * theta_z^2 / 2
// (d = mirror_distance_m: platen centre to the mirror face; the d term is the
// cosine error of the rotated mirror, exact to O(theta^3)). x, y are measured
// from the interferometer zero, i.e. before the homing offset.
struct BeamConfig {
  BeamAxis axis;
  double perpendicular_m;
  double mirror_distance_m;
  std::int8_t sign;  // +1 or -1: counts increase with +axis motion or not
};

// The Hall signal's harmonics above the fundamental that the homing solve
// removes: n = 5, 9, 13 (a Halbach array's n = 4k + 1; the plant models these
// four). The 17th is below 2e-4 of the fundamental at the seed's 1.6 mm.
inline constexpr int kHallHarmonics = 3;
constexpr int HallHarmonicOrder(int k) { return 4 * k + 5; }  // k = 0, 1, 2 -> 5, 9, 13

struct SensorsToPoseConfig {
  // Interferometer: LSB = wavelength / (fold * interpolation).
  double wavelength_m;
  int fold;
  int interpolation;
  BeamConfig beam[io::kInterferometerAxes];
  // Include the Abbe (y*theta_z, x*theta_z) and cosine (d*theta_z^2/2) terms.
  bool abbe_cosine_correction;
  // Plausibility: a per-tick count jump above max_speed / servo_rate is a
  // glitch (lost fringe, counter reset), flagged and not absorbed.
  double max_speed_m_per_s;
  double servo_rate_Hz;

  // Laser displacement sensors: height_i = zero_height + code * FS/32768 * scale.
  double displacement_scale_m_per_V;
  double displacement_zero_height_m;
  double adc_full_scale_V;
  double displacement_sensor_x_m[io::kDisplacementSensors];  // platen frame
  double displacement_sensor_y_m[io::kDisplacementSensors];
  // An ADC code with |code| >= rail_code is "at the rail": invalid.
  std::int16_t adc_rail_code;

  // Hall sensors (homing).
  double pitch_m;
  double hall_a_x_m;  // sensor A, platen frame; B is a quarter pitch further in X and Y
  double hall_a_y_m;
  // c_n / c_1 of eq (3) at the Hall height for n = 5, 9, 13 (harmonic n =
  // 4k + 1 enters eq (1) with sign (-1)^k; HalbachHarmonicRatio). Removed
  // from the phase by a fixed-count iteration. The 9th is 2.9 % of the
  // fundamental at the seed stage's 1.6 mm: left out, it misplaced homing
  // by up to 0.28 mm (1.4 deg of commutation phase on the default run).
  double hall_harmonic_ratio[kHallHarmonics];
  // sqrt(A^2 + B^2) must be within [min, max] ADC codes to trust the phase.
  double hall_min_amplitude_codes;
  double hall_max_amplitude_codes;

  // Acceleration plausibility (0 disables): a count step whose change from
  // the previous step implies more than this acceleration of the beam's
  // mirror is a glitch (lost or spurious fringes), not motion: no actuator of
  // the stage can produce it. The step is replaced by the previous one (the
  // counter extrapolates one tick and absorbs the jump as an offset) and
  // PoseMeasurement::beam_glitch reports it. Within max_speed_m_per_s only;
  // beyond it the jump check above acts. Applied from the third fresh sample
  // after a re-seed (it needs two real steps).
  double max_acceleration_m_per_s2;

  // Laser displacement sensors' target steps (issue 15). The sensors look at
  // the magnet array, whose blocks differ in height (a +-0.05 mm tolerance:
  // up to 0.1 mm between neighbours). When a sensor's spot crosses from one
  // block to the next its reading jumps by that step within a tick, and the
  // z / tilt loops would chase it (a 0.1 mm step is 1.6 mrad of measured tilt
  // at the seed stage's sensor spacing, past the tilt envelope). The platen
  // itself does not move that far in one tick, so a reading whose whole change
  // over the tick exceeds lds_target_step_min_um, while the sensor's spot
  // (homed x, y + the sensor's position) is within lds_target_window_um of a
  // block edge of the lds_target_cell_m grid, is a target step: it is taken as
  // an offset of that sensor (the repaired reading continues the previous one)
  // and reported in PoseMeasurement::lds_target_step. One step is repaired per
  // visit of an edge's window, plus steps that undo it (a spot that goes back,
  // or dithers on the edge): a run of same-way jumps at one edge is the platen
  // moving. A jump away from an edge is not repaired (a real fault, left to the
  // supervisor). The offsets persist while the sensor is tracked; they reset
  // when a configuration is applied. lds_target_cell_m = 0 turns the repair off.
  // The window covers the sensors' position tolerance and the array's
  // placement. The threshold, 1 um, is 10x the largest change of a reading per
  // tick in the bench's suite outside the target steps (0.10 um,
  // loop_response) and 100x the sensors' 10 nm noise; at 5 um a step left to
  // the loops put the as-built platen's low corner on its stop (docs/KERNEL.md).
  // The threshold and the window are float um: registers lds.target_step_min
  // and lds.target_window (F32, um) hold exactly these values, so a value
  // written, saved and booted is the value the kernel got. They become metres
  // as value / 1e6 (a correctly rounded quotient: 1 um and 1000 um give the
  // doubles 1e-6 and 1e-3 themselves).
  double lds_target_cell_m = 0.0;
  float lds_target_step_min_um = 1.0f;
  float lds_target_window_um = 1000.0f;
  // The repair switch (register lds.target_repair): 1 repairs on the stage's
  // cell grid, 0 leaves every step to the loops (a flat target, or the paper's
  // stage) and keeps the cell, so turning it back on needs no stage data.
  // Repair acts when this is 1 and lds_target_cell_m > 0.
  std::uint8_t lds_target_repair = 1;
  // Where the laser displacement sensors' plane gives z (the bench's
  // [controller] z_point; no register: the shipped controller measures z at
  // the centre): 0 at the platen's centre, the point the force allocation
  // and the tilt axes use (the kernel's design: a tilt moves no z); 1 at the
  // sensors' centroid, i.e. z = the mean of the three heights. A stage whose
  // controller averages its height sensors measures (and regulates) z there:
  // with three sensors at three corners of a square of side a, the centroid
  // is a/6 off both tilt axes, so a tilt d reads as a z change of (a/6) d
  // (20.5 nm/urad on the seed stage; docs/PERFORMANCE.md, paper 003 Table 5).
  // Configuration-time only: the tick's plane fit is the same product.
  std::uint8_t lds_z_point = 0;
  // Explicit, always zero (configurations compare byte by byte).
  std::uint8_t reserved_lds[6] = {};
};

// The laser displacement sensors' target, the magnet array's top, is made of
// blocks a quarter pitch wide (a Halbach array's four magnetisations per
// pitch): lds_target_cell_m of a stage with this pitch.
constexpr double MagnetBlockWidth_m(double pitch_m) { return pitch_m / 4.0; }

// The laser displacement sensors' centroid in the platen frame (m), where
// lds_z_point = 1 measures z: the mean of the three sensors' x and y.
void HeightSensorCentroid(const SensorsToPoseConfig& c, double* x_m, double* y_m);

// Defaults from io/stage_parameters.hpp. Not constexpr (uses std::exp).
SensorsToPoseConfig DefaultSensorsToPoseConfig();

// c_n(z) / c_1(z) of eq (3) for harmonic n at height z over an array of
// thickness delta (the sign (-1)^k is NOT included).
double HalbachHarmonicRatio(int n, double z_m, double delta_m, double pitch_m);
// hall_harmonic_ratio of a Hall sensor at height z over that array: n = 5, 9, 13.
void HallHarmonicRatios(double z_m, double delta_m, double pitch_m, double (&ratio)[kHallHarmonics]);
// The least slope d phi / d theta of the Hall phase over a pitch with these
// harmonics (HallSolveStep's f'; 1 without harmonics). The solve needs the
// phase monotonic with margin: configuration refuses a slope below
// kHallPhaseSlopeMin. 0.2: where the solve's fixed steps are measured to
// converge for a Halbach array's three harmonics (a Hall sensor down to
// 0.5 mm over the seed's array; 0.45 mm still converges, 0.33 mm diverges)
// and for the 5th alone (eps_5 <= 0.165; the bound was eps_5 < 0.19 before
// the 9th and 13th were modelled, i.e. a sensor above ~0.53 mm here).
double HallPhaseSlopeMin(const double (&ratio)[kHallHarmonics]);
inline constexpr double kHallPhaseSlopeMin = 0.2;

// The highest platen height above rest the laser displacement sensors
// measure: their zero height + full scale (300 um on the seed board). The
// supervisor's z window must stay below it.
constexpr double HeightSensorsTop_m(const SensorsToPoseConfig& c) {
  return c.displacement_zero_height_m + c.adc_full_scale_V * c.displacement_scale_m_per_V;
}

enum class SensorsToPoseError : std::uint8_t {
  kOk = 0,
  kBadInterferometerScale,   // wavelength/fold/interpolation not positive / too fine
  kBadBeamSign,
  kSingularBeamLayout,       // the three beams do not determine x, y, theta_z
  kBadPlausibilityBound,
  kSingularDisplacementLayout,  // the three sensors are collinear
  kBadDisplacementScale,
  kBadPitch,
  kBadHallConfig,
  kBadTargetStepRepair,      // lds_target_*: cell < 0, or threshold / window out of range
  kBadZPoint,                // lds_z_point neither 0 (platen centre) nor 1 (sensors' centroid)
};

// ---------------------------------------------------------------------------
// State (caller-owned, static). Holds the applied constants and the counters.
// ---------------------------------------------------------------------------
struct SensorsToPoseState {
  // --- applied constants (ApplySensorsToPoseConfig) ---
  // pm = round(counts * lsb_num / lsb_den), exact; lsb_num/lsb_den is the
  // reduced fraction wavelength_fm / (fold * interpolation * 1000).
  std::int64_t lsb_num;
  std::int64_t lsb_den;
  std::int64_t max_counts_per_tick;
  // |step - previous step| above this is a glitch (0: check off).
  std::int64_t max_counts_step_change;
  // The tick's arithmetic is double (one FPU instruction per operation on
  // the M7, where int64 products need 128-bit limbs and divisions are
  // library calls); positions stay int64 pm / prad at the interfaces.
  double lsb_pm;  // lsb_num / lsb_den
  // Beam b's sign (BeamConfig::sign) times lsb_pm, exactly (a sign flip):
  // counts * signed_lsb_pm[b] is the beam's reading with one multiply, the
  // same bits as sign * (counts * lsb_pm) (rounding to nearest is symmetric
  // about zero).
  double signed_lsb_pm[io::kInterferometerAxes];
  bool abbe_cosine_correction;
  // [x, y, theta_z] = inv_beam * m (rows x, y in pm/pm, theta_z in prad/pm):
  // the solve without the Abbe / cosine terms.
  double inv_beam[3][3];
  // The closed-form solve with them (SensorsToPoseStep): two beams share an
  // axis (a layout with three is singular), their difference gives
  // t = tan theta_z from (dd/2) t^2 + dp t = m_a - m_b, then x and y solve a
  // 2 x 2 system. All in pm; t dimensionless.
  std::uint8_t pair_a, pair_b;  // the two beams along one axis, ordered so that dp > 0
  std::uint8_t single;          // the third beam, along the other axis
  bool pair_is_y;               // the pair is along Y (the y row), the single beam along X
  double pair_dp_pm, pair_dp2_pm2, pair_two_dd_pm;
  // The x row: x + t y = m_X + t (p_X - t d_X / 2); the y row: y - t x =
  // m_Y - t (p_Y + t d_Y / 2). m_X, m_Y: the single beam's reading and the
  // pair's mean; p and d the same beams' perpendicular offsets and mirror
  // distances.
  double p_x_pm, half_d_x_pm, p_y_pm, half_d_y_pm;
  // heights: lds_zero_pm + code * lds_gain_pm
  double lds_zero_pm;
  double lds_gain_pm;
  // [z, theta_x, theta_y] = inv_plane * h.
  double inv_plane[3][3];
  std::int16_t adc_rail_code;
  std::int64_t pitch_pm;
  std::int64_t hall_a_x_pm;
  std::int64_t hall_a_y_pm;
  double hall_harmonic_ratio[kHallHarmonics];
  double hall_min_amplitude_codes;
  double hall_max_amplitude_codes;

  // --- runtime ---
  std::uint32_t last_raw[io::kInterferometerAxes];
  // The extended count of each beam: an integer, held in a double, where
  // it is exact while |counts| < 2^53 (5 500 km at 0.618 nm a count; a step
  // is at most max_counts_per_tick < 1e9). The tick adds its int32 step and
  // multiplies by the LSB in the FPU; as an int64 it cost an add with carry
  // and a conversion to double every tick (~40 M7 instructions over the
  // three beams, issue 16).
  double counts[io::kInterferometerAxes];
  std::uint8_t jump_latched;  // bit b: beam b saw an implausible jump (sticky until re-seed)
  // Counts per tick of the last fresh step: |.| <= max_counts_per_tick < 1e9.
  std::int32_t last_step[io::kInterferometerAxes];
  std::uint8_t steps_seen;   // fresh steps since the re-seed (saturates at 2)
  std::uint8_t stale_gap;    // stale samples since the last fresh one (saturates)
  bool seeded;
  // Homing offsets added to the interferometer x, y (magnet-frame absolute).
  std::int64_t home_offset_x_pm;
  std::int64_t home_offset_y_pm;
  bool homed;
  // LDS target-step repair (lds_target_*): constants, then runtime.
  double lds_cell_pm;         // 0: off
  double lds_inv_cell_per_pm;
  std::int32_t lds_step_min_codes;  // 0: off
  double lds_step_min_pm;           // the same in pm
  double lds_window_pm;
  double lds_sensor_x_pm[io::kDisplacementSensors];
  double lds_sensor_y_pm[io::kDisplacementSensors];
  std::int16_t lds_last_code[io::kDisplacementSensors];  // last reading's ADC code
  double lds_last_x_pm;  // last tick's unhomed x, y (where the spots are)
  double lds_last_y_pm;
  double lds_offset_pm[io::kDisplacementSensors];    // added to the reading
  // The step last repaired and its edge (lds_held_edge cells
  // along x or y): until the spot leaves that edge's window, only a step
  // that undoes it is repaired there.
  double lds_held_pm[io::kDisplacementSensors];
  double lds_held_edge[io::kDisplacementSensors];
  std::uint8_t lds_held_along_x[io::kDisplacementSensors];
  std::uint8_t lds_held;  // bit i: lds_held_pm[i] is held
  std::uint8_t lds_tracked;   // bit i: lds_last_code[i] was a good reading
  std::uint32_t lds_steps_repaired;  // since the configuration was applied (saturating)
};

// Validates, precomputes, and re-seeds the counters on the next sample.
// On error the state is left unchanged.
SensorsToPoseError ApplySensorsToPoseConfig(const SensorsToPoseConfig& config,
                                            SensorsToPoseState* state);

struct PoseMeasurement {
  Pose64 pose;               // x, y include the homing offset
  Pose64 pose_unhomed;       // x, y relative to the interferometer zero
  std::uint8_t valid_axes;   // kPoseValid* bits
  std::uint8_t beam_loss;    // bit b: status kBeamLoss<b>
  std::uint8_t beam_jump;    // bit b: implausible count jump (latched)
  // bit b: THIS tick's step of beam b implied an impossible acceleration and
  // was replaced by the previous step (max_acceleration_m_per_s2); the pose
  // stays valid. glitch_counts[b]: the step change that was refused (counts).
  // The check skips samples flagged io::kStaleFrame (a repeat, not a step)
  // and allows a step one tick longer or shorter than predicted (a sample
  // that reached the kernel a tick early or late over a link).
  std::uint8_t beam_glitch;
  std::int64_t glitch_counts[io::kInterferometerAxes];
  // bit s: THIS tick's reading of displacement sensor s jumped at a target
  // block edge and was repaired (lds_target_*; the step is in
  // SensorsToPoseState::lds_held_pm[s]).
  std::uint8_t lds_target_step;
  std::uint8_t displacement_bad;  // bit s: out of range, or ADC at the rail
  bool adc_fault;
  bool stale_frame;
};

// One tick. Constant work, no early exits.
PoseMeasurement SensorsToPoseStep(const io::SensorSample& sample, SensorsToPoseState* state);

// Interferometer counter extension alone (the step above applies the same
// rule, StepCounter in sensors_to_pose.cpp, with its 32-bit bound).
// Returns true if the sample's delta was plausible and absorbed.
bool ExtendCounter(std::uint32_t raw, std::uint32_t* last_raw, std::int64_t* counts,
                   std::int64_t max_counts_per_tick);

// Exact count -> pm, rounding to nearest with ties away from zero.
std::int64_t CountsToPicometres(std::int64_t counts, const SensorsToPoseState& state);

// Re-seed the counters at the next sample (counts restart at 0 = the
// present position) and clear the jump latches. Homing must follow.
void ReseedInterferometers(SensorsToPoseState* state);

// ---------------------------------------------------------------------------
// Hall sensors and homing
// ---------------------------------------------------------------------------
struct HallPhase {
  // Magnet-frame phase of sensor A in X and Y, 2^32 = one pitch.
  std::uint32_t phase_x_turn;
  std::uint32_t phase_y_turn;
  double amplitude_x_codes;
  double amplitude_y_codes;
  bool plausible;  // amplitudes in range and ADC not faulted / railed
};

// phase = atan2(A, B) of each axis, with the 5th harmonic removed. Homing
// only (double, the kernel's own atan2/sin/cos), ~10 000 M7 instructions:
// the controller runs it outside the servo tick (Controller::background()),
// from a copy of what it reads (HallSolveInputs). In bounded steps:
//   HallSolveBegin (the sample's atan2s, amplitudes, plausibility),
//   HallSolveStep x kHallSolveSteps (one fixed-point pass, then Newton),
//   HallSolveFinish (any steps left, then the phases in turns);
// HallSolveRun does them all.
inline constexpr int kHallSolveSteps = 7;
struct HallSolve {
  double phi[2];    // atan2(A, B) of x and y
  double theta[2];  // the solution so far
  double eps[kHallHarmonics];  // hall_harmonic_ratio (n = 5, 9, 13)
  int steps;        // steps done
  HallPhase result;  // amplitudes and plausibility (phases: HallSolveFinish)
};
// What the solve reads: the sample's Hall channels and flags and four
// configuration values, copied so that it can run outside the tick
// (Controller::background()) on values the tick no longer touches.
struct HallSolveInputs {
  std::int16_t hall_adc[io::kHallChannels];
  std::uint16_t status_flags;
  std::int16_t adc_rail_code;
  double eps[kHallHarmonics];  // hall_harmonic_ratio
  double min_amplitude_codes;
  double max_amplitude_codes;
  // And what ComputeHomingOffsets reads of the geometry.
  std::int64_t pitch_pm;
  std::int64_t hall_a_x_pm;
  std::int64_t hall_a_y_pm;
};
HallSolveInputs HallSolveInputsOf(const io::SensorSample& sample, const SensorsToPoseState& state);
void HallSolveBegin(const HallSolveInputs& in, HallSolve* solve);
void HallSolveStep(HallSolve* solve);
HallPhase HallSolveFinish(HallSolve* solve);
// Begin, every step and Finish: the same bits as spreading them over ticks.
HallPhase HallSolveRun(const HallSolveInputs& in);
// All of it at once (tests, tools).
HallPhase HallToPhase(const io::SensorSample& sample, const SensorsToPoseState& state);

// Magnet-frame platen-centre coordinate (mod pitch, in [0, pitch)) from a
// Hall phase: x = phase * pitch - hall_a_x (theta_z ~ 0 at homing).
std::int64_t HallCoarsePosition_pm(std::uint32_t phase_turn, std::int64_t sensor_offset_pm,
                                   std::int64_t pitch_pm);

struct HomingOffsets {
  std::int64_t x_pm;
  std::int64_t y_pm;
};

// Offsets that make interferometer + offset == Hall coordinate (mod pitch),
// chosen in [-pitch/2, pitch/2): the smallest correction.
HomingOffsets ComputeHomingOffsets(const HallPhase& hall, const Pose64& pose_unhomed,
                                   const SensorsToPoseState& state);
// The same from the solve's copied inputs (Controller::background()).
HomingOffsets ComputeHomingOffsets(const HallPhase& hall, const Pose64& pose_unhomed, const HallSolveInputs& in);
// pose = pose_unhomed with the homing offsets added to x and y (the last
// part of SensorsToPoseStep; also used right after homing on that tick).
void ApplyHomingOffsets(const SensorsToPoseState& state, PoseMeasurement* measurement);

void SetHomingOffsets(const HomingOffsets& offsets, SensorsToPoseState* state);

}  // namespace maglev::kernel
