#include "maglev/stage_profile/apply_profile.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

#include "maglev/axis_loops/defaults.hpp"
#include "maglev/axis_loops/loop_check.hpp"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/elementary.hpp"

namespace maglev::stage_profile {

MAGLEV_ENUM_TO_STRING(ProfileError, MAGLEV_PROFILE_ERRORS)

namespace {

constexpr int kA = kAxes;

bool active(const StageProfile& p, int a) { return p.axis[a].mode == AxisMode::kActive; }

// Eigenvalues of a symmetric n x n matrix (n <= 6), cyclic Jacobi; constant
// work (a fixed number of sweeps), no heap.
void symmetric_eigenvalues(double m[kA][kA], int n, double ev[kA]) {
  for (int sweep = 0; sweep < 30; ++sweep) {
    for (int p = 0; p < n; ++p) {
      for (int q = p + 1; q < n; ++q) {
        if (std::fabs(m[p][q]) < 1e-300) continue;
        const double theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (int k = 0; k < n; ++k) {
          const double mkp = m[k][p], mkq = m[k][q];
          m[k][p] = c * mkp - s * mkq;
          m[k][q] = s * mkp + c * mkq;
        }
        for (int k = 0; k < n; ++k) {
          const double mpk = m[p][k], mqk = m[q][k];
          m[p][k] = c * mpk - s * mqk;
          m[q][k] = s * mpk + c * mqk;
        }
      }
    }
  }
  for (int i = 0; i < n; ++i) ev[i] = m[i][i];
}

// rank and condition of the rows `use` of a (rows x cols), via the
// eigenvalues of the Gram matrix G = A_use A_use^T.
template <std::size_t Cols>
void rank_condition(const double a[kA][Cols], const bool use[kA], int* rank, double* cond) {
  int idx[kA];
  int n = 0;
  for (int r = 0; r < kA; ++r) {
    if (use[r]) idx[n++] = r;
  }
  double g[kA][kA] = {};
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      double s = 0.0;
      for (std::size_t c = 0; c < Cols; ++c) s += a[idx[i]][c] * a[idx[j]][c];
      g[i][j] = s;
    }
  }
  double ev[kA] = {};
  symmetric_eigenvalues(g, n, ev);
  double hi = 0.0, lo = 1e300;
  for (int i = 0; i < n; ++i) hi = std::fmax(hi, ev[i]);
  *rank = 0;
  for (int i = 0; i < n; ++i) {
    if (ev[i] > 1e-12 * hi) {
      ++*rank;
      lo = std::fmin(lo, ev[i]);
    }
  }
  *cond = (*rank == n && n > 0) ? std::sqrt(hi / lo) : 1e300;  // "infinite": rank-deficient
}

// What each sensor observes of the small-motion pose (kernel Axis order).
void observation_row(const Sensor& s, double row[kA]) {
  for (int a = 0; a < kA; ++a) row[a] = 0.0;
  switch (s.kind) {
    case SensorKind::kInterferometer:
    case SensorKind::kLinearEncoder: {
      const double c = numeric::dcos(s.direction_rad), sn = numeric::dsin(s.direction_rad);
      row[0] = c;
      row[1] = sn;
      row[2] = -s.y_m * c + s.x_m * sn;  // theta_z moves the point by theta x (-y, x)
      break;
    }
    case SensorKind::kLaserDisplacement:
    case SensorKind::kPsd:
      row[3] = 1.0;       // z
      row[4] = s.y_m;     // theta_x lifts +y
      row[5] = -s.x_m;    // theta_y lowers +x
      break;
    case SensorKind::kHall:
      break;  // homing only
  }
}

kernel::ForceLayout kernel_layout(ForcerLayout l) {
  switch (l) {
    case ForcerLayout::kSquare: return kernel::ForceLayout::kSquare;
    case ForcerLayout::kTriangle: return kernel::ForceLayout::kTriangular;
    default: return kernel::ForceLayout::kCross;
  }
}

