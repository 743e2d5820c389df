// solenoid_magnet profile -> selfstab kernel configuration (selfstab_config.hpp).
#include "maglev/stage_profile/selfstab_config.hpp"

#include <cmath>
#include <cstring>

#include "maglev/numeric/elementary.hpp"

namespace maglev::stage_profile {
namespace {

namespace ss = maglev::selfstab;
constexpr double kPi = 3.14159265358979323846;

// Paper axis -> profile axis.
constexpr int kProfileAxis[ss::kAxes] = {0, 1, 3, 4, 5, 2};

// Eq (13)'s brackets: the coil pattern of each axis' effort, normalized to
// the first current of the bracket (which is the effort itself). Coils A, B,
// C, dm, dn, em, en, fm, fn. The minimum-norm input for each axis: it moves
// no other axis at the nominal point (the other brackets of (13) sum to 0).
constexpr double kBracket[ss::kAxes][ss::kCoils] = {
    {0, 0, 0, 1, -1, -2, 2, 1, -1},    // x: (dm-dn) - 2(em-en) + (fm-fn)
    {0, 0, 0, 1, -1, 0, 0, -1, 1},     // y: (dm-dn) - (fm-fn)
    {1, 1, 1, 0, 0, 0, 0, 0, 0},       // z: A + B + C
    {1, -0.5, -0.5, 0, 0, 0, 0, 0, 0}, // alpha: A - B/2 - C/2
    {0, 1, -1, 0, 0, 0, 0, 0, 0},      // beta: B - C
    // gamma: -[(dm-dn) + (em-en) + (fm-fn)]: (13)'s gamma gain is negative,
    // so the column is negated and a positive effort turns gamma positive.
    {0, 0, 0, -1, 1, -1, 1, -1, 1},
};

// Solves A x = b in place (n = 6), partial pivoting. false when singular.
bool solve6(double A[6][6], double b[6]) {
  for (int c = 0; c < 6; ++c) {
    int piv = c;
    for (int r = c + 1; r < 6; ++r)
      if (std::fabs(A[r][c]) > std::fabs(A[piv][c])) piv = r;
    if (std::fabs(A[piv][c]) < 1e-12) return false;
    for (int k = 0; k < 6; ++k) {
      const double t = A[c][k];
      A[c][k] = A[piv][k];
      A[piv][k] = t;
    }
    const double tb = b[c];
    b[c] = b[piv];
    b[piv] = tb;
    for (int r = c + 1; r < 6; ++r) {
      const double f = A[r][c] / A[c][c];
      for (int k = c; k < 6; ++k) A[r][k] -= f * A[c][k];
      b[r] -= f * b[c];
    }
  }
  for (int c = 5; c >= 0; --c) {
    double s = b[c];
    for (int k = c + 1; k < 6; ++k) s -= A[c][k] * b[k];
    b[c] = s / A[c][c];
  }
  return true;
}

}  // namespace

int ProfileAxisOfSelfstabAxis(int a) { return (a >= 0 && a < ss::kAxes) ? kProfileAxis[a] : -1; }

double SelfstabAxisGain(const StageProfile& p, int a) {
  const double kip = p.solenoid.force_constant_in_plane_N_per_A;
  const double kop = p.solenoid.force_constant_out_of_plane_N_per_A;
  const double m = p.body.mass_kg;
  const double r1 = p.solenoid.radius_r1_m, r2 = p.solenoid.radius_r2_m;
  switch (a) {
    case ss::kX: return 6.0 * kip / m;  // bracket 12 u, (13): k_ip / (2 m) per A
    case ss::kY: return 2.0 * std::sqrt(3.0) * kip / m;  // 4 (sqrt3/2) k_ip / m
    case ss::kZ: return 3.0 * kop / m;
    case ss::kAlpha: return 1.5 * r1 * kop / p.body.inertia_kgm2[0];
    case ss::kBeta: return std::sqrt(3.0) * r1 * kop / p.body.inertia_kgm2[1];
    case ss::kGamma: return 6.0 * r2 * kip / p.body.inertia_kgm2[2];
    default: return 0.0;
  }
}

ProfileError MakeSelfstabKernelConfig(const StageProfile& p, ss::SelfstabKernelConfig* out) {
  if (p.family != ActuatorFamily::kSolenoidMagnet) return ProfileError::kUnsupportedFamily;
  if (p.name[0] == '\0' || std::memchr(p.name, '\0', sizeof p.name) == nullptr) return ProfileError::kBadName;
  if (!(p.servo_rate_Hz >= 500.0 && p.servo_rate_Hz <= 20000.0)) return ProfileError::kBadServoRate;
  if (!(p.body.mass_kg > 0.0) || !(p.body.inertia_kgm2[0] > 0.0) || !(p.body.inertia_kgm2[1] > 0.0) ||
      !(p.body.inertia_kgm2[2] > 0.0)) {
    return ProfileError::kBadBody;
  }
  if (p.startup[0] != StartupStep::kLiftOffFromDock || p.startup[1] != StartupStep::kReady) {
    return ProfileError::kBadStartup;
  }
  const SolenoidParameters& s = p.solenoid;
  if (!(s.force_constant_in_plane_N_per_A > 0.0) || !(s.force_constant_out_of_plane_N_per_A > 0.0) ||
      !(s.nominal_current_in_plane_A > 0.0) || !(s.nominal_current_out_of_plane_A > 0.0) ||
      !(s.radius_r1_m > 0.0) || !(s.radius_r2_m > 0.0)) {
    return ProfileError::kBadActuatorParameters;
  }
  const Limits& lim = p.limits;
  if (!(lim.peak_current_A > 0.0) || lim.peak_current_A > lim.hardware_current_A) {
    return ProfileError::kLimitsOutsideHardware;
  }
  // Three two-axis PSDs (tangential, vertical): R is the inverse of their
  // first-order sensor matrix. A PSD at angle psi, radius Rr reads
  //   tangential = -sin(psi) x + cos(psi) y + Rr gamma
  //   vertical   = z + Rr (sin(psi) alpha - cos(psi) beta)
  // (a radial beam from the rotor; the LED radius drops out to first order).
  int psd = 0;
  double J[6][6] = {};
  double lsb[6] = {};
  for (int k = 0; k < p.sensor_count; ++k) {
    const Sensor& z = p.sensors[k];
    if (z.kind != SensorKind::kPsd) return ProfileError::kUnsupportedSensors;
    if (psd == 3 || !(z.resolution > 0.0)) return ProfileError::kUnsupportedSensors;
    const double Rr = std::sqrt(z.x_m * z.x_m + z.y_m * z.y_m);
    const double psi = numeric::datan2(z.y_m, z.x_m);
    const double sp = numeric::dsin(psi), cp = numeric::dcos(psi);  // not libm: host and M7 agree
    double* t = J[2 * psd];
    double* v = J[2 * psd + 1];
    t[ss::kX] = -sp;
    t[ss::kY] = cp;
    t[ss::kGamma] = Rr;
    v[ss::kZ] = 1.0;
    v[ss::kAlpha] = Rr * sp;
    v[ss::kBeta] = -Rr * cp;
    lsb[2 * psd] = lsb[2 * psd + 1] = z.resolution;
    ++psd;
  }
  if (psd != 3) return ProfileError::kUnsupportedSensors;
  ss::SelfstabKernelConfig c{};
  for (int ch = 0; ch < 6; ++ch) {
    double A[6][6];
    std::memcpy(A, J, sizeof A);
    double col[6] = {};
    col[ch] = lsb[ch];
    if (!solve6(A, col)) return ProfileError::kAllocationRank;
    for (int a = 0; a < 6; ++a) c.pose_per_code[a][ch] = static_cast<float>(col[a]);
  }
  // The largest code a PSD can give: half its active area in counts. The
  // format has no active area: the paper's 4.7 mm [P] (Section 4) is used,
  // so a 12-bit A/D reads +-2048 at the edges (which counts as off the PSD).
  {
    const double half_area_m = 0.5 * 4.7e-3;
    const double limit = std::floor(half_area_m / lsb[0] + 0.5);
    c.psd_code_limit = static_cast<std::int16_t>(limit > 32767.0 ? 32767.0 : limit);
  }
  c.servo_rate_Hz = static_cast<float>(p.servo_rate_Hz);
  c.feedback_filter_enabled = 0;
  int active = 0;
  double worst_coil_A[ss::kCoils] = {};
  for (int j = 0; j < ss::kCoils; ++j) {
    worst_coil_A[j] = j < 3 ? s.nominal_current_out_of_plane_A : s.nominal_current_in_plane_A;
    c.nominal_current_A[j] = static_cast<float>(worst_coil_A[j]);
  }
  for (int a = 0; a < ss::kAxes; ++a) {
    const Axis& ax = p.axis[kProfileAxis[a]];
    c.role[a] = ax.mode == AxisMode::kActive    ? ss::AxisRole::kActive
                : ax.mode == AxisMode::kPassive ? ss::AxisRole::kPassive
                                                : ss::AxisRole::kAbsent;
    if (ax.mode != AxisMode::kActive) continue;
    ++active;
    const AxisController& k = ax.controller;
    if (k.kind != ControllerKind::kPid2Dof) return ProfileError::kUnsupportedController;
    ss::SelfstabLoopConfig& l = c.loop[a];
    l.kp = static_cast<float>(k.kp);
    l.ki = static_cast<float>(k.ki);
    l.kd = static_cast<float>(k.kd);
    l.derivative_filter_Hz = static_cast<float>(k.derivative_filter_Hz);
    l.effort_limit_A = static_cast<float>(k.effort_limit_A);
    l.travel_min = static_cast<float>(ax.travel_min);
    l.travel_max = static_cast<float>(ax.travel_max);
    l.max_velocity = static_cast<float>(ax.max_velocity);
    l.schedule_points = k.schedule_points;
    for (int i = 0; i < k.schedule_points && i < ss::kMaxSchedulePoints; ++i) {
      l.schedule_at[i] = static_cast<float>(k.schedule[i].at);
      l.kp_scale[i] = static_cast<float>(k.schedule[i].kp_scale);
      l.kd_scale[i] = static_cast<float>(k.schedule[i].kd_scale);
    }
    if (k.filter_count > 1) return ProfileError::kUnsupportedController;
    if (k.filter_count == 1) {
      const Filter& f = k.filters[0];
      if (f.kind != FilterKind::kButterworth2 && f.kind != FilterKind::kLowPass) {
        return ProfileError::kUnsupportedController;
      }
      l.feedback_filter.type = kernel::BiquadType::kLowPass;
      l.feedback_filter.frequency_Hz = static_cast<float>(f.frequency_Hz);
      // A second-order Butterworth is the low-pass with Q = 1/sqrt(2).
      l.feedback_filter.q = f.kind == FilterKind::kButterworth2 ? static_cast<float>(1.0 / std::sqrt(2.0))
                                                                : static_cast<float>(f.q);
      c.feedback_filter_enabled = 1;
    }
    // T: the bracket of (13), and the worst current it can ask for.
    for (int j = 0; j < ss::kCoils; ++j) {
      c.coil_per_effort[j][a] = static_cast<float>(kBracket[a][j]);
      worst_coil_A[j] += std::fabs(kBracket[a][j]) * k.effort_limit_A;
    }
  }
  if (active == 0) return ProfileError::kNoActiveAxis;
  for (double w : worst_coil_A) {
    if (w > lim.peak_current_A) return ProfileError::kLimitsOutsideHardware;
  }
  c.current_limit_A = static_cast<float>(lim.peak_current_A);
  c.dac_A_per_code = static_cast<float>(lim.hardware_current_A / 32767.0);
  // Start-up and landing ramps (ours): slow against the 2..4 Hz passive
  // modes, so the rotor follows its equilibrium off and onto the dock.
  c.liftoff_ramp_s = 1.0f;
  c.liftoff_settle_s = 0.5f;
  c.land_ramp_s = 1.0f;
  *out = c;
  return ProfileError::kOk;
}

}  // namespace maglev::stage_profile
