#include "maglev/io/code_placement.hpp"
#include "maglev/sensors_to_pose/sensors_to_pose.hpp"

#include <cmath>
#include <cstdint>

#include "maglev/io/stage_parameters.hpp"
#include "maglev/sensors_to_pose/internal/wide_math.hpp"
#include "maglev/numeric/elementary.hpp"
#include "maglev/numeric/int64_double.hpp"

namespace maglev::kernel {
namespace {

namespace stage = io::stage;
using wide::MulShiftRound;

constexpr std::int64_t Gcd(std::int64_t a, std::int64_t b) {
  while (b != 0) {
    const std::int64_t t = a % b;
    a = b;
    b = t;
  }
  return a;
}

MAGLEV_CONFIG_CODE std::int64_t RoundToInt64(double v) { return static_cast<std::int64_t>(std::llround(v)); }

// Inverse of a 3x3 matrix in double (configuration time). Returns false if
// the matrix is singular relative to its scale.
MAGLEV_CONFIG_CODE bool Invert3(const double m[3][3], double inv[3][3]) {
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  const double c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  const double c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  const double det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
  double scale = 0.0;
  for (int r = 0; r < 3; ++r) {
    double row = 0.0;
    for (int c = 0; c < 3; ++c) row += std::fabs(m[r][c]);
    scale = scale > row ? scale : row;
  }
  if (!(std::fabs(det) > 1e-9 * scale * scale * scale)) return false;
  const double k = 1.0 / det;
  inv[0][0] = c00 * k;
  inv[1][0] = c01 * k;
  inv[2][0] = c02 * k;
  inv[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * k;
  inv[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * k;
  inv[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * k;
  inv[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * k;
  inv[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * k;
  inv[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * k;
  return true;
}

using numeric::Int64ToDouble;

// |v| as uint32: exact for every int32, INT32_MIN included (2^31).
constexpr std::uint32_t UnsignedMagnitude(std::int32_t v) {
  return v < 0 ? 0u - static_cast<std::uint32_t>(v) : static_cast<std::uint32_t>(v);
}

// The counter's rule, ExtendCounter's and the tick's: the modular step from
// last_raw to raw (reinterpreted as signed: correct across the 2^32 wrap in
// both directions while |true step| < 2^31), taken when its magnitude is at
// most max_step, else nothing.
struct CounterStep {
  std::int32_t moved;  // the step taken (0 when implausible)
  bool plausible;
};
constexpr CounterStep StepCounter(std::uint32_t raw, std::uint32_t last_raw, std::uint32_t max_step) {
  const auto delta = static_cast<std::int32_t>(raw - last_raw);
  const bool plausible = UnsignedMagnitude(delta) <= max_step;
  return {plausible ? delta : 0, plausible};
}

}  // namespace

MAGLEV_CONFIG_CODE double HalbachHarmonicRatio(int n, double z_m, double delta_m, double pitch_m) {
  const double g1 = 2.0 * stage::kPi / pitch_m;
  const double gn = g1 * n;
  return (1.0 / n) * (1.0 - numeric::dexp(-gn * delta_m)) / (1.0 - numeric::dexp(-g1 * delta_m)) *
         numeric::dexp(-(gn - g1) * z_m);
}

MAGLEV_CONFIG_CODE void HallHarmonicRatios(double z_m, double delta_m, double pitch_m,
                                           double (&ratio)[kHallHarmonics]) {
  for (int k = 0; k < kHallHarmonics; ++k) ratio[k] = HalbachHarmonicRatio(HallHarmonicOrder(k), z_m, delta_m, pitch_m);
}

namespace {
// w(theta) and u(theta) of HallSolveStep from cos / sin 4 theta.
struct HallW {
  double wr, wi, ur, ui;
};
HallW HallWOf(const double (&e)[kHallHarmonics], double c4, double s4) {
  const double c8 = c4 * c4 - s4 * s4, s8 = 2.0 * s4 * c4;
  const double c12 = c8 * c4 - s8 * s4, s12 = s8 * c4 + c8 * s4;
  return HallW{1.0 - e[0] * c4 + e[1] * c8 - e[2] * c12, -e[0] * s4 + e[1] * s8 - e[2] * s12,
               -4.0 * e[0] * c4 + 8.0 * e[1] * c8 - 12.0 * e[2] * c12,
               -4.0 * e[0] * s4 + 8.0 * e[1] * s8 - 12.0 * e[2] * s12};
}
double HallSlope(const HallW& w) { return 1.0 + (w.ur * w.wr + w.ui * w.wi) / (w.wr * w.wr + w.wi * w.wi); }
}  // namespace

MAGLEV_CONFIG_CODE double HallPhaseSlopeMin(const double (&ratio)[kHallHarmonics]) {
  // w has period pi/2 in theta: 4 theta over one turn, 1024 points (the
  // slope is smooth: between points it dips by < 1e-4 at the bound).
  double least = 1.0;
  for (int i = 0; i < 1024; ++i) {
    const double a = 2.0 * stage::kPi * (i + 0.5) / 1024.0;
    const double slope = HallSlope(HallWOf(ratio, numeric::dcos(a), numeric::dsin(a)));
    least = slope < least ? slope : least;
  }
  return least;
}

MAGLEV_CONFIG_CODE SensorsToPoseConfig DefaultSensorsToPoseConfig() {
  SensorsToPoseConfig c{};
  c.wavelength_m = stage::kWavelength_m;
  c.fold = stage::kInterferometerFold;
  c.interpolation = stage::kInterferometerInterpolation;
  // "x, y1, y2": x beam along X at y = 0; y beams along Y at x = -/+ s/2.
  // (ours) mirror faces at the 143 mm frame's edge: 71.5 mm from the centre.
  c.beam[0] = {BeamAxis::kX, 0.0, 0.0715, 1};
  c.beam[1] = {BeamAxis::kY, -stage::kYBeamSeparation_m / 2, 0.0715, 1};
  c.beam[2] = {BeamAxis::kY, +stage::kYBeamSeparation_m / 2, 0.0715, 1};
  c.abbe_cosine_correction = true;
  // (ours) 2 m/s: 1.7x the paper's fastest move (1.2 m/s^2 trapezoid peaks
  // near 0.12 m/s) would still be far inside; a lost fringe burst is not.
  c.max_speed_m_per_s = 2.0;
  c.servo_rate_Hz = stage::kServoRate_Hz;
  c.displacement_scale_m_per_V = stage::kDisplacementScale_m_per_V;
  c.displacement_zero_height_m = stage::kDisplacementZeroHeight_m;
  c.adc_full_scale_V = stage::kAdcFullScale_V;
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    c.displacement_sensor_x_m[i] = stage::kDisplacementSensorX_m[i];
    c.displacement_sensor_y_m[i] = stage::kDisplacementSensorY_m[i];
  }
  c.adc_rail_code = 32767;  // the AD7606 clips at +32767 / -32768
  c.pitch_m = stage::kPitch_m;
  c.hall_a_x_m = stage::kHallAX_m;
  c.hall_a_y_m = stage::kHallAY_m;
  HallHarmonicRatios(stage::kHallHeightAboveMagnets_m, stage::kMagnetThickness_m, stage::kPitch_m,
                     c.hall_harmonic_ratio);
  // (ours) accept 10%..105% of full scale: a detached/unpowered sensor reads ~0.
  c.hall_min_amplitude_codes = 3276.8;
  c.hall_max_amplitude_codes = 34406.0;
  // (ours) 80 m/s^2 at a beam's mirror. Upper bound of what the coils can do:
  // 8 coils at the 4 A peak give at most 8 * 4 A * b* (0.85 N/A) = 27 N,
  // 36 m/s^2 on the 0.75 kg platen, plus at most 27 N * 0.07 m / Iz *
  // 0.05 m = 26 m/s^2 of rotation at a y beam: 63 m/s^2. Measured: at most
  // 7.8 m/s^2 in the 19 suite scenarios and 21.7 m/s^2 in 400 fault-campaign
  // runs (shorted amplifiers and pushes included). 80 m/s^2 is a step change
  // of 20 707 counts (12.8 um) in one tick at 2.5 kHz (docs/RELIABILITY.md).
  c.max_acceleration_m_per_s2 = 80.0;
  c.lds_target_cell_m = MagnetBlockWidth_m(stage::kPitch_m);
  c.lds_target_step_min_um = 1.0f;
  c.lds_target_window_um = 1000.0f;
  return c;
}

MAGLEV_CONFIG_CODE void HeightSensorCentroid(const SensorsToPoseConfig& c, double* x_m, double* y_m) {
  *x_m = *y_m = 0.0;
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    *x_m += c.displacement_sensor_x_m[i] / io::kDisplacementSensors;
    *y_m += c.displacement_sensor_y_m[i] / io::kDisplacementSensors;
  }
}

MAGLEV_CONFIG_CODE SensorsToPoseError ApplySensorsToPoseConfig(const SensorsToPoseConfig& config,
                                            SensorsToPoseState* state) {
  SensorsToPoseState s{};
  // --- interferometer LSB as an exact reduced fraction of pm ---------------
  // wavelength rounded to whole femtometres (632.991 nm is exactly 632991000 fm).
  if (!(config.wavelength_m > 0.0 && config.wavelength_m < 1e-3) || config.fold <= 0 ||
      config.interpolation <= 0 || config.fold > 64 || config.interpolation > 65536) {
    return SensorsToPoseError::kBadInterferometerScale;
  }
  const std::int64_t wavelength_fm = RoundToInt64(config.wavelength_m * 1e15);
  const std::int64_t den = std::int64_t{config.fold} * config.interpolation * 1000;
  const std::int64_t g = Gcd(wavelength_fm, den);
  s.lsb_num = wavelength_fm / g;
  s.lsb_den = den / g;
  // counts are split as q*den + r with r < den; r * num must fit in int64.
  if (s.lsb_num >= (std::int64_t{1} << 40) || s.lsb_den >= (std::int64_t{1} << 22)) {
    return SensorsToPoseError::kBadInterferometerScale;
  }
  const double lsb_m = config.wavelength_m / (config.fold * config.interpolation);
  s.lsb_pm = static_cast<double>(s.lsb_num) / static_cast<double>(s.lsb_den);
  if (!(config.max_speed_m_per_s > 0.0) || !(config.servo_rate_Hz > 0.0)) {
    return SensorsToPoseError::kBadPlausibilityBound;
  }
  const double max_counts = std::ceil(config.max_speed_m_per_s / config.servo_rate_Hz / lsb_m);
  if (!(max_counts >= 1.0 && max_counts < 1.0e9)) return SensorsToPoseError::kBadPlausibilityBound;
  s.max_counts_per_tick = static_cast<std::int64_t>(max_counts);
  // Step change per tick: a * T^2 / lsb. 0 disables; otherwise at least one
  // count and below the speed bound (a finer bound would refuse noise).
  if (!(config.max_acceleration_m_per_s2 >= 0.0 && config.max_acceleration_m_per_s2 < 1.0e9)) {
    return SensorsToPoseError::kBadPlausibilityBound;
  }
  const double change_counts = config.max_acceleration_m_per_s2 / (config.servo_rate_Hz * config.servo_rate_Hz) / lsb_m;
  const double max_change = std::ceil(change_counts);
  if (config.max_acceleration_m_per_s2 > 0.0 && !(change_counts >= 1.0 && max_change <= max_counts)) {
    return SensorsToPoseError::kBadPlausibilityBound;
  }
  s.max_counts_step_change = config.max_acceleration_m_per_s2 > 0.0 ? static_cast<std::int64_t>(max_change) : 0;

  // --- beam layout -----------------------------------------------------------
  double m[3][3];
  bool beam_is_y[io::kInterferometerAxes];
  double mirror_pm[io::kInterferometerAxes];
  for (int b = 0; b < io::kInterferometerAxes; ++b) {
    const BeamConfig& beam = config.beam[b];
    if (beam.sign != 1 && beam.sign != -1) return SensorsToPoseError::kBadBeamSign;
    s.signed_lsb_pm[b] = static_cast<double>(beam.sign) * s.lsb_pm;
    beam_is_y[b] = beam.axis == BeamAxis::kY;
    mirror_pm[b] = beam.mirror_distance_m * 1e12;
    // Linear part, units pm per (pm, pm, prad): prad * m = pm.
    if (beam.axis == BeamAxis::kX) {
      m[b][0] = 1.0;
      m[b][1] = 0.0;
      m[b][2] = -beam.perpendicular_m;
    } else {
      m[b][0] = 0.0;
      m[b][1] = 1.0;
      m[b][2] = beam.perpendicular_m;
    }
  }
  double inv[3][3];
  if (!Invert3(m, inv)) return SensorsToPoseError::kSingularBeamLayout;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.inv_beam[r][c] = inv[r][c];
  s.abbe_cosine_correction = config.abbe_cosine_correction;
  // The closed form's pair and single beam. Invert3 refused three beams
  // along one axis, so exactly two share one.
  {
    int ys = 0;
    for (int b = 0; b < 3; ++b) ys += beam_is_y[b] ? 1 : 0;
    const bool pair_is_y = ys == 2;
    int pair[2] = {-1, -1}, single = -1;
    for (int b = 0; b < 3; ++b) {
      if (beam_is_y[b] == pair_is_y) {
        pair[pair[0] < 0 ? 0 : 1] = b;
      } else {
        single = b;
      }
    }
    const auto p_pm = [&config](int b) { return config.beam[b].perpendicular_m * 1e12; };
    // Along Y: m_a - m_b = (p_a - p_b) t + ...; along X: (p_b - p_a) t + ...
    double dp = pair_is_y ? p_pm(pair[0]) - p_pm(pair[1]) : p_pm(pair[1]) - p_pm(pair[0]);
    if (dp < 0.0) {
      const int k = pair[0];
      pair[0] = pair[1];
      pair[1] = k;
      dp = -dp;
    }
    if (!(dp > 0.0) || single < 0) return SensorsToPoseError::kSingularBeamLayout;
    s.pair_a = static_cast<std::uint8_t>(pair[0]);
    s.pair_b = static_cast<std::uint8_t>(pair[1]);
    s.single = static_cast<std::uint8_t>(single);
    s.pair_is_y = pair_is_y;
    s.pair_dp_pm = dp;
    s.pair_dp2_pm2 = dp * dp;
    s.pair_two_dd_pm = 2.0 * (mirror_pm[pair[0]] - mirror_pm[pair[1]]);
    const double p_pair = 0.5 * (p_pm(pair[0]) + p_pm(pair[1]));
    const double half_d_pair = 0.25 * (mirror_pm[pair[0]] + mirror_pm[pair[1]]);
    const double half_d_single = 0.5 * mirror_pm[single];
    s.p_x_pm = pair_is_y ? p_pm(single) : p_pair;
    s.half_d_x_pm = pair_is_y ? half_d_single : half_d_pair;
    s.p_y_pm = pair_is_y ? p_pair : p_pm(single);
    s.half_d_y_pm = pair_is_y ? half_d_pair : half_d_single;
  }

  // --- laser displacement sensors: z_i = z + theta_x*y_i - theta_y*x_i ------
  if (!(config.displacement_scale_m_per_V > 0.0) || !(config.adc_full_scale_V > 0.0) ||
      config.adc_rail_code <= 0) {
    return SensorsToPoseError::kBadDisplacementScale;
  }
  s.lds_zero_pm = config.displacement_zero_height_m * 1e12;
  s.lds_gain_pm = config.displacement_scale_m_per_V * config.adc_full_scale_V / 32768.0 * 1e12;
  double p[3][3];
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    p[i][0] = 1.0;
    p[i][1] = config.displacement_sensor_y_m[i];
    p[i][2] = -config.displacement_sensor_x_m[i];
  }
  if (!Invert3(p, inv)) return SensorsToPoseError::kSingularDisplacementLayout;
  if (config.lds_z_point > 1) return SensorsToPoseError::kBadZPoint;
  if (config.lds_z_point == 1) {
    // z at the sensors' centroid (xc, yc): z + theta_x yc - theta_y xc of
    // the plane, one row of weights (1/3 each up to rounding: the plane
    // passes through the three heights).
    double xc = 0.0, yc = 0.0;
    HeightSensorCentroid(config, &xc, &yc);
    for (int c = 0; c < 3; ++c) inv[0][c] = inv[0][c] + yc * inv[1][c] - xc * inv[2][c];
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.inv_plane[r][c] = inv[r][c];
  s.adc_rail_code = config.adc_rail_code;

  // --- Hall / pitch ------------------------------------------------------------
  if (!(config.pitch_m > 1e-4 && config.pitch_m < 1.0)) return SensorsToPoseError::kBadPitch;
  s.pitch_pm = RoundToInt64(config.pitch_m * 1e12);
  // A phase monotonic with margin: where the Hall solve's fixed 7 steps
  // still converge (HallSolveStep; for the 5th alone eps_5 < 0.19).
  bool harmonics_ok = true;
  for (double r : config.hall_harmonic_ratio) harmonics_ok = harmonics_ok && r >= 0.0 && r < 1.0;
  if (!harmonics_ok || !(HallPhaseSlopeMin(config.hall_harmonic_ratio) >= kHallPhaseSlopeMin) ||
      !(config.hall_min_amplitude_codes >= 0.0) ||
      !(config.hall_max_amplitude_codes > config.hall_min_amplitude_codes)) {
    return SensorsToPoseError::kBadHallConfig;
  }
  s.hall_a_x_pm = RoundToInt64(config.hall_a_x_m * 1e12);
  s.hall_a_y_pm = RoundToInt64(config.hall_a_y_m * 1e12);
  for (int k = 0; k < kHallHarmonics; ++k) s.hall_harmonic_ratio[k] = config.hall_harmonic_ratio[k];
  s.hall_min_amplitude_codes = config.hall_min_amplitude_codes;
  s.hall_max_amplitude_codes = config.hall_max_amplitude_codes;

  // --- LDS target-step repair ---------------------------------------------------
  if (!(config.lds_target_cell_m >= 0.0 && config.lds_target_cell_m < 1.0) || config.lds_target_repair > 1) {
    return SensorsToPoseError::kBadTargetStepRepair;
  }
  // Switched off: as with no cell (the cell itself stays checked above).
  const double cell_m = config.lds_target_repair != 0 ? config.lds_target_cell_m : 0.0;
  const double step_min_m = static_cast<double>(config.lds_target_step_min_um) / 1e6;
  const double window_m = static_cast<double>(config.lds_target_window_um) / 1e6;
  // Checked whether or not the repair is on: a value written while it is
  // off must not be refused only when it is turned on.
  if (!(step_min_m >= 1e-7 && step_min_m <= 1e-3) || !(window_m > 0.0 && window_m < 0.5)) {
    return SensorsToPoseError::kBadTargetStepRepair;
  }
  if (cell_m > 0.0 && !(window_m < 0.5 * cell_m)) {
    return SensorsToPoseError::kBadTargetStepRepair;
  }
  s.lds_cell_pm = cell_m * 1e12;
  s.lds_inv_cell_per_pm = cell_m > 0.0 ? 1.0 / s.lds_cell_pm : 0.0;
  // In ADC codes (at least one: the minimum is validated > 0): the tick compares codes.
  s.lds_step_min_codes =
      cell_m > 0.0 ? static_cast<std::int32_t>(std::ceil(step_min_m * 1e12 / s.lds_gain_pm)) : 0;
  if (s.lds_step_min_codes < 0 || s.lds_step_min_codes > 16384) return SensorsToPoseError::kBadTargetStepRepair;
  s.lds_step_min_pm = static_cast<double>(s.lds_step_min_codes) * s.lds_gain_pm;
  s.lds_window_pm = window_m * 1e12;
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    s.lds_sensor_x_pm[i] = config.displacement_sensor_x_m[i] * 1e12;
    s.lds_sensor_y_pm[i] = config.displacement_sensor_y_m[i] * 1e12;
  }

  s.seeded = false;
  s.homed = false;
  *state = s;
  return SensorsToPoseError::kOk;
}

bool ExtendCounter(std::uint32_t raw, std::uint32_t* last_raw, std::int64_t* counts,
                   std::int64_t max_counts_per_tick) {
  // A magnitude is at most 2^31: a bound at or above 2^32 - 1 is that bound,
  // and a negative one takes nothing.
  if (max_counts_per_tick < 0) return false;
  const auto max_step = static_cast<std::uint32_t>(max_counts_per_tick < 0xFFFFFFFF ? max_counts_per_tick : 0xFFFFFFFF);
  const CounterStep c = StepCounter(raw, *last_raw, max_step);
  *counts += c.moved;
  *last_raw = c.plausible ? raw : *last_raw;
  return c.plausible;
}

std::int64_t CountsToPicometres(std::int64_t counts, const SensorsToPoseState& state) {
  // counts * num / den exactly: counts = q*den + r, 0 <= r < den, so
  // counts*num/den = q*num + r*num/den with r*num < 2^62. Then round half
  // away from zero on the fractional part (symmetric about zero).
  const std::int64_t q = wide::FloorDiv(counts, state.lsb_den);
  const std::int64_t r = counts - q * state.lsb_den;
  const std::int64_t rn = r * state.lsb_num;
  const std::int64_t whole = rn / state.lsb_den;
  const std::int64_t frac2 = 2 * (rn - whole * state.lsb_den);  // twice the remainder
  // value = q*num + whole + rem/den; rem/den in [0, 1).
  const std::int64_t base = q * state.lsb_num + whole;
  // Non-negative value: round up if rem/den >= 1/2. Negative value (base < 0
  // with a remainder): the magnitude's fraction is 1 - rem/den; rounding away
  // from zero means rounding down (keeping base) if rem/den <= 1/2.
  const bool negative = base < 0;
  const bool up = negative ? (frac2 > state.lsb_den) : (frac2 >= state.lsb_den);
  return base + (up ? 1 : 0);
}

void ReseedInterferometers(SensorsToPoseState* state) {
  state->seeded = false;
  state->homed = false;
  state->jump_latched = 0;
  state->steps_seen = 0;
}

namespace {

// A laser displacement reading at an ADC rail: code >= rail or
// code <= -rail - 1, i.e. outside [-rail, rail - 1], as one unsigned
// compare (rail is in (0, 32767], so code + rail and 2 rail - 1 are
// nonnegative int32 where code is inside; a code below -rail wraps to a
// large unsigned value).
bool LdsCodeAtRail(std::int16_t code, const SensorsToPoseState& s) {
  const std::int32_t rail = s.adc_rail_code;
  return static_cast<std::uint32_t>(std::int32_t{code} + rail) > static_cast<std::uint32_t>(2 * rail - 1);
}

// The laser displacement sensors' out-of-range status bits, bit i = sensor i
// (io::kDisplacementOutOfRange0..2 are three consecutive bits).
static_assert(io::kDisplacementOutOfRange1 == io::kDisplacementOutOfRange0 << 1 &&
              io::kDisplacementOutOfRange2 == io::kDisplacementOutOfRange0 << 2);
std::uint8_t LdsOutOfRangeBits(std::uint16_t status_flags) {
  return static_cast<std::uint8_t>((status_flags / io::kDisplacementOutOfRange0) & 7u);
}

// A laser displacement reading out of range (its status bit) or at an ADC rail.
bool LdsReadingBad(const io::SensorSample& sample, int i, const SensorsToPoseState& s) {
  return LdsCodeAtRail(sample.displacement_adc[i], s) || (LdsOutOfRangeBits(sample.status_flags) & (1u << i)) != 0;
}

// The rare part of the LDS target-step repair (SensorsToPoseConfig::lds_target_*):
// sensor i's reading changed by jump_codes this tick, or a repaired step is
// held at its edge.
[[gnu::noinline, gnu::cold]] void RepairTargetStep(int i, std::int32_t jump_codes, bool jumped,
                                                    const io::SensorSample& sample, SensorsToPoseState* state,
                                                    PoseMeasurement* out) {
  SensorsToPoseState& s = *state;
  const std::uint8_t bit = static_cast<std::uint8_t>(1u << i);
  if ((s.lds_tracked & bit) == 0 || LdsReadingBad(sample, i, s) || !s.homed) return;
  const double jump = static_cast<double>(jump_codes) * s.lds_gain_pm;
  const double x_pm = s.lds_last_x_pm, y_pm = s.lds_last_y_pm;
  const double held = (s.lds_held & bit) != 0 ? s.lds_held_pm[i] : 0.0;
  // Spot in the magnet frame (homed x, y; theta_z moves it by less than the
  // window) and the nearest block edge: its index along x or y (edge k at k
  // cells) and the spot's distance to it.
  const double sx = x_pm + numeric::Int64ToDouble(s.home_offset_x_pm) + s.lds_sensor_x_pm[i];
  const double sy = y_pm + numeric::Int64ToDouble(s.home_offset_y_pm) + s.lds_sensor_y_pm[i];
  const double fx = sx * s.lds_inv_cell_per_pm, fy = sy * s.lds_inv_cell_per_pm;
  const double kx = std::floor(fx + 0.5), ky = std::floor(fy + 0.5);
  const double dx = std::fabs(fx - kx) * s.lds_cell_pm, dy = std::fabs(fy - ky) * s.lds_cell_pm;
  const bool along_x = dx <= dy;
  const double edge = along_x ? kx : ky;
  const double dist = along_x ? dx : dy;
  // The edge of the step held, if any: is the spot still within its window?
  const double held_dist = std::fabs((s.lds_held_along_x[i] ? fx : fy) - s.lds_held_edge[i]) * s.lds_cell_pm;
  const bool at_held_edge = held != 0.0 && held_dist < s.lds_window_pm;
  // One step per edge visit, or one that undoes the step held (a spot that
  // went back over the edge, or dithers on it): a second step the same way
  // at the same edge is the platen moving (a fall, a touchdown), which must
  // reach the loops and the supervisor.
  const double undo = jump + held;
  const bool same_edge = at_held_edge && (s.lds_held_along_x[i] != 0) == along_x && s.lds_held_edge[i] == edge;
  const bool allowed = !same_edge || (undo < s.lds_step_min_pm && undo > -s.lds_step_min_pm);
  if (jumped && dist < s.lds_window_pm && allowed) {
    s.lds_offset_pm[i] -= jump;
    s.lds_held_pm[i] = jump;
    s.lds_held = static_cast<std::uint8_t>(s.lds_held | bit);
    s.lds_held_along_x[i] = along_x ? 1u : 0u;
    s.lds_held_edge[i] = edge;
    out->lds_target_step = static_cast<std::uint8_t>(out->lds_target_step | bit);
    if (s.lds_steps_repaired != 0xFFFFFFFFu) ++s.lds_steps_repaired;
  } else if (!at_held_edge) {
    s.lds_held = static_cast<std::uint8_t>(s.lds_held & ~bit);
  }
}

}  // namespace

namespace {

// One beam's raw step this tick and what the counter rule reads of it.
struct BeamStep {
  std::uint32_t raw;
  std::int32_t step;       // modular raw - last_raw
  std::int32_t last_step;  // the last fresh step per tick
  std::uint32_t speed_mag;  // |last_step|
  bool in_speed;            // |step| <= max_step
};
[[gnu::always_inline]] inline BeamStep ReadBeamStep(const io::SensorSample& sample, const SensorsToPoseState& s,
                                                    int b, std::uint32_t max_step) {
  BeamStep t;
  t.raw = sample.interferometer_counts[b];
  t.step = static_cast<std::int32_t>(t.raw - s.last_raw[b]);
  t.last_step = s.last_step[b];
  t.speed_mag = UnsignedMagnitude(t.last_step);
  t.in_speed = UnsignedMagnitude(t.step) <= max_step;
  return t;
}

// The step taken into the extended count, the flags, and the beam's reading
// in pm.
[[gnu::always_inline]] inline void FinishBeam(int b, bool glitch, bool ok, std::int32_t moved, std::int64_t change,
                                              SensorsToPoseState* state, PoseMeasurement* out, double* meas_pm) {
  SensorsToPoseState& s = *state;
  s.counts[b] += static_cast<double>(moved);  // integers below 2^53: exact
  out->beam_glitch = static_cast<std::uint8_t>(out->beam_glitch | (glitch ? (1u << b) : 0u));
  out->glitch_counts[b] = glitch ? change : 0;
  s.jump_latched = static_cast<std::uint8_t>(s.jump_latched | (ok ? 0u : (1u << b)));
  // counts * lsb in double: the product's rounding is < 1e-4 pm anywhere
  // within a metre of travel.
  meas_pm[b] = s.counts[b] * s.signed_lsb_pm[b];
}

}  // namespace

PoseMeasurement SensorsToPoseStep(const io::SensorSample& sample, SensorsToPoseState* state) {
  SensorsToPoseState& s = *state;
  PoseMeasurement out;  // every field is written below (no memset per tick)
  out.beam_glitch = 0;
  out.lds_target_step = 0;
  // A stale sample repeats the previous one (the transport had nothing new):
  // not a step of the mirror, nor of a displacement reading.
  const bool stale = (sample.status_flags & io::kStaleFrame) != 0;

  // --- laser displacement sensors' target steps (lds_target_*) -------------------
  // First, while little else is live: per sensor one subtraction and a
  // compare of ADC codes; the rest (RepairTargetStep) only on a jump, or
  // while a repaired step is held at its edge. It places the spot with the
  // previous tick's x, y (at 2 m/s 0.8 mm from this tick's, inside the
  // window's margin).
  if (s.lds_step_min_codes != 0 && !stale) {
    for (int i = 0; i < io::kDisplacementSensors; ++i) {
      const std::int32_t code = sample.displacement_adc[i];
      const std::int32_t jump = code - s.lds_last_code[i];
      s.lds_last_code[i] = static_cast<std::int16_t>(code);
      // |jump| > min as one unsigned compare.
      const bool jumped = static_cast<std::uint32_t>(jump + s.lds_step_min_codes) >
                          static_cast<std::uint32_t>(2 * s.lds_step_min_codes);
      if (jumped || (s.lds_held & (1u << i)) != 0) RepairTargetStep(i, jump, jumped, sample, &s, &out);
    }
  }

  // --- counters ----------------------------------------------------------------
  // Counts and their steps are int32 wherever they fit: a step is a 32-bit
  // counter difference, and a kept step (last_step) is at most
  // max_counts_per_tick < 1e9 (ApplySensorsToPoseConfig) in magnitude. Only
  // the extended count and the n-tick prediction after a stale gap need
  // int64 (each int64 operation is two to four M7 instructions).
  const bool seed = !s.seeded;
  if (seed) {  // once per (re)seed: this sample is the counters' zero
    s.steps_seen = 0;
    s.stale_gap = 0;
    for (int b = 0; b < io::kInterferometerAxes; ++b) {
      s.last_raw[b] = sample.interferometer_counts[b];
      s.counts[b] = 0.0;
      s.last_step[b] = 0;
    }
  }
  // After stale samples the next fresh sample's step covers n = stale_gap + 1
  // ticks.
  const std::int32_t n = std::int32_t{s.stale_gap} + 1;
  // The acceleration check needs two real steps after the seed (the seed's
  // own step is zero by construction), and a fresh sample.
  const bool armed = s.max_counts_step_change > 0 && s.steps_seen >= 2 && !stale;
  const auto max_step = static_cast<std::uint32_t>(s.max_counts_per_tick);      // < 1e9
  const auto max_change = static_cast<std::uint32_t>(s.max_counts_step_change);  // <= max_step
  double meas_pm[3];
  // The two loops below share their first and last steps (BeamStep,
  // FinishBeam); they are apart because GCC does not unswitch the one loop
  // on n (measured: +41 M7 instructions a tick as one loop).
  if (n == 1) {
    // Every tick but the first after a stale gap: the general form below
    // with n = 1, in 32 bits and with what follows from it spelled out (the
    // same values for every input, test
    // SensorsToPose.TheCounterRuleOnEveryTickEqualsItsGeneralForm; GCC did
    // not derive them: ~35 M7 instructions a beam):
    //  * not a glitch: used = raw, so the counter's step is `step` itself,
    //    taken when in_speed (ok = in_speed);
    //  * a glitch: used = last_raw + last_step, so the step is last_step,
    //    taken when |last_step| <= max_step;
    //  * last_raw becomes raw on a glitch or a taken step, else stays;
    //  * the per-tick step is the step taken (no mean over a gap).
    // Within the speed bound |step| and |last_step| are below 1e9, so
    // step - last_step is an exact int32 (the wrapped difference is read only
    // then), and max_change + speed_mag < 2^31.
    for (int b = 0; b < io::kInterferometerAxes; ++b) {
      const BeamStep t = ReadBeamStep(sample, s, b, max_step);
      const auto change = static_cast<std::int32_t>(static_cast<std::uint32_t>(t.step) -
                                                    static_cast<std::uint32_t>(t.last_step));
      const bool glitch = armed && t.in_speed && UnsignedMagnitude(change) > max_change + t.speed_mag;
      const bool ok = glitch ? t.speed_mag <= max_step : t.in_speed;
      const std::int32_t moved = ok ? (glitch ? t.last_step : t.step) : 0;
      if (glitch || t.in_speed) s.last_raw[b] = t.raw;
      s.last_step[b] = stale ? t.last_step : moved;
      FinishBeam(b, glitch, ok, moved, change, &s, &out, meas_pm);
    }
  } else {
    // The first fresh sample after a stale gap: its step covers n > 1 ticks.
    for (int b = 0; b < io::kInterferometerAxes; ++b) {
      const BeamStep t = ReadBeamStep(sample, s, b, max_step);
      // A step within the speed bound that differs from the one the last step
      // predicts (n of them) by more than any actuator can make it, over n
      // ticks, plus one tick's worth of steps (a sample that reaches the
      // kernel a tick early or late over a link: its step is then one tick
      // longer or shorter) is a glitch: lost or spurious fringes, a jumped
      // counter. Count the predicted step instead and take the rest as an
      // offset of the raw counter, so that a jump that stays, or one that
      // comes back, leaves the pose where the mirror is.
      const std::int64_t expected = std::int64_t{n} * t.last_step;
      const std::int64_t tolerance = std::int64_t{max_change} * n * n + t.speed_mag;
      const std::int64_t change = t.step - expected;
      const std::int64_t change_mag = change < 0 ? -change : change;
      const bool glitch = armed && t.in_speed && change_mag > tolerance;
      const std::uint32_t used = glitch ? s.last_raw[b] + static_cast<std::uint32_t>(expected) : t.raw;
      // ExtendCounter's rule, with the step it took kept in int32.
      const CounterStep counted = StepCounter(used, s.last_raw[b], max_step);
      s.last_raw[b] = glitch ? t.raw : (counted.plausible ? used : s.last_raw[b]);
      // The step per tick: the gap's mean step, truncated toward zero. In
      // double: an integer division is a library call on the M7. Exact:
      // |moved| < 2^31 n, and a non-integer moved/n lies at least 1/n from an
      // integer, far beyond double's rounding.
      const double mean_step = static_cast<double>(counted.moved) / static_cast<double>(n);
      const auto truncated = static_cast<std::int32_t>(mean_step);  // VCVT truncates toward zero
      s.last_step[b] = stale ? t.last_step : truncated;
      FinishBeam(b, glitch, counted.plausible, counted.moved, change, &s, &out, meas_pm);
    }
  }
  const bool counted = !stale || seed;
  s.steps_seen = static_cast<std::uint8_t>(counted && s.steps_seen < 2 ? s.steps_seen + 1 : s.steps_seen);
  s.stale_gap = static_cast<std::uint8_t>(stale && !seed ? (s.stale_gap < 255 ? s.stale_gap + 1 : 255) : 0);
  s.seeded = true;

  // --- beam solve, closed form ---------------------------------------------------
  // The beams read (sign applied; t = tan theta_z, the mirror's slope):
  //   X beam at y = p:  m = x + (y - p) t + d t^2 / 2
  //   Y beam at x = p:  m = y + (p - x) t + d t^2 / 2
  // Two beams share an axis; their difference holds t alone:
  //   (dd / 2) t^2 + dp t = m_a - m_b   (dp > 0: the configuration orders them),
  // whose root near (m_a - m_b) / dp is t = 2 dm / (dp + sqrt(dp^2 + 2 dd dm))
  // (exactly dm / dp when the mirrors are equally far: sqrt(dp^2) = dp in
  // IEEE arithmetic). Then x and y from the x row and the y row (the single
  // beam and the pair's mean):
  //   x + t y = m_X + t (p_X - t d_X / 2),  y - t x = m_Y - t (p_Y + t d_Y / 2),
  //   det = 1 + t^2.
  // The exact solution of the model, where the three fixed-point passes it
  // replaces (issue 16: "a closed-form or single-pass beam solve") were
  // within 5.4 pm of it at the corners of the travel; what is left is the
  // double arithmetic (< 1e-3 pm) and the final rounding to whole pm (0.5 pm).
  // One square root and one division, no data-dependent loop.
  double est[3];
  double theta_z_prad;
  if (s.abbe_cosine_correction) {
    const double dm = meas_pm[s.pair_a] - meas_pm[s.pair_b];
    const double t = 2.0 * dm / (s.pair_dp_pm + std::sqrt(s.pair_dp2_pm2 + s.pair_two_dd_pm * dm));
    const double m_pair = 0.5 * (meas_pm[s.pair_a] + meas_pm[s.pair_b]);
    const double m_single = meas_pm[s.single];
    const double m_x = s.pair_is_y ? m_single : m_pair;
    const double m_y = s.pair_is_y ? m_pair : m_single;
    const double r_x = m_x + t * (s.p_x_pm - t * s.half_d_x_pm);
    const double r_y = m_y - t * (s.p_y_pm + t * s.half_d_y_pm);
    const double inv_det = 1.0 / (1.0 + t * t);
    est[0] = (r_x - t * r_y) * inv_det;
    est[1] = (r_y + t * r_x) * inv_det;
    est[2] = t * 1e12;
    // The beams see tan(theta_z) (the mirror's slope): theta = atan(t) = t - t^3/3
    // (+ t^5/5 < 1.4e-13 rad at 3.72 mrad). Without it: 1.7e-8 rad at the travel limit.
    const double t_rad = est[2] * 1e-12;
    theta_z_prad = est[2] - est[2] * (t_rad * t_rad) / 3.0;
  } else {
    // The linear inverse alone (abbe_cosine_correction off).
#pragma GCC unroll 3
    for (int r = 0; r < 3; ++r) {
      est[r] = s.inv_beam[r][0] * meas_pm[0] + s.inv_beam[r][1] * meas_pm[1] + s.inv_beam[r][2] * meas_pm[2];
    }
    theta_z_prad = est[2];
  }

  // --- laser displacement plane fit ------------------------------------------
  double h[3];
  // A bad reading: out of range (its status bit) or at an ADC rail.
  std::uint8_t lds_bad = LdsOutOfRangeBits(sample.status_flags);
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    h[i] = s.lds_zero_pm + static_cast<double>(sample.displacement_adc[i]) * s.lds_gain_pm;
    lds_bad = static_cast<std::uint8_t>(lds_bad | (LdsCodeAtRail(sample.displacement_adc[i], s) ? (1u << i) : 0u));
  }
  if (s.lds_step_min_codes != 0 && !stale) {
    // The offsets of the target-step repair (below), and the track: a bad
    // reading is not compared with the next one.
    for (int i = 0; i < io::kDisplacementSensors; ++i) h[i] += s.lds_offset_pm[i];
    s.lds_tracked = static_cast<std::uint8_t>(~lds_bad & 7u);
  }
  double plane[3];
  for (int r = 0; r < 3; ++r) {
    plane[r] = s.inv_plane[r][0] * h[0] + s.inv_plane[r][1] * h[1] + s.inv_plane[r][2] * h[2];
  }

  out.pose_unhomed[Axis::kX] = numeric::RoundToInt64(est[0]);
  out.pose_unhomed[Axis::kY] = numeric::RoundToInt64(est[1]);
  s.lds_last_x_pm = est[0];
  s.lds_last_y_pm = est[1];
  out.pose_unhomed[Axis::kZ] = numeric::RoundToInt64(plane[0]);
  out.pose_unhomed[Axis::kThetaX] = numeric::RoundToInt64(plane[1]);
  out.pose_unhomed[Axis::kThetaY] = numeric::RoundToInt64(plane[2]);
  out.pose_unhomed[Axis::kThetaZ] = numeric::RoundToInt64(theta_z_prad);
  ApplyHomingOffsets(s, &out);

  // --- validity ------------------------------------------------------------------
  // Every in-plane axis uses every beam (the solve and the Abbe terms couple
  // them), every out-of-plane axis every displacement sensor (plane fit).
  out.beam_loss = static_cast<std::uint8_t>(sample.status_flags & (io::kBeamLoss0 | io::kBeamLoss1 | io::kBeamLoss2));
  out.beam_jump = s.jump_latched;
  out.displacement_bad = lds_bad;
  out.adc_fault = (sample.status_flags & io::kAdcFault) != 0;
  out.stale_frame = (sample.status_flags & io::kStaleFrame) != 0;
  const bool in_plane_ok = out.beam_loss == 0 && out.beam_jump == 0 && !out.stale_frame;
  const bool out_of_plane_ok = lds_bad == 0 && !out.adc_fault && !out.stale_frame;
  out.valid_axes = static_cast<std::uint8_t>((in_plane_ok ? kPoseValidInPlane : 0u) |
                                             (out_of_plane_ok ? kPoseValidOutOfPlane : 0u));
  return out;
}

// ---------------------------------------------------------------------------
// Hall / homing (not per tick)
// ---------------------------------------------------------------------------
namespace {

std::uint32_t RadToTurn(double rad) {
  double t = rad / (2.0 * io::stage::kPi);
  t -= std::floor(t);
  // [0,1) -> [0, 2^32), wrapping 1.0 to 0.
  const double scaled = std::floor(t * 4294967296.0 + 0.5);
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(scaled) & 0xffffffffu);
}

}  // namespace

// Phase of  B + jA = e^{j theta} w(theta),
//   w(theta) = 1 - eps_5 e^{j4 theta} + eps_9 e^{j8 theta} - eps_13 e^{j12 theta}
// (eq (1): harmonic n = 4k + 1 has sign (-1)^k). atan2 gives
// phi = theta + arg w(theta), so theta solves f(theta) = theta + arg w - phi = 0,
//   f'(theta) = 1 + Im(w'/w) = 1 + Re(u conj(w)) / |w|^2,
//   u = sum_k (-1)^k 4k eps e^{j4k theta}   (w' = j u).
// Configuration refuses harmonics whose least f' over a pitch is below 0.2
// (HallPhaseSlopeMin, kHallPhaseSlopeMin; the seed's three at 1.6 mm give
// 0.63). Step 0
// is one fixed-point pass (theta = phi - arg w), steps 1..6 are Newton steps.
// Measured on exact phases (kernel_sensors_to_pose_test,
// HallSolveConvergesOverTheValidHarmonicRange): after all 7 steps the error is
// at the double floor (< 2e-14 rad) wherever the least slope is >= 0.2 (Hall
// heights 0.5-6 mm over arrays of thickness pitch/8 .. pitch/2, the 5th alone
// up to 0.165). Plain Newton from phi diverges near the bound, hence the
// fixed-point pass first. The 9th and 13th cost one complex product
// each per step (the angle-multiplied e^{j8 theta}, e^{j12 theta}).
void HallSolveStep(HallSolve* solve) {
  HallSolve& h = *solve;
  if (h.steps >= kHallSolveSteps) return;
  for (int a = 0; a < 2; ++a) {
    const double th = h.theta[a];
    const HallW w = HallWOf(h.eps, numeric::dcos(4.0 * th), numeric::dsin(4.0 * th));
    const double arg = numeric::datan2(w.wi, w.wr);
    if (h.steps == 0) {
      h.theta[a] = h.phi[a] - arg;
    } else {
      h.theta[a] = th - (th + arg - h.phi[a]) / HallSlope(w);
    }
  }
  ++h.steps;
}

HallSolveInputs HallSolveInputsOf(const io::SensorSample& sample, const SensorsToPoseState& state) {
  HallSolveInputs in{};
  for (int i = 0; i < io::kHallChannels; ++i) in.hall_adc[i] = sample.hall_adc[i];
  in.status_flags = sample.status_flags;
  in.adc_rail_code = state.adc_rail_code;
  for (int k = 0; k < kHallHarmonics; ++k) in.eps[k] = state.hall_harmonic_ratio[k];
  in.min_amplitude_codes = state.hall_min_amplitude_codes;
  in.max_amplitude_codes = state.hall_max_amplitude_codes;
  in.pitch_pm = state.pitch_pm;
  in.hall_a_x_pm = state.hall_a_x_pm;
  in.hall_a_y_pm = state.hall_a_y_pm;
  return in;
}

void HallSolveBegin(const HallSolveInputs& in, HallSolve* solve) {
  HallSolve h{};
  const double a_x = in.hall_adc[0];
  const double a_y = in.hall_adc[1];
  const double b_x = in.hall_adc[2];
  const double b_y = in.hall_adc[3];
  for (int k = 0; k < kHallHarmonics; ++k) h.eps[k] = in.eps[k];
  h.phi[0] = numeric::datan2(a_x, b_x);
  h.phi[1] = numeric::datan2(a_y, b_y);
  h.theta[0] = h.phi[0];
  h.theta[1] = h.phi[1];
  h.steps = 0;
  HallPhase& out = h.result;
  out.amplitude_x_codes = std::sqrt(a_x * a_x + b_x * b_x);
  out.amplitude_y_codes = std::sqrt(a_y * a_y + b_y * b_y);
  bool railed = false;
  for (int i = 0; i < io::kHallChannels; ++i) {
    const std::int16_t c = in.hall_adc[i];
    railed = railed || c >= in.adc_rail_code || c <= -in.adc_rail_code - 1;
  }
  const auto in_range = [&in](double amp) {
    return amp >= in.min_amplitude_codes && amp <= in.max_amplitude_codes;
  };
  out.plausible = !railed && (in.status_flags & io::kAdcFault) == 0 &&
                  in_range(out.amplitude_x_codes) && in_range(out.amplitude_y_codes);
  *solve = h;
}

HallPhase HallSolveFinish(HallSolve* solve) {
  while (solve->steps < kHallSolveSteps) HallSolveStep(solve);
  HallPhase out = solve->result;
  out.phase_x_turn = RadToTurn(solve->theta[0]);
  out.phase_y_turn = RadToTurn(solve->theta[1]);
  return out;
}

HallPhase HallSolveRun(const HallSolveInputs& in) {
  HallSolve h;
  HallSolveBegin(in, &h);
  return HallSolveFinish(&h);
}

MAGLEV_CONFIG_CODE HallPhase HallToPhase(const io::SensorSample& sample, const SensorsToPoseState& state) {
  return HallSolveRun(HallSolveInputsOf(sample, state));
}

std::int64_t HallCoarsePosition_pm(std::uint32_t phase_turn, std::int64_t sensor_offset_pm,
                                   std::int64_t pitch_pm) {
  // phase * pitch / 2^32 exactly rounded (128-bit product), minus the sensor's
  // platen-frame offset, reduced into [0, pitch).
  const std::int64_t along = MulShiftRound(static_cast<std::int64_t>(phase_turn), pitch_pm, 32);
  return wide::FloorMod(along - sensor_offset_pm, pitch_pm);
}

HomingOffsets ComputeHomingOffsets(const HallPhase& hall, const Pose64& pose_unhomed, const HallSolveInputs& in) {
  const std::int64_t p = in.pitch_pm;
  const std::int64_t hx = HallCoarsePosition_pm(hall.phase_x_turn, in.hall_a_x_pm, p);
  const std::int64_t hy = HallCoarsePosition_pm(hall.phase_y_turn, in.hall_a_y_pm, p);
  // offset = hall - ifm (mod p), represented in [-p/2, p/2).
  const auto wrap = [p](std::int64_t v) { return wide::FloorMod(v + p / 2, p) - p / 2; };
  return HomingOffsets{wrap(hx - pose_unhomed[Axis::kX]), wrap(hy - pose_unhomed[Axis::kY])};
}

HomingOffsets ComputeHomingOffsets(const HallPhase& hall, const Pose64& pose_unhomed,
                                   const SensorsToPoseState& state) {
  HallSolveInputs in{};
  in.pitch_pm = state.pitch_pm;
  in.hall_a_x_pm = state.hall_a_x_pm;
  in.hall_a_y_pm = state.hall_a_y_pm;
  return ComputeHomingOffsets(hall, pose_unhomed, in);
}

void ApplyHomingOffsets(const SensorsToPoseState& state, PoseMeasurement* m) {
  m->pose = m->pose_unhomed;
  m->pose[Axis::kX] += state.home_offset_x_pm;
  m->pose[Axis::kY] += state.home_offset_y_pm;
}

void SetHomingOffsets(const HomingOffsets& offsets, SensorsToPoseState* state) {
  state->home_offset_x_pm = offsets.x_pm;
  state->home_offset_y_pm = offsets.y_pm;
  state->homed = true;
}

}  // namespace maglev::kernel