// The allocation part of the kernel configuration for a Halbach profile.
kernel::ForceAllocationConfig allocation_of(const StageProfile& p) {
  kernel::ForceAllocationConfig c = kernel::DefaultForceAllocationConfig();
  const HalbachParameters& h = p.halbach;
  c.layout = kernel_layout(h.layout);
  c.lever_arm_m = h.lever_arm_m;
  if (h.layout == ForcerLayout::kTriangle) c.triangle_alpha_rad = h.triangle_alpha_rad;
  c.pitch_m = h.pitch_m;
  // Coil centres at this pitch (the seed's layout rule: cross and square);
  // the triangle's coil places are not the seed's, so its forces stay at the
  // forcer centres as eq (8) writes them.
  kernel::SetCoilCentreOffsets(&c);
  if (h.layout == ForcerLayout::kTriangle) {
    for (auto& o : c.coil_centre_offset_m) o[0] = o[1] = 0.0;
  }
  c.two_b_star_identified_N_per_A = h.two_b_star_N_per_A;
  c.coil_effective_length_m = h.coil_effective_length_m;
  c.coil_side_width_m = h.coil_side_width_m;
  c.coil_thickness_m = h.coil_thickness_m;
  c.coil_turns = h.coil_turns;
  c.magnet_thickness_m = h.magnet_thickness_m;
  c.nominal_gap_m = h.rest_gap_m;
  // Commutation: a forcer whose centre sits off the platen origin along its
  // thrust axis sees the array's phase shifted by gamma_1 * that offset (the
  // cross layout's forcers sit on the axes: no shift).
  if (h.layout == ForcerLayout::kSquare) {
    const double g1 = 2.0 * io::stage::kPi / h.pitch_m;
    const double along[kernel::kForcers] = {h.lever_arm_m, h.lever_arm_m, -h.lever_arm_m, -h.lever_arm_m};
    for (int j = 0; j < io::kCoils; ++j) c.coil_phase_rad[j] += g1 * along[j / 2];
  }
  c.peak_current_A = p.limits.peak_current_A;
  c.mass_kg = p.body.mass_kg;
  for (int i = 0; i < 3; ++i) c.inertia_kgm2[i] = p.body.inertia_kgm2[i];
  c.gravity_m_per_s2 = p.body.gravity_m_per_s2;
  return c;
}

kernel::BiquadConfig biquad_of(const Filter& f) {
  kernel::BiquadConfig b{};
  switch (f.kind) {
    case FilterKind::kNone: b.type = kernel::BiquadType::kNone; break;
    case FilterKind::kNotch: b.type = kernel::BiquadType::kNotch; break;
    case FilterKind::kLowPass: b.type = kernel::BiquadType::kLowPass; break;
    case FilterKind::kLeadLag: b.type = kernel::BiquadType::kLeadLag; break;
    case FilterKind::kButterworth2: b.type = kernel::BiquadType::kLowPass; break;  // q = 1/sqrt(2)
  }
  b.frequency_Hz = static_cast<float>(f.frequency_Hz);
  b.q = f.kind == FilterKind::kButterworth2 ? 0.7071f : static_cast<float>(f.q);
  b.depth_dB = static_cast<float>(f.depth_dB);
  b.pole_Hz = static_cast<float>(f.pole_Hz);
  return b;
}

}  // namespace

double AxisPlantGain(const StageProfile& p, int a) {
  const double m_eff = p.body.effective_mass_kg[a];
  double inertia = 0.0;
  switch (a) {
    case 0: case 1: case 3: inertia = p.body.mass_kg; break;
    case 2: inertia = p.body.inertia_kgm2[2]; break;
    case 4: inertia = p.body.inertia_kgm2[0]; break;
    default: inertia = p.body.inertia_kgm2[1]; break;
  }
  if (m_eff > 0.0) inertia = m_eff;
  return p.halbach.two_b_star_N_per_A / inertia;
}

LoopMargins AxisLoopMargins(const StageProfile& p, int a) {
  const AxisController& c = p.axis[a].controller;
  kernel::Pid2DofConfig pid{};
  pid.kp = static_cast<float>(c.kp);
  pid.ki = static_cast<float>(c.ki);
  pid.kd = static_cast<float>(c.kd);
  pid.derivative_filter_hz = static_cast<float>(c.derivative_filter_Hz);
  const kernel::LoopPlant plant{AxisPlantGain(p, a), p.axis[a].open_loop_damping_per_s,
                                p.axis[a].open_loop_stiffness_per_s2};
  // The filters the kernel will run are in the loop the check judges.
  kernel::BiquadConfig filters[kernel::kMaxBiquadStages];
  for (int f = 0; f < kernel::kMaxBiquadStages; ++f) {
    filters[f] = f < c.filter_count && f < kMaxFilters ? biquad_of(c.filters[f]) : kernel::BiquadConfig{};
  }
  return kernel::Pid2DofLoopMargins(pid, plant, p.servo_rate_Hz, filters, kernel::kMaxBiquadStages);
}

namespace {
kernel::KernelConfig config_of(const StageProfile& p);

// The larger |end| of an axis' travel: what a symmetric window must hold.
double travel_reach(const StageProfile& p, int a) {
  return std::fmax(std::fabs(p.axis[a].travel_min), std::fabs(p.axis[a].travel_max));
}

double hall_height_m(const Sensor& s) { return s.height_m > 0.0 ? s.height_m : io::stage::kHallHeightAboveMagnets_m; }
double hall_sensitivity_V_per_T(const Sensor& s) {
  return s.sensitivity_V_per_T > 0.0 ? s.sensitivity_V_per_T : io::stage::kHallSensitivity_V_per_T;
}
}  // namespace

HallSwing HallSignalSwing(const StageProfile& p, const Sensor& hall) {
  const HalbachParameters& h = p.halbach;
  HallSwing w{};
  w.height_m = hall_height_m(hall);
  w.sensitivity_V_per_T = hall_sensitivity_V_per_T(hall);
  const double gamma1 = 2.0 * io::stage::kPi / h.pitch_m;
  const double half_width = gamma1 * h.coil_side_width_m / 2.0;
  const double g_thick = gamma1 * h.coil_thickness_m;
  const double side = (numeric::dsin(half_width) / half_width) * ((1.0 - numeric::dexp(-g_thick)) / g_thick);
  // |B_1|: a coil side wider than half a pitch turns S_1 negative.
  w.fundamental_T = std::fabs(h.two_b_star_N_per_A) * numeric::dexp(-gamma1 * (w.height_m - h.rest_gap_m)) /
                    std::fabs(4.0 * h.coil_turns * h.coil_effective_length_m * side);
  const double harmonics = 1.0 + kernel::HalbachHarmonicRatio(5, w.height_m, h.magnet_thickness_m, h.pitch_m) +
                           kernel::HalbachHarmonicRatio(9, w.height_m, h.magnet_thickness_m, h.pitch_m);
  w.peak_V = w.sensitivity_V_per_T * w.fundamental_T * harmonics;
  w.amplitude_fraction = w.sensitivity_V_per_T * w.fundamental_T / io::stage::kAdcFullScale_V;
  w.peak_fraction = w.peak_V / io::stage::kAdcFullScale_V;
  return w;
}

ProfileCheck CheckStageProfile(const StageProfile& p) {
  ProfileCheck r;
  auto fail = [&](ProfileError e, int axis = -1) {
    r.error = e;
    r.axis = static_cast<std::int8_t>(axis);
    return r;
  };
  if (p.name[0] == '\0' || p.name[kNameLength - 1] != '\0') return fail(ProfileError::kBadName);
  // A stored record's counts bound every loop below (a sensor_count of 13
  // read and wrote past the 12-row observation matrix).
  if (p.sensor_count > kMaxSensors) return fail(ProfileError::kUnsupportedSensors);
  if (p.actuator_count > kMaxActuators) return fail(ProfileError::kBadActuatorParameters);
  if (!io::stage::is_supported_servo_rate(p.servo_rate_Hz)) return fail(ProfileError::kBadServoRate);
  if (!(p.body.mass_kg > 0.0) || !(p.body.inertia_kgm2[0] > 0.0) || !(p.body.inertia_kgm2[1] > 0.0) ||
      !(p.body.inertia_kgm2[2] > 0.0)) {
    return fail(ProfileError::kBadBody);
  }
  bool use[kA] = {};
  int n_active = 0;
  for (int a = 0; a < kA; ++a) {
    use[a] = active(p, a);
    n_active += use[a] ? 1 : 0;
  }
  if (n_active == 0) return fail(ProfileError::kNoActiveAxis);
  // Every active axis observed: the active columns of the sensors'
  // observation matrix have full rank, and none is empty.
  double h[kMaxSensors][kA] = {};
  for (int i = 0; i < p.sensor_count && i < kMaxSensors; ++i) observation_row(p.sensors[i], h[i]);
  for (int a = 0; a < kA; ++a) {
    if (!use[a]) continue;
    bool seen = false;
    for (int i = 0; i < p.sensor_count; ++i) seen = seen || std::fabs(h[i][a]) > 1e-12;
    if (!seen) return fail(ProfileError::kAxisWithoutSensor, a);
  }
  {
    double ht[kA][kMaxSensors] = {};
    for (int i = 0; i < p.sensor_count; ++i) {
      for (int a = 0; a < kA; ++a) ht[a][i] = h[i][a];
    }
    int rank = 0;
    double cond = 0.0;
    rank_condition<kMaxSensors>(ht, use, &rank, &cond);
    if (rank < n_active) return fail(ProfileError::kAxisWithoutSensor);
  }
  // Limits: inside what the board's amplifiers and the profile's own hardware can do.
  if (!(p.limits.peak_current_A > 0.0) || p.limits.peak_current_A > p.limits.hardware_current_A ||
      p.limits.rms_current_A > p.limits.peak_current_A ||
      p.limits.hardware_current_A > io::stage::kDacFullScale_V * io::stage::kAmplifierGain_A_per_V ||
      !(p.limits.landing_speed_m_per_s > 0.0)) {
    return fail(ProfileError::kLimitsOutsideHardware);
  }
  for (int a = 0; a < kA; ++a) {
    if (use[a] && !(p.axis[a].max_velocity > 0.0 && p.axis[a].max_acceleration > 0.0)) {
      return fail(ProfileError::kLimitsOutsideHardware, a);
    }
  }
  // What this firmware can drive: the Halbach family, six active axes (the
  // kernel's sequencer closes all six), PID or internal-model loops.
  if (p.family != ActuatorFamily::kHalbachLorentz || p.halbach.layout == ForcerLayout::kCustom) {
    return fail(ProfileError::kUnsupportedFamily);
  }
  for (int a = 0; a < kA; ++a) {
    const ControllerKind k = p.axis[a].controller.kind;
    if (!use[a]) return fail(ProfileError::kUnsupportedController, a);  // no passive axes in this kernel yet
    if (k != ControllerKind::kPid2Dof && k != ControllerKind::kInternalModel) {
      return fail(ProfileError::kUnsupportedController, a);
    }
    if (p.axis[a].controller.schedule_points != 0 || p.axis[a].controller.feedback_linearization) {
      return fail(ProfileError::kUnsupportedController, a);
    }
    // Paper 002's anti-windup gain E and LQR weights belong to its own
    // kernel (pmlsm_stage). This one designs its internal-model regulator by
    // pole placement on the profile's axis plant, with back-calculation
    // anti-windup: a value set here would change nothing, so it is refused
    // rather than ignored.
    bool lqr_weights = false;
    for (double w : p.axis[a].controller.lqr_weight_h) lqr_weights = lqr_weights || w != 0.0;
    if (p.axis[a].controller.antiwindup_gain != 0.0 || lqr_weights) {
      return fail(ProfileError::kUnsupportedController, a);
    }
  }
  // The kernel's pose solver (sensors_to_pose): three interferometer beams
  // along X or Y, three height sensors; MakeKernelConfig hands it their
  // placement.
  {
    int beams = 0, heights = 0;
    // One counter resolution for the three beams and one scale for the three
    // heights (one interpolator, one ADC scale in the pose solver): they were
    // parsed and ignored, so a lab's 1.24 nm counter read as 0.618 nm (every
    // length halved, every loop gain doubled).
    double beam_resolution = -1.0, height_scale = -1.0;
    const auto one_value = [](double* kept, double v) {
      if (*kept < 0.0) *kept = v;
      return *kept == v;
    };
    for (int s = 0; s < p.sensor_count && s < kMaxSensors; ++s) {
      const Sensor& sensor = p.sensors[s];
      if (sensor.kind == SensorKind::kInterferometer) {
        ++beams;
        const double c = std::fabs(numeric::dcos(sensor.direction_rad)), sn = std::fabs(numeric::dsin(sensor.direction_rad));
        if (!(c > 1.0 - 1e-9 || sn > 1.0 - 1e-9)) return fail(ProfileError::kUnsupportedSensors);
        if (!one_value(&beam_resolution, sensor.resolution) ||
            (sensor.resolution != 0.0 && InterferometerInterpolation(sensor.resolution) == 0)) {
          return fail(ProfileError::kUnsupportedSensors);
        }
      } else if (sensor.kind == SensorKind::kLaserDisplacement) {
        ++heights;
        // m per V on the +-10 V ADC: 0.1 um .. 1 mm of range per side.
        if (!one_value(&height_scale, sensor.resolution) ||
            (sensor.resolution != 0.0 && !(sensor.resolution >= 1e-8 && sensor.resolution <= 1e-4))) {
          return fail(ProfileError::kUnsupportedSensors);
        }
      } else if (sensor.kind != SensorKind::kHall) {
        return fail(ProfileError::kUnsupportedSensors);
      }
    }
    if (beams != io::kInterferometerAxes || heights != io::kDisplacementSensors) {
      return fail(ProfileError::kUnsupportedSensors);
    }
  }
  // The kernel's start-up is paper 000's Sec. V.
  constexpr StartupStep kPaper000[] = {StartupStep::kCloseInPlane, StartupStep::kLiftFeedforward,
                                       StartupStep::kCloseVertical, StartupStep::kCloseTilts, StartupStep::kReady};
  for (int i = 0; i < 5; ++i) {
    if (p.startup[i] != kPaper000[i]) return fail(ProfileError::kBadStartup);
  }
  if (p.startup[5] != StartupStep::kEnd) return fail(ProfileError::kBadStartup);  // nothing after Ready
  // Allocation: A (6 x 8) of the layout, rank and condition on the active rows.
  kernel::ForceAllocationTablesDouble t{};
  if (kernel::ComputeForceAllocationTables(allocation_of(p), &t) != kernel::ForceAllocationError::kOk) {
    return fail(ProfileError::kAllocationRank);
  }
  rank_condition<kernel::kForcerForces>(t.a, use, &r.allocation_rank, &r.allocation_condition);
  if (r.allocation_rank < n_active) return fail(ProfileError::kAllocationRank);
  if (r.allocation_condition > 1e3) return fail(ProfileError::kAllocationCondition);
  // The kernel configuration this profile yields must pass the kernel's own
  // checks of what the profile sets: "runs" here means the kernel takes it.
  // Found by fuzz_profile: a theta_y travel of +-200 rad passed this check
  // and the kernel refused the configuration (ConfigError::kReferenceLimits);
  // an exploratory run also met kSupervisor refusals (e.g. an x travel of
  // +-0.2 m, beyond the supervisor's +-0.1 m). The supervisor and the
  // sequencer are checked by their own validate(); the reference and
  // excitation rules are the kernel's apply_config rules.
  {
    const kernel::KernelConfig c = config_of(p);
    const kernel::SupervisorConfig& sv = c.supervisor;
    if (kernel::validate(sv, c.servo_rate_Hz) != kernel::SupervisorConfigError::kOk) {
      // The theta_z, z and tilt windows follow the profile's travel: name the
      // axis whose window the supervisor refuses (the family's window in its
      // place passes), the larger tilt for the shared tilt window.
      const kernel::SupervisorConfig family{};
      for (int a = 2; a < kA; ++a) {
        kernel::SupervisorConfig trial = sv;
        if (a == 2) trial.theta_z_limit_rad = family.theta_z_limit_rad;
        if (a == 3) trial.z_max_m = family.z_max_m;
        if (a >= 4) trial.tilt_limit_rad = family.tilt_limit_rad;
        if (kernel::validate(trial, c.servo_rate_Hz) == kernel::SupervisorConfigError::kOk) {
          const bool tilt_y = a >= 4 && travel_reach(p, 5) > travel_reach(p, 4);
          return fail(ProfileError::kLimitsOutsideHardware, tilt_y ? 5 : a);
        }
      }
      return fail(ProfileError::kLimitsOutsideHardware);
    }
    if (kernel::validate(c.sequencer, c.servo_rate_Hz) != kernel::SequencerConfigError::kOk ||
        c.sequencer.nominal_height_m > sv.z_max_m) {
      return fail(ProfileError::kLimitsOutsideHardware);
    }
    // The z window inside what the laser displacement sensors measure (the
    // kernel's prepare_config rule).
    if (!(static_cast<double>(sv.z_max_m) < kernel::HeightSensorsTop_m(c.measurement))) {
      return fail(ProfileError::kLimitsOutsideHardware, 3);
    }
    constexpr float kOpen = std::numeric_limits<float>::infinity();
    const float window_min[kA] = {sv.x_min_m, sv.y_min_m, -sv.theta_z_limit_rad, sv.z_min_m, -sv.tilt_limit_rad,
                                  -sv.tilt_limit_rad};
    const float window_max[kA] = {sv.x_max_m, sv.y_max_m, sv.theta_z_limit_rad, sv.z_max_m, sv.tilt_limit_rad,
                                  sv.tilt_limit_rad};
    for (int a = 0; a < kA; ++a) {
      const float lo = c.references.position_min[a];
      const float hi = c.references.position_max[a];
      if (!(lo < hi) || !(lo > -kOpen) || !(hi < kOpen) || lo < window_min[a] || hi > window_max[a]) {
        return fail(ProfileError::kLimitsOutsideHardware, a);
      }
    }
    // The kernel applies the allocation in its own scalar type, and in Q7.24
    // every constant (pinv(A) entries, gravity effort, 1/2b*) must stay below
    // 128: triangle_alpha_rad = 1.52 passed the double tables above and the
    // kernel refused it (ConfigError::kAllocation, found by fuzz_profile).
    // Checked as the fixed-point kernel applies it, the stricter build.
    {
      kernel::ForceAllocationConfig alloc = c.allocation;
      alloc.payload_kg = static_cast<double>(c.payload_mass_kg);
      kernel::ForceAllocationState<numeric::Q7_24> state{};
      const kernel::ForceAllocationError e = kernel::ApplyForceAllocationConfig<numeric::Q7_24>(alloc, &state);
      if (e == kernel::ForceAllocationError::kScalarRange) return fail(ProfileError::kAllocationCondition);
      if (e != kernel::ForceAllocationError::kOk) return fail(ProfileError::kAllocationRank);
    }
    // The supervisor lands the stage when a beam's count rate implies more
    // than max_interferometer_speed_m_per_s (a lost fringe burst): an x or y
    // velocity limit above it passed here, and the first fast move faulted
    // (kCounterJump at 0.3 m/s with max_velocity = 0.5). 10 % is left for
    // the loop's overshoot and what a turning platen adds at a beam.
    for (int a = 0; a < 2; ++a) {
      if (!(c.references.max_velocity[a] <= 0.9f * sv.max_interferometer_speed_m_per_s)) {
        return fail(ProfileError::kLimitsOutsideHardware, a);
      }
    }
    const kernel::ExcitationLimits& ex = c.excitation;
    if (!(ex.max_amplitude_A <= sv.peak_current_A) || !(ex.max_frequency_Hz < 0.5f * c.servo_rate_Hz)) {
      return fail(ProfileError::kLimitsOutsideHardware);
    }
    // The measurement and every axis' loop and filters, designed as the
    // kernel's apply_config designs them (kernel::DesignAxis), in the
    // stricter fixed point: a derivative filter at or above half the servo
    // rate, or an LDS target cell under twice the sensors' window, passed
    // this check and the kernel refused the profile.
    {
      kernel::SensorsToPoseState s2p;
      if (kernel::ApplySensorsToPoseConfig(c.measurement, &s2p) != kernel::SensorsToPoseError::kOk) {
        return fail(ProfileError::kKernelRefused);
      }
      for (int a = 0; a < kA; ++a) {
        kernel::Pid2DofCoefficients<numeric::Q7_24> pid{};
        kernel::InternalModelCoefficients<numeric::Q7_24> imr{};
        kernel::BiquadCoefficients<numeric::Q7_24> filter[kernel::kMaxBiquadStages]{};
        const kernel::ConfigError e = kernel::DesignAxis<numeric::Q7_24>(c, a, &pid, &imr, filter);
        if (e == kernel::ConfigError::kUnstableLoop) return fail(ProfileError::kUnstableLoop, a);
        if (e != kernel::ConfigError::kOk) return fail(ProfileError::kKernelRefused, a);
      }
    }
  }
  // Homing's Hall sensors (after what the kernel itself refuses): exactly two, B a quarter pitch beyond A in x and y
  // (the Hall solve reads them as a quadrature pair: a profile without them
  // homed on the seed stage's Hall places), each with a swing the ADC can
  // read. A stronger array than the seed's (2 b* 2.2 N/A) on the seed's
  // 20 V/T railed the ADC at rest and homing failed without a reason.
  {
    const Sensor* hall[2] = {nullptr, nullptr};
    int halls = 0;
    for (int s = 0; s < p.sensor_count && s < kMaxSensors; ++s) {
      if (p.sensors[s].kind != SensorKind::kHall) continue;
      if (halls < 2) hall[halls] = &p.sensors[s];
      ++halls;
    }
    if (halls != 2) return fail(ProfileError::kUnsupportedSensors);
    const double quarter = p.halbach.pitch_m / 4.0;
    if (!(std::fabs(hall[1]->x_m - hall[0]->x_m - quarter) <= kHallQuadratureTolerance_m) ||
        !(std::fabs(hall[1]->y_m - hall[0]->y_m - quarter) <= kHallQuadratureTolerance_m)) {
      return fail(ProfileError::kUnsupportedSensors);
    }
    // One height and one sensitivity: the solve takes A and B's channels as
    // the sine and cosine of one amplitude.
    if (hall_height_m(*hall[0]) != hall_height_m(*hall[1]) ||
        hall_sensitivity_V_per_T(*hall[0]) != hall_sensitivity_V_per_T(*hall[1])) {
      return fail(ProfileError::kUnsupportedSensors);
    }
    for (const Sensor* s : hall) {
      if (!(s->height_m >= 0.0 && s->height_m < 0.1) ||
          !(s->sensitivity_V_per_T >= 0.0 && s->sensitivity_V_per_T < 1e4)) {
        return fail(ProfileError::kHallSignalRange);
      }
      const HallSwing w = HallSignalSwing(p, *s);
      if (!(w.peak_fraction <= kHallMaxPeakFraction) || !(w.amplitude_fraction >= kHallMinAmplitudeFraction)) {
        return fail(ProfileError::kHallSignalRange);
      }
    }
  }
  // Every PID loop must cross over once with a positive phase margin.
  for (int a = 0; a < kA; ++a) {
    if (p.axis[a].controller.kind != ControllerKind::kPid2Dof) continue;
    const LoopMargins lm = AxisLoopMargins(p, a);
    if (!kernel::LoopIsAcceptable(lm)) return fail(ProfileError::kUnstableLoop, a);
  }
  return r;
}

namespace {
// The kernel configuration of a profile, unchecked (MakeKernelConfig's
// mapping; CheckStageProfile validates what it yields).
kernel::KernelConfig config_of(const StageProfile& p) {
  kernel::KernelConfig c = kernel::default_kernel_config();
  c.servo_rate_Hz = static_cast<float>(p.servo_rate_Hz);
  c.measurement.servo_rate_Hz = c.servo_rate_Hz;
  c.allocation = allocation_of(p);
  for (int a = 0; a < kA; ++a) {
    const Axis& ax = p.axis[a];
    const AxisController& k = ax.controller;
    kernel::AxisLoopConfig& l = c.axis[a];
    l.type = k.kind == ControllerKind::kInternalModel ? kernel::LoopType::kInternalModel : kernel::LoopType::kPid2Dof;
    l.pid.kp = static_cast<float>(k.kp);
    l.pid.ki = static_cast<float>(k.ki);
    l.pid.kd = static_cast<float>(k.kd);
    l.pid.derivative_filter_hz = static_cast<float>(k.derivative_filter_Hz);
    l.pid.setpoint_weight_p = static_cast<float>(k.setpoint_weight_p);
    l.pid.effort_limit_A = static_cast<float>(k.effort_limit_A);
    l.imr.effort_limit_A = l.pid.effort_limit_A;
    if (k.imr_omega0_rad_per_s > 0.0) l.imr.omega0_rad_s = static_cast<float>(k.imr_omega0_rad_per_s);
    if (k.imr_bandwidth_Hz > 0.0) l.imr.bandwidth_Hz = static_cast<float>(k.imr_bandwidth_Hz);
    if (k.imr_model_bandwidth_Hz > 0.0) l.imr.internal_model_bandwidth_Hz = static_cast<float>(k.imr_model_bandwidth_Hz);
    if (k.kind == ControllerKind::kInternalModel) {
      // The regulator's own 2-DOF weight and derivative filter (they reached
      // only the unused PID before: an internal-model axis ran b = 1 and the
      // family's 1 kHz filter whatever the profile said).
      l.imr.setpoint_weight_p = static_cast<float>(k.setpoint_weight_p);
      l.imr.derivative_filter_hz = static_cast<float>(k.derivative_filter_Hz);
    }
    // The internal-model regulator is designed on this profile's axis plant
    // (the one the checker judges the PID loops on), not the seed stage's.
    l.imr.plant_gain = static_cast<float>(AxisPlantGain(p, a));
    l.imr.plant_damping_per_s = static_cast<float>(ax.open_loop_damping_per_s);
    l.imr.plant_stiffness_per_s2 = static_cast<float>(ax.open_loop_stiffness_per_s2);
    // Back-calculation time as the kernel's defaults derive it (sqrt(Ti Td), or Ti without D).
    if (l.pid.ki > 0.0f && l.pid.kp > 0.0f) {
      const double ti = static_cast<double>(l.pid.kp) / static_cast<double>(l.pid.ki);
      const double td = static_cast<double>(l.pid.kd) / static_cast<double>(l.pid.kp);
      l.pid.antiwindup_tracking_time_s = static_cast<float>(l.pid.kd > 0.0f ? std::sqrt(ti * td) : ti);
    }
    for (int f = 0; f < kernel::kMaxBiquadStages; ++f) {
      l.filters[f] = f < k.filter_count && f < kMaxFilters ? biquad_of(k.filters[f]) : kernel::BiquadConfig{};
    }
    c.references.position_min[a] = static_cast<float>(ax.travel_min);
    c.references.position_max[a] = static_cast<float>(ax.travel_max);
    c.references.max_velocity[a] = static_cast<float>(ax.max_velocity);
    c.references.max_acceleration[a] = static_cast<float>(ax.max_acceleration);
  }
  // The supervisor's travel window: 1 mm beyond the in-plane travel (a move
  // to the end of travel must not trip on its small following error).
  c.supervisor.x_min_m = -static_cast<float>(-p.axis[0].travel_min + 1e-3);
  c.supervisor.x_max_m = static_cast<float>(p.axis[0].travel_max + 1e-3);
  c.supervisor.y_min_m = -static_cast<float>(-p.axis[1].travel_min + 1e-3);
  c.supervisor.y_max_m = static_cast<float>(p.axis[1].travel_max + 1e-3);
  // The theta_z, z and tilt windows from the profile's travel, with the
  // seed's margins (1 mrad, 2 um, 100 urad: its 5 mrad, 40 um and 300 urad);
  // they were the seed's whatever the profile said, which refused a stage
  // that levitates higher or tilts further. z_min (5 um below rest: the
  // landing's contact) stays the family's.
  if (active(p, 2)) c.supervisor.theta_z_limit_rad = static_cast<float>(travel_reach(p, 2) + 1e-3);
  if (active(p, 3)) c.supervisor.z_max_m = static_cast<float>(p.axis[3].travel_max + 2e-6);
  if (active(p, 4) || active(p, 5)) {
    const double tilt = std::fmax(active(p, 4) ? travel_reach(p, 4) : 0.0, active(p, 5) ? travel_reach(p, 5) : 0.0);
    c.supervisor.tilt_limit_rad = static_cast<float>(tilt + 100e-6);
  }
  c.supervisor.peak_current_A = static_cast<float>(p.limits.peak_current_A);
  c.supervisor.rms_current_A = static_cast<float>(p.limits.rms_current_A);
  // The stage's own limits, which no register write may exceed (kernel
  // StageEnvelope): the profile's currents, its travel + 2 mm.
  c.stage.peak_current_A = c.supervisor.peak_current_A;
  c.stage.rms_current_A = c.supervisor.rms_current_A;
  c.stage.x_min_m = -static_cast<float>(-p.axis[0].travel_min + kernel::kStageWindowBeyondTravel_m);
  c.stage.x_max_m = static_cast<float>(p.axis[0].travel_max + kernel::kStageWindowBeyondTravel_m);
  c.stage.y_min_m = -static_cast<float>(-p.axis[1].travel_min + kernel::kStageWindowBeyondTravel_m);
  c.stage.y_max_m = static_cast<float>(p.axis[1].travel_max + kernel::kStageWindowBeyondTravel_m);
  c.sequencer.nominal_height_m = static_cast<float>(p.limits.nominal_height_m);
  SetSensorGeometry(p, &c.measurement);
  return c;
}
}  // namespace

int InterferometerInterpolation(double resolution_m) {
  if (!(resolution_m > 0.0 && resolution_m < 1.0)) return 0;
  const double per_count = io::stage::kWavelength_m / io::stage::kInterferometerFold;
  const double n = std::floor(per_count / resolution_m + 0.5);
  if (!(n >= 1.0 && n <= 65536.0)) return 0;
  const double exact = per_count / n;
  return std::fabs(exact - resolution_m) <= kResolutionRounding * resolution_m ? static_cast<int>(n) : 0;
}

void SetSensorGeometry(const StageProfile& p, kernel::SensorsToPoseConfig* m) {
  // The sensor geometry sensors_to_pose solves with: the profile's sensors, in
  // order of kind (interferometers -> the three beams, laser displacement
  // sensors -> the three heights, the first Hall sensor -> Hall A; B sits a
  // quarter pitch further). What the profile does not describe (wavelength,
  // fold, mirror distance, ADC scale) stays the family's.
  int beams = 0, heights = 0, halls = 0;
  for (int s = 0; s < p.sensor_count && s < kMaxSensors; ++s) {
    const Sensor& sensor = p.sensors[s];
    switch (sensor.kind) {
      case SensorKind::kInterferometer:
        if (beams < io::kInterferometerAxes) {
          // Along X (direction 0 or pi) or along Y (+-pi/2): the check admits no other.
          const bool along_x = std::fabs(numeric::dcos(sensor.direction_rad)) > 0.5;
          kernel::BeamConfig& b = m->beam[beams++];
          b.axis = along_x ? kernel::BeamAxis::kX : kernel::BeamAxis::kY;
          b.perpendicular_m = along_x ? sensor.y_m : sensor.x_m;
          // A beam that looks along -X or -Y counts down as the stage moves +.
          b.sign = (along_x ? numeric::dcos(sensor.direction_rad) : numeric::dsin(sensor.direction_rad)) < 0.0 ? -1 : 1;
          // The counter's resolution (the check requires one for all three).
          if (sensor.resolution != 0.0) m->interpolation = InterferometerInterpolation(sensor.resolution);
        }
        break;
      case SensorKind::kLaserDisplacement:
        if (heights < io::kDisplacementSensors) {
          m->displacement_sensor_x_m[heights] = sensor.x_m;
          m->displacement_sensor_y_m[heights] = sensor.y_m;
          if (sensor.resolution != 0.0) m->displacement_scale_m_per_V = sensor.resolution;
          ++heights;
        }
        break;
      case SensorKind::kHall:
        if (halls++ == 0) {
          m->hall_a_x_m = sensor.x_m;
          m->hall_a_y_m = sensor.y_m;
          // The harmonics' shares at Hall A's height over this array (the
          // 5th was the seed stage's whatever the profile said).
          kernel::HallHarmonicRatios(hall_height_m(sensor), p.halbach.magnet_thickness_m, p.halbach.pitch_m,
                                     m->hall_harmonic_ratio);
        }
        break;
      default:
        break;
    }
  }
  m->pitch_m = p.halbach.pitch_m;
  m->lds_target_cell_m = kernel::MagnetBlockWidth_m(p.halbach.pitch_m);
}

ProfileCheck MakeKernelConfig(const StageProfile& p, kernel::KernelConfig* out) {
  const ProfileCheck check = CheckStageProfile(p);
  if (check.error != ProfileError::kOk) return check;
  *out = config_of(p);
  return check;
}

}  // namespace maglev::stage_profile
