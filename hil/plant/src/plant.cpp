#include "maglev/plant/plant.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace maglev::hil {
namespace {

constexpr double kPi = io::stage::kPi;

std::int16_t QuantizeAdc(double volts, double full_scale_V) {
  const double code = std::nearbyint(volts * (32768.0 / full_scale_V));
  return static_cast<std::int16_t>(std::clamp(code, -32768.0, 32767.0));
}

// Forcer centres in the platen frame. Cross, eq (18): 1&2 at y = -l (Fx),
// 3&4 at x = +l (Fy), 5&6 at y = +l (Fx), 7&8 at x = -l (Fy). Square, paper
// 003 eq (6): 1&2 at (l, l) (Fx), 3&4 at (-l, l) (Fy), 5&6 at (-l, -l) (Fx),
// 7&8 at (l, -l) (Fy).
Eigen::Vector2d ForcerCentre(int forcer, double l, BodyConfig::Layout layout) {
  if (layout == BodyConfig::Layout::kSquare) {
    switch (forcer) {
      case 0: return {l, l};
      case 1: return {-l, l};
      case 2: return {-l, -l};
      default: return {l, -l};
    }
  }
  switch (forcer) {
    case 0: return {0.0, -l};
    case 1: return {l, 0.0};
    case 2: return {0.0, l};
    default: return {-l, 0.0};
  }
}

// As built: the magnets' pitch differs from the one the kernel (and the coil
// layout) assume.
FieldConfig FieldOf(const PlantConfig& c) {
  FieldConfig f = c.field;
  if (c.as_built.active && c.as_built.magnet_pitch_error != 0.0) f.pitch_m *= 1.0 + c.as_built.magnet_pitch_error;
  return f;
}

}  // namespace

PlantConfig PlantConfig::Ideal() { return IdealOf(PlantConfig{}); }

PlantConfig PlantConfig::AsDrawn(const PlantConfig& stage) {
  PlantConfig c = stage;
  c.forcer_errors = ForcerErrors{};
  for (int j = 0; j < kCoils; ++j) {
    c.amplifier.gain_error[j] = 0.0;
    c.amplifier.offset_A[j] = 0.0;
    c.amplifier.bandwidth_error[j] = 0.0;
  }
  c.as_built = AsBuiltConfig{};
  return c;
}

PlantConfig PlantConfig::IdealOf(const PlantConfig& stage) {
  PlantConfig c = AsDrawn(stage);
  // No noise.
  c.amplifier.current_noise_scale = 0.0;
  c.amplifier.monitor_noise_A = 0.0;
  c.amplifier.monitor_reproduces_table1 = false;
  c.sensor_noise_enabled = false;
  return c;
}

PlantConfig PlantConfig::Default() {
  PlantConfig c;
  // (ours) small, fixed imperfections of the size paper 003 discusses: coil
  // pair misalignments of a few 0.1 mrad, tangential force errors of a few
  // 0.1 %, off-axis vertical error forces of a few 0.1 % of the thrust.
  const double eps_t[kForcers] = {0.003, -0.002, 0.004, -0.003};
  const double eps_z[kForcers] = {0.002, -0.003, 0.001, -0.002};
  const double misalign[kForcers] = {0.5e-3, -0.3e-3, 0.2e-3, -0.4e-3};
  for (int f = 0; f < kForcers; ++f) {
    c.forcer_errors.epsilon_tangential[f] = eps_t[f];
    c.forcer_errors.epsilon_off_axis_z[f] = eps_z[f];
    c.forcer_errors.misalignment_rad[f] = misalign[f];
  }
  // (ours) amplifier gain errors within the 1 % resistor tolerance of paper
  // 003 Sec. 3.1, and offsets of a few mA (uncalibrated DC drift).
  const double gain_err[kCoils] = {0.004, -0.006, 0.002, -0.003, 0.007, -0.002, 0.005, -0.008};
  const double offset[kCoils] = {2e-3, -1.5e-3, 1e-3, -2.5e-3, 0.5e-3, 3e-3, -1e-3, 1.5e-3};
  for (int j = 0; j < kCoils; ++j) {
    c.amplifier.gain_error[j] = gain_err[j];
    c.amplifier.offset_A[j] = offset[j];
  }
  return c;
}

Eigen::Matrix3d Plant::RotationFromAngles(double theta_x, double theta_y, double theta_z) {
  return (Eigen::AngleAxisd(theta_z, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(theta_y, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(theta_x, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d Plant::AnglesFromRotation(const Eigen::Matrix3d& r) {
  return {std::atan2(r(2, 1), r(2, 2)), std::asin(std::clamp(-r(2, 0), -1.0, 1.0)),
          std::atan2(r(1, 0), r(0, 0))};
}

Plant::Plant(const PlantConfig& config, std::uint64_t seed)
    : config_(config),
      field_(FieldOf(config)),
      amplifiers_(config.amplifier),
      rng_(seed, config.noise_generator),
      mass_(config.body.mass_kg + config.body.payload_kg),
      tick_s_(1.0 / config.integration.servo_rate_Hz),
      side_force_per_A_(config.field.coil_turns * config.field.coil_effective_length_m),
      com_arm_m_(config.body.com_above_coil_midplane_m) {
  if (config.floor.active()) floor_ = FloorVibration(config.floor, tick_s_, seed);
  const double s2 = config.body.payload_side_m * config.body.payload_side_m;
  inertia_ = {config.body.inertia_kgm2[0] + config.body.payload_kg * s2 / 12.0,
              config.body.inertia_kgm2[1] + config.body.payload_kg * s2 / 12.0,
              config.body.inertia_kgm2[2] + config.body.payload_kg * s2 / 6.0};

  // Suspension spring: identified total minus the magnetic gradient stiffness
  // of the levitating force (gamma_1 * weight), see SuspensionConfig.
  const double weight = mass_ * config.body.gravity_m_per_s2;
  k_susp_ = config.suspension.stiffness_N_per_m -
            (config.suspension.subtract_magnetic_stiffness ? field_.gamma1_per_m() * weight : 0.0);

  triangle_ = config.body.layout == BodyConfig::Layout::kTriangle;
  as_built_ = config.as_built.active;
  if (triangle_) {
    BuildTriangleSides();
  } else {
    BuildArraySides();
  }
  BuildSprings();
  for (int f = 0; f < kForcers; ++f) {
    if (config.forcer_errors.epsilon_tangential[f] != 0.0 || config.forcer_errors.epsilon_off_axis_z[f] != 0.0) {
      forcer_errors_active_ = true;
    }
  }

  // --- initial state ---------------------------------------------------------
  body_.position_m = {config.initial.position_m[0], config.initial.position_m[1], config.initial.position_m[2]};
  body_.attitude = Eigen::Quaterniond(
      RotationFromAngles(config.initial.angles_rad[0], config.initial.angles_rad[1], config.initial.angles_rad[2]));

  if (as_built_) {
    // The platen's geometric centre starts where the nominal one would: its
    // CoM (the state) sits at the drawn offset from it.
    body_.position_m.x() += config.as_built.com_offset_m[0];
    body_.position_m.y() += config.as_built.com_offset_m[1];
    const double* poi = config.as_built.products_of_inertia_kgm2;
    if (poi[0] != 0.0 || poi[1] != 0.0 || poi[2] != 0.0) {
      full_inertia_ = true;
      inertia_matrix_ << inertia_[0], -poi[0], -poi[1], -poi[0], inertia_[1], -poi[2], -poi[1], -poi[2], inertia_[2];
      inertia_inverse_ = inertia_matrix_.inverse();
    }
    // Readings are zero at the reference pose (geometric centre at the
    // origin, level): the counters and the LDS are set there on the stage as
    // built, as the nominal plant's are.
    const BodyState initial = body_;
    body_ = BodyState{};
    body_.position_m = {config.as_built.com_offset_m[0], config.as_built.com_offset_m[1], 0.0};
    for (int a = 0; a < io::kInterferometerAxes; ++a) interferometer_zero_[a] = AsBuiltInterferometer(a);
    for (int i = 0; i < io::kDisplacementSensors; ++i) {
      // Spot at the sensor's own (x, y) when the geometric centre is at the origin.
      target_home_m_[i] = TargetHeight(config.displacement.sensor_x_m[i], config.displacement.sensor_y_m[i]);
    }
    body_ = initial;
  }

  lsb_m_ = config.interferometer.wavelength_m /
           (static_cast<double>(config.interferometer.fold) * config.interferometer.interpolation);
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    counter_adjust_[a] = 0;
    last_count_[a] = static_cast<std::int64_t>(config.interferometer.start_count[a]);
  }
  UpdateTruth();
}

void Plant::BuildArraySides() {
  // --- coil geometry from eq (18) and kCoilPhase_rad (eq 19) ---------------
  // Coil j obeys (F_tangential, F_z) = b* i_j (sin psi_j, cos psi_j) with
  // psi_j = gamma_1 * base + phi_j. A side carrying current along u_ref
  // (-Y' for the Fx coils, +X' for the Fy coils) at s along the array axis
  // gives (F_t, F_z) ~ (sin(gamma_1 s - pi/2), cos(gamma_1 s - pi/2)), so
  // the reference side sits at s0 = base + (phi_j + pi/2) / gamma_1; the
  // other side is L/2 away with the opposite current. Only s0 mod L/2 matters
  // for the forces; the representative sets the torque arms. (ours) Each
  // coil is centred at 0 when its phase allows it, otherwise at +L/4 (pairs
  // 1&2, 3&4) or -L/4 (5&6, 7&8): the layout is symmetric under a 180 deg
  // turn, and the four sides of a pair are L/4 apart (Sec. III).
  const double pitch = config_.field.pitch_m;
  // The layout is the kernel's (nominal pitch) even when the magnets differ.
  const double gamma1 = (as_built_ && config_.as_built.magnet_pitch_error != 0.0) ? 2.0 * kPi / pitch
                                                                                    : field_.gamma1_per_m();
  const double l = config_.body.lever_arm_m;
  const AsBuiltConfig& ab = config_.as_built;
  int k = 0;
  for (int j = 0; j < kCoils; ++j) {
    const int f = j / 2;
    const bool fx_coil = (f % 2) == 0;
    const double base = fx_coil ? io::stage::kBasePointX2_m : io::stage::kBasePointY8_m;
    const double s0 = (io::stage::kCoilPhase_rad[j] + kPi / 2.0) / gamma1;  // relative to base
    const double m = (s0 - pitch / 4.0) / (pitch / 2.0);
    double centre = 0.0;
    if (std::fabs(m - std::nearbyint(m)) > 1e-9) {
      centre = (f < 2) ? pitch / 4.0 : -pitch / 4.0;
    }
    const Eigen::Vector3d u_ref = fx_coil ? Eigen::Vector3d(0.0, -1.0, 0.0) : Eigen::Vector3d(1.0, 0.0, 0.0);
    Eigen::Vector2d fc = ForcerCentre(f, l, config_.body.layout);
    if (as_built_) fc *= 1.0 + ab.forcer_lever_offset_m[f] / fc.norm();
    const double alpha = config_.forcer_errors.misalignment_rad[f];
    const Eigen::Matrix3d rot_alpha = Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (int side = 0; side < 2; ++side) {
      const double s = centre + (side == 0 ? -pitch / 4.0 : pitch / 4.0);
      const double half_pitches = std::nearbyint((s - s0) / (pitch / 2.0));
      const bool odd = std::fabs(std::fmod(half_pitches, 2.0)) > 0.5;
      // Along its array the coil sits at the forcer centre's coordinate (0 in
      // the cross layout) + the base point + s.
      Eigen::Vector3d r = fx_coil ? Eigen::Vector3d(fc.x() + base + s, fc.y(), -com_arm_m_)
                                  : Eigen::Vector3d(fc.x(), fc.y() + base + s, -com_arm_m_);
      // Misalignment: the pair turns by alpha about its centre (paper 003).
      const Eigen::Vector3d centre3(fc.x(), fc.y(), -com_arm_m_);
      r = centre3 + rot_alpha * (r - centre3);
      if (as_built_) {
        // The coil sits off its place along the array (a commutation phase
        // error), and the CoM is off the geometric centre.
        r[fx_coil ? 0 : 1] += ab.coil_shift_m[j];
        r.x() -= ab.com_offset_m[0];
        r.y() -= ab.com_offset_m[1];
      }
      CoilSide cs;
      cs.coil = j;
      cs.forcer = f;
      cs.array_axis = fx_coil ? 0 : 1;
      cs.r_body_m = r;
      cs.u_body = rot_alpha * (odd ? -u_ref : u_ref);
      cs.quarter_turns = 0;
      sides_[static_cast<std::size_t>(k++)] = cs;
    }
  }
  // Quarter-pitch offsets of each side from its forcer's first side.
  for (std::size_t idx = 0; idx < sides_.size(); ++idx) {
    const CoilSide& ref = sides_[idx - idx % 4];
    const int ax = sides_[idx].array_axis;
    sides_[idx].quarter_turns =
        static_cast<int>(std::nearbyint((sides_[idx].r_body_m[ax] - ref.r_body_m[ax]) / (pitch / 4.0)));
  }
  for (std::size_t idx = 0; idx < sides_.size(); ++idx) {
    const CoilSide& cs = sides_[idx];
    SideConstants& c = side_constants_[idx];
    for (int a = 0; a < 3; ++a) c.rb[a] = cs.r_body_m[a];
    c.ux = cs.u_body.x();
    c.uy = cs.u_body.y();
    static constexpr double kQc[4] = {1.0, 0.0, -1.0, 0.0};
    static constexpr double kQs[4] = {0.0, 1.0, 0.0, -1.0};
    c.qc = kQc[cs.quarter_turns & 3];
    c.qs = kQs[cs.quarter_turns & 3];
    c.q_half_pi = cs.quarter_turns * (kPi / 2.0);
    // The side's phase offset from its forcer's reference side at rest is
    // gamma_1 (rb - rb_ref) along the array: whole quarter turns in the
    // nominal geometry (the exact 0 / +-1 above), plus a constant residual
    // where the coils sit off their places (as built: coil_shift_m, sigma
    // 0.1 mm = 0.012 rad). Folded in here, the residual leaves the
    // per-evaluation eps at what rotation adds (micro-radians: the Taylor
    // branch); left in eps it took the library's sin/cos on most
    // evaluations of an as-built plant (3.5 k instructions a tick). The
    // nominal layout's residuals (<= 6e-7 rad: its whole-quarter layout
    // under the field's own gamma_1) stay in eps, as they always were.
    const int ax = cs.array_axis;
    const double offset = field_.gamma1_per_m() * (cs.r_body_m[ax] - sides_[idx - idx % 4].r_body_m[ax]);
    if (std::fabs(offset - c.q_half_pi) > 1e-4) {
      c.q_half_pi = offset;
      c.qc = std::cos(offset);
      c.qs = std::sin(offset);
    }
    c.sel_x = cs.array_axis == 0 ? 1.0 : 0.0;
    c.sel_y = cs.array_axis == 0 ? 0.0 : 1.0;
    c.eps_t_x = c.sel_x * config_.forcer_errors.epsilon_tangential[cs.forcer];
    c.eps_t_y = c.sel_y * config_.forcer_errors.epsilon_tangential[cs.forcer];
    c.eps_z = config_.forcer_errors.epsilon_off_axis_z[cs.forcer];
    c.gain = 1.0 + (as_built_ ? ab.forcer_bstar_error[cs.forcer] : 0.0);
    c.roll = as_built_ ? ab.coil_roll_rad[cs.coil] : 0.0;
    c.ax = cs.array_axis;
    c.coil = cs.coil;
  }
  // Lanes: side 4 f + q -> lane f, position q (q = 0 is the forcer's
  // reference side, as in AddMagnetic's loop).
  lanes_ok_ = field_.harmonics() == 4;
  for (int f = 0; f < kForcers; ++f) {
    lane_axis_[f] = side_constants_[static_cast<std::size_t>(4 * f)].ax;
    for (int q = 0; q < 4; ++q) {
      const SideConstants& c = side_constants_[static_cast<std::size_t>(4 * f + q)];
      SideLanes& lane = side_lanes_[static_cast<std::size_t>(q)];
      if (c.ax != lane_axis_[f] || sides_[static_cast<std::size_t>(4 * f + q)].forcer != f) lanes_ok_ = false;
      lane.rb0[f] = c.rb[0];
      lane.rb1[f] = c.rb[1];
      lane.rb2[f] = c.rb[2];
      lane.ux[f] = c.ux;
      lane.uy[f] = c.uy;
      lane.qc[f] = c.qc;
      lane.qs[f] = c.qs;
      lane.q_half_pi[f] = c.q_half_pi;
      lane.sel_x[f] = c.sel_x;
      lane.sel_y[f] = c.sel_y;
      lane.eps_t_x[f] = c.eps_t_x;
      lane.eps_t_y[f] = c.eps_t_y;
      lane.eps_z[f] = c.eps_z;
      lane.gain[f] = c.gain;
      lane.roll[f] = c.roll;
      lane.coil[f] = c.coil;
    }
  }
  lanes_avx_ = __builtin_cpu_supports("avx") != 0;
}

void Plant::TriangleForcer(int f, double centre[2], double thrust[2]) const {
  // The kernel's LayoutGeometry (force_allocation.cpp), paper 003 eq (8).
  const double l = config_.body.lever_arm_m;
  const double sa = std::sin(config_.body.triangle_alpha_rad);
  const double ca = std::cos(config_.body.triangle_alpha_rad);
  switch (f) {
    case 0: centre[0] = l * ca; centre[1] = l * sa; thrust[0] = -sa; thrust[1] = ca; break;
    case 1: centre[0] = -l * ca; centre[1] = l * sa; thrust[0] = -sa; thrust[1] = -ca; break;
    default: centre[0] = 0.0; centre[1] = -l; thrust[0] = 1.0; thrust[1] = 0.0; break;
  }
}

// Triangle coil geometry. The kernel commutates coil j of forcer f as
// (F_h, F_z) = b* i_j (sin psi_j, cos psi_j) along (h_f, Z), psi_j =
// gamma_1 h_f . (x + x2_offset, y + y8_offset) + kCoilPhase_rad[j]: a travelling
// wave along h_f. Over the matrix (an X and a Y array) an oblique side sees
// two waves instead. A coil = a side at r1 with current along u = (h_y, -h_x)
// (the cross layout's reference direction) and one at r1 + (L/2) h_f with the
// opposite current; per unit current its fundamental force is
//   F_h = -P_x sin(beta_x) - P_y sin(beta_y),
//   F_z = -h_x P_x cos(beta_x) - h_y P_y cos(beta_y),
// P_s = 2 A_s sin(pi h_s / 2) (A_s: that array's side-averaged amplitude for
// this direction), beta_x = gamma_1 x1 + pi h_x / 2, beta_y likewise. The
// position r1 sets beta_x and beta_y independently; each is chosen so that
// its array's share points along the kernel's (sin psi_j, cos psi_j) at the
// home pose, i.e. tan(beta_s) = h_s tan(psi_j) on the right branch. The
// direction then matches the kernel exactly; the magnitude is what the
// physics gives (docs/PLANT.md: 0.76 b* for the oblique forcers' vertical
// coils, 0.98 b* horizontal at alpha = 30 deg), and away from home the two
// waves drift from the kernel's single one by gamma_1 times the travel. Of
// the periodic choices of r1 the one nearest the forcer centre (coil centre
// r1 + L/4 h_f) is taken; an array that gives this coil no force (P_s = 0)
// leaves r1 at the forcer centre's coordinate.
void Plant::BuildTriangleSides() {
  const double pitch = config_.field.pitch_m;
  const double gamma1 = field_.gamma1_per_m();
  auto wrap = [](double v) { return v - 2.0 * kPi * std::floor((v + kPi) / (2.0 * kPi)); };
  for (CoilSide& cs : sides_) {
    cs.coil = -1;
    cs.forcer = -1;
    cs.array_axis = -1;
    cs.r_body_m = Eigen::Vector3d::Zero();
    cs.u_body = Eigen::Vector3d::Zero();
    cs.quarter_turns = 0;
  }
  int k = 0;
  for (int f = 0; f < kTriangleForcers; ++f) {
    double c[2], h[2];
    TriangleForcer(f, c, h);
    const double u_ref[2] = {h[1], -h[0]};
    const ObliqueSideAmplitudes amp = field_.ObliqueAmplitudes(u_ref[0], u_ref[1]);
    const double p_gain[2] = {2.0 * amp.x_array_T[0] * std::sin(kPi * h[0] / 2.0),
                              2.0 * amp.y_array_T[0] * std::sin(kPi * h[1] / 2.0)};
    const double p_floor = 1e-9 * std::fabs(amp.x_array_T[0] + amp.y_array_T[0]);
    const double alpha = config_.forcer_errors.misalignment_rad[f];
    const Eigen::Matrix3d rot_alpha = Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d centre3(c[0], c[1], -com_arm_m_);
    for (int j = 2 * f; j < 2 * f + 2; ++j) {
      const double psi = io::stage::kCoilPhase_rad[j] +
                         gamma1 * (h[0] * io::stage::kBasePointX2_m + h[1] * io::stage::kBasePointY8_m);
      double r1[2];
      for (int s = 0; s < 2; ++s) {
        const double target = c[s] - pitch / 4.0 * h[s];
        if (std::fabs(p_gain[s]) <= p_floor || std::fabs(h[s]) < 1e-12) {
          r1[s] = target;
          continue;
        }
        const double beta = std::atan2(-std::sin(psi) / p_gain[s], -std::cos(psi) / (h[s] * p_gain[s]));
        const double theta = beta - kPi * h[s] / 2.0;
        r1[s] = target + wrap(theta - gamma1 * target) / gamma1;
      }
      for (int side = 0; side < 2; ++side) {
        const double off = side == 0 ? 0.0 : pitch / 2.0;
        Eigen::Vector3d r(r1[0] + off * h[0], r1[1] + off * h[1], -com_arm_m_);
        r = centre3 + rot_alpha * (r - centre3);
        const double sign = side == 0 ? 1.0 : -1.0;
        CoilSide& cs = sides_[static_cast<std::size_t>(k)];
        cs.coil = j;
        cs.forcer = f;
        cs.array_axis = -1;
        cs.r_body_m = r;
        cs.u_body = rot_alpha * Eigen::Vector3d(sign * u_ref[0], sign * u_ref[1], 0.0);
        cs.quarter_turns = 0;
        ObliqueSide& o = oblique_sides_[static_cast<std::size_t>(k)];
        for (int a = 0; a < 3; ++a) o.rb[a] = r[a];
        o.ux = cs.u_body.x();
        o.uy = cs.u_body.y();
        const Eigen::Vector3d hb = rot_alpha * Eigen::Vector3d(h[0], h[1], 0.0);
        o.hx = hb.x();
        o.hy = hb.y();
        // The misalignment turns the side by a few 0.1 mrad: its averaging
        // factors are those of the nominal direction (the change is second order).
        o.amp = amp;
        o.eps_t = config_.forcer_errors.epsilon_tangential[f];
        o.eps_z = config_.forcer_errors.epsilon_off_axis_z[f];
        o.coil = j;
        ++k;
      }
    }
  }
}

void Plant::set_body_state(const BodyState& state) {
  body_ = state;
  lane_chain_left_ = 0;  // moved from outside: the next stage 1 from the library
  hall_chain_.left = 0;  // and the next Hall sample
  body_.attitude.normalize();
  UpdateTruth();
}

void Plant::set_coil_currents(const std::array<double, kCoils>& currents_A) {
  for (int j = 0; j < kCoils; ++j) {
    amplifiers_.set_current(j, currents_A[static_cast<std::size_t>(j)]);
  }
  UpdateTruth();
}

void Plant::set_beam_loss(int axis, bool lost) {
  if (axis >= 0 && axis < io::kInterferometerAxes) {
    manual_loss_[axis] = lost;
  }
}

// ---------------------------------------------------------------------------
// Forces
// ---------------------------------------------------------------------------
Eigen::Vector3d Plant::CoilForceWorld(const BodyState& state, int coil, double current_A) const {
  if (triangle_) {
    // The force loop itself, with only this coil's current.
    Kinematics k;
    const Eigen::Matrix3d r = state.attitude.normalized().toRotationMatrix();
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) k.r[a][b] = r(a, b);
      k.p[a] = state.position_m[a];
      k.v[a] = 0.0;
      k.omega_w[a] = 0.0;
    }
    double currents[kCoils] = {};
    if (coil >= 0 && coil < kCoils) currents[coil] = current_A;
    Accum acc{};
    AddMagneticOblique(k, currents, &acc);
    return {acc.f[0], acc.f[1], acc.f[2]};
  }
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d r = state.attitude.normalized().toRotationMatrix();
  for (const CoilSide& cs : sides_) {
    if (cs.coil != coil) {
      continue;
    }
    const Eigen::Vector3d rw = r * cs.r_body_m;
    const double height = state.position_m.z() + rw.z() - cs.r_body_m.z();
    const double gap = config_.field.rest_gap_m + height;
    const double s = (cs.array_axis == 0 ? state.position_m.x() + rw.x() : state.position_m.y() + rw.y());
    const FieldSZ b = field_.SideAverageField(s, gap);
    const Eigen::Vector3d bw = cs.array_axis == 0 ? Eigen::Vector3d(b.b_s_T, 0.0, b.b_z_T)
                                                  : Eigen::Vector3d(0.0, b.b_s_T, b.b_z_T);
    Eigen::Vector3d f = side_force_per_A_ * current_A * (r * cs.u_body).cross(bw);
    if (forcer_errors_active_) {
      // Paper 003: F_t -> F_t (1 + eps_t), dF_z = eps_z F_t (platen frame).
      Eigen::Vector3d fb = r.transpose() * f;
      const int t_axis = cs.array_axis;  // X' for the Fx coils, Y' for the Fy coils
      const double ft = fb(t_axis);
      fb(t_axis) += config_.forcer_errors.epsilon_tangential[cs.forcer] * ft;
      fb.z() += config_.forcer_errors.epsilon_off_axis_z[cs.forcer] * ft;
      f = r * fb;
    }
    total += f;
  }
  return total;
}

namespace {

Kinematics MakeKinematics(const BodyState& state) {
  Kinematics k;
  const Eigen::Matrix3d r = state.attitude.normalized().toRotationMatrix();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      k.r[a][b] = r(a, b);
    }
    k.p[a] = state.position_m[a];
    k.v[a] = state.velocity_m_per_s[a];
  }
  const Eigen::Vector3d& w = state.omega_body_rad_per_s;
  for (int a = 0; a < 3; ++a) {
    k.omega_w[a] = k.r[a][0] * w.x() + k.r[a][1] * w.y() + k.r[a][2] * w.z();
  }
  return k;
}

inline void Rotate(const double r[3][3], const Eigen::Vector3d& x, double* out) {
  for (int a = 0; a < 3; ++a) {
    out[a] = r[a][0] * x.x() + r[a][1] * x.y() + r[a][2] * x.z();
  }
}

inline void Cross(const double* a, const double* b, double* out) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

// sin/cos/exp of small arguments (|x| < 0.02): Taylor to 5th order, relative
// error < 1e-13; exact library calls otherwise.
inline void SmallSinCos(double e, double* s, double* c) {
  if (std::fabs(e) < 0.02) {
    // Multiplications by reciprocal constants (no divisions in the hot loop).
    const double e2 = e * e;
    *s = e * (1.0 - e2 * (1.0 / 6.0) * (1.0 - e2 * (1.0 / 20.0)));
    *c = 1.0 - e2 * 0.5 * (1.0 - e2 * (1.0 / 12.0) * (1.0 - e2 * (1.0 / 30.0)));
  } else {
    *s = std::sin(e);
    *c = std::cos(e);
  }
}
// (sin, cos) of ph0 + e from (s0, c0) of ph0: angle addition.
inline void RotateBy(double s0, double c0, double e, double* s, double* c) {
  double se, ce;
  SmallSinCos(e, &se, &ce);
  *s = s0 * ce + c0 * se;
  *c = c0 * ce - s0 * se;
}
inline double SmallExp(double x) {
  if (std::fabs(x) < 0.02) {
    return 1.0 + x * (1.0 + x * 0.5 *
                                (1.0 + x * (1.0 / 3.0) *
                                           (1.0 + x * 0.25 * (1.0 + x * 0.2 * (1.0 + x * (1.0 / 6.0))))));
  }
  return std::exp(x);
}

}  // namespace

void Plant::AddMagneticOblique(const Kinematics& k, const double* currents_A, Accum* acc) const {
  // World frame, every side on its own (full sin/cos per array): 12 sides.
  const double rest_gap = config_.field.rest_gap_m;
  const double(&r)[3][3] = k.r;
  for (const ObliqueSide& c : oblique_sides_) {
    const double* rb = c.rb;
    double rw[3];
    for (int a = 0; a < 3; ++a) rw[a] = r[a][0] * rb[0] + r[a][1] * rb[1] + r[a][2] * rb[2];
    const double gap = rest_gap + k.p[2] + rw[2] - rb[2];
    const FieldXYZ b = field_.ObliqueSideField(c.amp, k.p[0] + rw[0], k.p[1] + rw[1], gap);
    const double uw[3] = {r[0][0] * c.ux + r[0][1] * c.uy, r[1][0] * c.ux + r[1][1] * c.uy,
                          r[2][0] * c.ux + r[2][1] * c.uy};
    const double bw[3] = {b.b_x_T, b.b_y_T, b.b_z_T};
    double f[3];
    Cross(uw, bw, f);
    const double scale = side_force_per_A_ * currents_A[c.coil];
    for (double& v : f) v *= scale;
    if (forcer_errors_active_) {
      // Paper 003 in the platen frame: F_t -> F_t (1 + eps_t) along the
      // forcer's thrust axis, dF_z = eps_z F_t.
      double fb[3];
      for (int a = 0; a < 3; ++a) fb[a] = r[0][a] * f[0] + r[1][a] * f[1] + r[2][a] * f[2];
      const double ft = c.hx * fb[0] + c.hy * fb[1];
      fb[0] += c.eps_t * ft * c.hx;
      fb[1] += c.eps_t * ft * c.hy;
      fb[2] += c.eps_z * ft;
      for (int a = 0; a < 3; ++a) f[a] = r[a][0] * fb[0] + r[a][1] * fb[1] + r[a][2] * fb[2];
    }
    double t[3];
    Cross(rw, f, t);
    for (int a = 0; a < 3; ++a) {
      acc->f[a] += f[a];
      acc->t[a] += t[a];
    }
  }
}

// ---------------------------------------------------------------------------
// AddMagnetic, four forcers at a time. Lane f of every vector is forcer f's
// side at position q (q = 0: its reference side): the operations are
// AddMagnetic's below, written once for a vector of 4 doubles, in the same
// order with the same parentheses, so every lane rounds exactly as the
// scalar loop does (IEEE-754 add/mul/sub are lane-wise; -ffp-contract=off
// keeps them apart; the library sin/cos/exp stay scalar calls). Only the
// force and torque sums cross sides: they are added in the scalar loop's
// side order after the lanes are done. GCC vector extensions: 4 doubles are
// one AVX register, or two SSE2 registers on a baseline x86-64.
// ---------------------------------------------------------------------------
#pragma GCC diagnostic ignored "-Wpsabi"
namespace {
typedef double V4 __attribute__((vector_size(32)));
typedef long long M4 __attribute__((vector_size(32)));

__attribute__((always_inline)) inline V4 Load4(const double* p) {
  V4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
__attribute__((always_inline)) inline V4 Splat4(double x) { return V4{x, x, x, x}; }

// SmallSinCos / SmallExp lane by lane: the Taylor branch as vectors, a lane
// outside |x| < 0.02 (or NaN) takes the library call, as the scalar does.
// |x| < 0.02 in every lane (false for a NaN lane, as the scalar test).
__attribute__((always_inline)) inline M4 Small4(V4 x) { return (x < 0.02) & (x > -0.02); }
__attribute__((always_inline)) inline bool All4(M4 m) { return (m[0] & m[1] & m[2] & m[3]) != 0; }
__attribute__((always_inline)) inline void SmallSinCos4(V4 e, bool all_small, V4* s, V4* c) {
  const V4 e2 = e * e;
  V4 sv = e * (1.0 - e2 * (1.0 / 6.0) * (1.0 - e2 * (1.0 / 20.0)));
  V4 cv = 1.0 - e2 * 0.5 * (1.0 - e2 * (1.0 / 12.0) * (1.0 - e2 * (1.0 / 30.0)));
  if (!all_small) {
    for (int i = 0; i < 4; ++i) {
      if (!(std::fabs(e[i]) < 0.02)) {
        sv[i] = std::sin(e[i]);
        cv[i] = std::cos(e[i]);
      }
    }
  }
  *s = sv;
  *c = cv;
}
__attribute__((always_inline)) inline V4 SmallExp4(V4 x, bool all_small) {
  V4 y = 1.0 + x * (1.0 + x * 0.5 *
                              (1.0 + x * (1.0 / 3.0) *
                                         (1.0 + x * 0.25 * (1.0 + x * 0.2 * (1.0 + x * (1.0 / 6.0))))));
  if (!all_small) {
    for (int i = 0; i < 4; ++i) {
      if (!(std::fabs(x[i]) < 0.02)) y[i] = std::exp(x[i]);
    }
  }
  return y;
}
// (sin, cos, exp) at phase ph0 + eps and decay exponent x0 + xe from
// (s0, c0, e0) at (ph0, x0): angle addition, exp(x0) exp(xe).
__attribute__((always_inline)) inline void Advance4(V4 s0, V4 c0, V4 e0, V4 eps, V4 xe, V4* s, V4* c, V4* e) {
  const bool all_small = All4(Small4(eps) & Small4(xe));
  V4 se, ce;
  SmallSinCos4(eps, all_small, &se, &ce);
  *s = s0 * ce + c0 * se;
  *c = c0 * ce - s0 * se;
  *e = e0 * SmallExp4(xe, all_small);
}
}  // namespace

__attribute__((always_inline)) inline void Plant::MagneticLanesBody(const Kinematics& k, const double* currents_A,
                                                                    Accum* acc) const {
  const double gamma1 = field_.gamma1_per_m();
  const double* amp = field_.side_amplitudes_T();
  const double(&r)[3][3] = k.r;
  const V4 g1 = Splat4(gamma1);
  const V4 neg_g1 = Splat4(-gamma1);
  // Per lane: the forcer's array axis picks the position and R's row.
  V4 p_ax, r_ax0, r_ax1, r_ax2;
  for (int f = 0; f < 4; ++f) {
    const int ax = lane_axis_[f];
    p_ax[f] = k.p[ax];
    r_ax0[f] = r[ax][0];
    r_ax1[f] = r[ax][1];
    r_ax2[f] = r[ax][2];
  }
  const V4 r20 = Splat4(r[2][0]), r21 = Splat4(r[2][1]), r22 = Splat4(r[2][2]);
  const V4 gap0 = Splat4(config_.field.rest_gap_m + k.p[2]);
  const V4 force_per_A = Splat4(side_force_per_A_);
  V4 ref_s{}, ref_gap{}, ref_sin{}, ref_cos{}, ref_exp{};
  // Per side (index 4 f + q) force and torque, platen frame, transposed so
  // that the sums below run four (f0, f1, f2, t0) and two (t1, t2) chains
  // per vector add: side_a[q][f] = {f0, f1, f2, t0} of side 4 f + q,
  // side_b[q][f] = {t1, t2, -, -} (lanes 2-3 unused).
  V4 side_a[4][4];
  V4 side_b[4][4];
  for (int q = 0; q < 4; ++q) {
    const SideLanes& c = side_lanes_[static_cast<std::size_t>(q)];
    const V4 rb0 = Load4(c.rb0), rb1 = Load4(c.rb1), rb2 = Load4(c.rb2);
    const V4 s = p_ax + (r_ax0 * rb0 + r_ax1 * rb1 + r_ax2 * rb2);
    const V4 gap = gap0 + (r20 * rb0 + r21 * rb1 + r22 * rb2) - rb2;
    V4 sin1, cos1, exp1;
    if (q == 0) {
      ref_s = s;
      ref_gap = gap;
      if (lane_ref_mode_ == LaneRefMode::kFromStore || lane_ref_mode_ == LaneRefMode::kChain) {
        // kFast, RK4 stages 2-4: the reference side moved by at most microns
        // since stage 1 (gamma_1 ds ~ 1e-3): its sin/cos/exp by angle addition
        // from stage 1's, as the other sides are derived from it (Taylor
        // branch, relative error < 1e-13; library calls past |x| = 0.02).
        // kChain, stage 1: the same from the previous sub-step's stage 1 (at
        // most 0.2 mm away), stored for this sub-step's stages 2-4 and the
        // next stage 1.
        Advance4(Load4(lane_ref_store_.sin), Load4(lane_ref_store_.cos), Load4(lane_ref_store_.exp),
                 g1 * (s - Load4(lane_ref_store_.s)), neg_g1 * (gap - Load4(lane_ref_store_.gap)), &ref_sin,
                 &ref_cos, &ref_exp);
      } else {
        const V4 gs = g1 * s;
        const V4 gg = neg_g1 * gap;
        for (int f = 0; f < 4; ++f) {
          ref_sin[f] = std::sin(gs[f]);
          ref_cos[f] = std::cos(gs[f]);
          ref_exp[f] = std::exp(gg[f]);
        }
      }
      if (lane_ref_mode_ == LaneRefMode::kStore || lane_ref_mode_ == LaneRefMode::kChain) {
        std::memcpy(lane_ref_store_.s, &ref_s, sizeof ref_s);
        std::memcpy(lane_ref_store_.gap, &ref_gap, sizeof ref_gap);
        std::memcpy(lane_ref_store_.sin, &ref_sin, sizeof ref_sin);
        std::memcpy(lane_ref_store_.cos, &ref_cos, sizeof ref_cos);
        std::memcpy(lane_ref_store_.exp, &ref_exp, sizeof ref_exp);
      }
      sin1 = ref_sin;
      cos1 = ref_cos;
      exp1 = ref_exp;
    } else {
      const V4 qc = Load4(c.qc), qs = Load4(c.qs);
      const V4 sq = ref_sin * qc + ref_cos * qs;
      const V4 cq = ref_cos * qc - ref_sin * qs;
      Advance4(sq, cq, ref_exp, g1 * (s - ref_s) - Load4(c.q_half_pi), neg_g1 * (gap - ref_gap), &sin1, &cos1,
               &exp1);
    }
    // n = 1, 5, 9, 13 (lanes_ok_ only with 4 harmonics).
    const V4 s2 = 2.0 * sin1 * cos1;
    const V4 c2 = cos1 * cos1 - sin1 * sin1;
    const V4 s4 = 2.0 * s2 * c2;
    const V4 c4 = c2 * c2 - s2 * s2;
    const V4 e2 = exp1 * exp1;
    const V4 e4 = e2 * e2;
    const V4 s5 = sin1 * c4 + cos1 * s4, c5 = cos1 * c4 - sin1 * s4, e5 = exp1 * e4;
    const V4 s9 = s5 * c4 + c5 * s4, c9 = c5 * c4 - s5 * s4, e9 = e5 * e4;
    const V4 s13 = s9 * c4 + c9 * s4, c13 = c9 * c4 - s9 * s4, e13 = e9 * e4;
    const V4 b_s = amp[0] * exp1 * sin1 + amp[1] * e5 * s5 + amp[2] * e9 * s9 + amp[3] * e13 * s13;
    const V4 b_z = amp[0] * exp1 * cos1 + amp[1] * e5 * c5 + amp[2] * e9 * c9 + amp[3] * e13 * c13;
    const V4 bb0 = b_s * r_ax0 + b_z * r20;
    const V4 bb1 = b_s * r_ax1 + b_z * r21;
    const V4 bb2 = b_s * r_ax2 + b_z * r22;
    V4 cur;
    for (int f = 0; f < 4; ++f) cur[f] = currents_A[c.coil[f]];
    const V4 scale = force_per_A * cur;
    const V4 ux = Load4(c.ux), uy = Load4(c.uy);
    V4 f0 = scale * (uy * bb2);
    V4 f1 = scale * (-ux * bb2);
    V4 f2 = scale * (ux * bb1 - uy * bb0);
    const V4 sel_x = Load4(c.sel_x), sel_y = Load4(c.sel_y);
    if (as_built_) {
      const V4 gain = Load4(c.gain), roll = Load4(c.roll);
      f0 *= gain;
      f1 *= gain;
      f2 *= gain;
      const V4 t0 = sel_x * f0 + sel_y * f1;
      const V4 dt = -roll * f2;
      f2 += roll * t0;
      f0 += sel_x * dt;
      f1 += sel_y * dt;
    }
    const V4 ft = sel_x * f0 + sel_y * f1;
    f0 += Load4(c.eps_t_x) * ft;
    f1 += Load4(c.eps_t_y) * ft;
    f2 += Load4(c.eps_z) * ft;
    const V4 t0 = rb1 * f2 - rb2 * f1;
    const V4 t1 = rb2 * f0 - rb0 * f2;
    const V4 t2 = rb0 * f1 - rb1 * f0;
    // 4 x 4 transpose of the rows (f0, f1, f2, t0) over the lanes f.
    const V4 lo01 = __builtin_shuffle(f0, f1, M4{0, 4, 2, 6});
    const V4 hi01 = __builtin_shuffle(f0, f1, M4{1, 5, 3, 7});
    const V4 lo23 = __builtin_shuffle(f2, t0, M4{0, 4, 2, 6});
    const V4 hi23 = __builtin_shuffle(f2, t0, M4{1, 5, 3, 7});
    side_a[q][0] = __builtin_shuffle(lo01, lo23, M4{0, 1, 4, 5});
    side_a[q][1] = __builtin_shuffle(hi01, hi23, M4{0, 1, 4, 5});
    side_a[q][2] = __builtin_shuffle(lo01, lo23, M4{2, 3, 6, 7});
    side_a[q][3] = __builtin_shuffle(hi01, hi23, M4{2, 3, 6, 7});
    const V4 lo45 = __builtin_shuffle(t1, t2, M4{0, 4, 2, 6});
    const V4 hi45 = __builtin_shuffle(t1, t2, M4{1, 5, 3, 7});
    side_b[q][0] = lo45;
    side_b[q][1] = hi45;
    side_b[q][2] = __builtin_shuffle(lo45, M4{2, 3, 2, 3});
    side_b[q][3] = __builtin_shuffle(hi45, M4{2, 3, 2, 3});
  }
  // The sums in the scalar loop's side order 0..15 (idx = 4 f + q), each of
  // the six chains in its own lane: IEEE adds are lane-wise, so every chain
  // rounds as the scalar loop's.
  V4 sum_a = Splat4(0.0), sum_b = Splat4(0.0);
  for (int f = 0; f < 4; ++f) {
    for (int q = 0; q < 4; ++q) {
      sum_a += side_a[q][f];
      sum_b += side_b[q][f];
    }
  }
  const double fb[3] = {sum_a[0], sum_a[1], sum_a[2]};
  const double tb[3] = {sum_a[3], sum_b[0], sum_b[1]};
  for (int a = 0; a < 3; ++a) {
    acc->f[a] += r[a][0] * fb[0] + r[a][1] * fb[1] + r[a][2] * fb[2];
    acc->t[a] += r[a][0] * tb[0] + r[a][1] * tb[1] + r[a][2] * tb[2];
  }
}

__attribute__((target("avx"))) void Plant::AddMagneticLanesAvx(const Kinematics& k, const double* currents_A,
                                                               Accum* acc) const {
  MagneticLanesBody(k, currents_A, acc);
}
void Plant::AddMagneticLanesBase(const Kinematics& k, const double* currents_A, Accum* acc) const {
  MagneticLanesBody(k, currents_A, acc);
}
// (-Wpsabi stays off to the end of the file: GCC reports the 32-byte vector
// ABI note at the end of the translation unit; no V4 crosses a call.)

void Plant::AddMagnetic(const Kinematics& k, const double* currents_A, Accum* acc) const {
  if (triangle_) {
    AddMagneticOblique(k, currents_A, acc);
    return;
  }
  if (lanes_ok_) {
    if (lanes_avx_) {
      AddMagneticLanesAvx(k, currents_A, acc);
    } else {
      AddMagneticLanesBase(k, currents_A, acc);
    }
    return;
  }
  // Evaluated in the PLATEN frame (the cheap frame: every side's r_body and
  // in-plane u_body are constants): a side's world field (B_s along its array
  // axis, B_z) is rotated into the platen frame with two rows of R, the
  // Lorentz force u x B and its torque r x F are formed there, and the sums
  // are rotated back once. Identical physics to the world-frame form
  // (R a x R b = R (a x b)); only the round-off differs.
  const double gamma1 = field_.gamma1_per_m();
  const double rest_gap = config_.field.rest_gap_m;
  const double* amp = field_.side_amplitudes_T();
  const int harmonics = field_.harmonics();
  const double(&r)[3][3] = k.r;
  double fb[3] = {0.0, 0.0, 0.0};  // platen-frame force sum
  double tb[3] = {0.0, 0.0, 0.0};  // platen-frame torque sum (about the CoM)
  double ref_s = 0.0, ref_gap = 0.0, ref_sin = 0.0, ref_cos = 1.0, ref_exp = 1.0;
  for (std::size_t idx = 0; idx < side_constants_.size(); ++idx) {
    const SideConstants& c = side_constants_[idx];
    const double* rb = c.rb;
    const int ax = c.ax;
    // World coordinate along the array axis and air gap of the side midpoint.
    const double s = k.p[ax] + (r[ax][0] * rb[0] + r[ax][1] * rb[1] + r[ax][2] * rb[2]);
    const double gap = rest_gap + k.p[2] + (r[2][0] * rb[0] + r[2][1] * rb[1] + r[2][2] * rb[2]) - rb[2];
    double sin1, cos1, exp1;
    if (idx % 4 == 0) {  // the forcer's reference side: the only full sincos/exp
      ref_s = s;
      ref_gap = gap;
      ref_sin = std::sin(gamma1 * s);
      ref_cos = std::cos(gamma1 * s);
      ref_exp = std::exp(-gamma1 * gap);
      sin1 = ref_sin;
      cos1 = ref_cos;
      exp1 = ref_exp;
    } else {
      // theta = theta_ref + q pi/2 + eps: exact quarter turns, then eps.
      const double sq = ref_sin * c.qc + ref_cos * c.qs;
      const double cq = ref_cos * c.qc - ref_sin * c.qs;
      RotateBy(sq, cq, gamma1 * (s - ref_s) - c.q_half_pi, &sin1, &cos1);
      exp1 = ref_exp * SmallExp(-gamma1 * (gap - ref_gap));
    }
    FieldSZ b;
    if (harmonics == 4) {  // the default n = 1, 5, 9, 13, unrolled
      const double s2 = 2.0 * sin1 * cos1;
      const double c2 = cos1 * cos1 - sin1 * sin1;
      const double s4 = 2.0 * s2 * c2;
      const double c4 = c2 * c2 - s2 * s2;
      const double e2 = exp1 * exp1;
      const double e4 = e2 * e2;
      const double s5 = sin1 * c4 + cos1 * s4, c5 = cos1 * c4 - sin1 * s4, e5 = exp1 * e4;
      const double s9 = s5 * c4 + c5 * s4, c9 = c5 * c4 - s5 * s4, e9 = e5 * e4;
      const double s13 = s9 * c4 + c9 * s4, c13 = c9 * c4 - s9 * s4, e13 = e9 * e4;
      b.b_s_T = amp[0] * exp1 * sin1 + amp[1] * e5 * s5 + amp[2] * e9 * s9 + amp[3] * e13 * s13;
      b.b_z_T = amp[0] * exp1 * cos1 + amp[1] * e5 * c5 + amp[2] * e9 * c9 + amp[3] * e13 * c13;
    } else {
      b = field_.SideAverageFieldFrom(sin1, cos1, exp1);
    }
    // Field in the platen frame: R^T (B_s e_ax + B_z e_z).
    const double bb0 = b.b_s_T * r[ax][0] + b.b_z_T * r[2][0];
    const double bb1 = b.b_s_T * r[ax][1] + b.b_z_T * r[2][1];
    const double bb2 = b.b_s_T * r[ax][2] + b.b_z_T * r[2][2];
    // F = N p I (u x B); u lies in the platen plane (u_z = 0).
    const double scale = side_force_per_A_ * currents_A[c.coil];
    double f0 = scale * (c.uy * bb2);
    double f1 = scale * (-c.ux * bb2);
    double f2 = scale * (c.ux * bb1 - c.uy * bb0);
    if (as_built_) {
      // The forcer's b* error scales both components; the coil's roll turns
      // (F_t, F_z) by its angle.
      f0 *= c.gain;
      f1 *= c.gain;
      f2 *= c.gain;
      const double t0 = c.sel_x * f0 + c.sel_y * f1;
      const double dt = -c.roll * f2;
      f2 += c.roll * t0;
      f0 += c.sel_x * dt;
      f1 += c.sel_y * dt;
    }
    // Paper 003: F_t -> F_t (1 + eps_t), dF_z = eps_z F_t (platen frame).
    // Branch-free in registers: the selectors are exact 0/1 (the tangential
    // axis is X' or Y'), eps = 0 when the errors are off (exact no-ops).
    const double ft = c.sel_x * f0 + c.sel_y * f1;
    f0 += c.eps_t_x * ft;
    f1 += c.eps_t_y * ft;
    f2 += c.eps_z * ft;
    fb[0] += f0;
    fb[1] += f1;
    fb[2] += f2;
    tb[0] += rb[1] * f2 - rb[2] * f1;
    tb[1] += rb[2] * f0 - rb[0] * f2;
    tb[2] += rb[0] * f1 - rb[1] * f0;
  }
  for (int a = 0; a < 3; ++a) {
    acc->f[a] += r[a][0] * fb[0] + r[a][1] * fb[1] + r[a][2] * fb[2];
    acc->t[a] += r[a][0] * tb[0] + r[a][1] * tb[1] + r[a][2] * tb[2];
  }
}

// The springs' attachments and constants, computed once exactly as the
// per-evaluation code computed them (same expressions, same rounding).
void Plant::BuildSprings() {
  spring_count_ = 0;
  auto add = [&](double x, double y, double k_spring, double c_spring) {
    if (as_built_) {
      x -= config_.as_built.com_offset_m[0];
      y -= config_.as_built.com_offset_m[1];
    }
    Spring& s = springs_[static_cast<std::size_t>(spring_count_++)];
    s.rb[0] = x;
    s.rb[1] = y;
    s.rb[2] = -com_arm_m_;
    s.k_N_per_m = k_spring;
    s.c_Ns_per_m = c_spring;
  };
  if (triangle_) {
    // Three spring-dampers (k/3, c/3) at the triangle's forcer centres: their
    // centroid is the CoM and sum(y^2) = sum(x^2) = 3 l^2 / 2, sum(x y) = 0
    // for any alpha, so k_torsional = (k/2) l^2 about X and Y exactly as the
    // cross layout's four (eqs (29)-(31)).
    const double k3 = k_susp_ / 3.0;
    const double c3 = config_.suspension.damping_Ns_per_m / 3.0;
    for (int f = 0; f < kTriangleForcers; ++f) {
      double c[2], h[2];
      TriangleForcer(f, c, h);
      add(c[0], c[1], k3, c3);
    }
    return;
  }
  const double k4 = k_susp_ / 4.0;
  const double c4 = config_.suspension.damping_Ns_per_m / 4.0;
  for (int f = 0; f < kForcers; ++f) {
    const Eigen::Vector2d fc = ForcerCentre(f, config_.body.lever_arm_m, config_.body.layout);
    add(fc.x(), fc.y(), k4, c4);
  }
  for (int i = 0; i < spring_count_; ++i) {
    const Spring& sp = springs_[static_cast<std::size_t>(i)];
    for (int a = 0; a < 3; ++a) spring_lanes_[a][i] = sp.rb[a];
    spring_lanes_[3][i] = sp.k_N_per_m;
    spring_lanes_[4][i] = sp.c_Ns_per_m;
  }
}

// The suspension spring-dampers under the forcers (at the coils' plane):
// their vertical forces and the tilt torques they make.
void Plant::AddSuspension(const Kinematics& k, Accum* acc) const {
  if (!config_.suspension.enabled) {
    return;
  }
  const double h0 = config_.suspension.neutral_height_m;
  // The three sums in locals: stores through acc may alias k (both double),
  // which made the compiler reload k's entries for every spring. Same
  // operations in the same order.
  double f2 = acc->f[2], t0 = acc->t[0], t1 = acc->t[1];
  const double r00 = k.r[0][0], r01 = k.r[0][1], r02 = k.r[0][2];
  const double r10 = k.r[1][0], r11 = k.r[1][1], r12 = k.r[1][2];
  const double r20 = k.r[2][0], r21 = k.r[2][1], r22 = k.r[2][2];
  const double pz = k.p[2], vz = k.v[2], wx = k.omega_w[0], wy = k.omega_w[1];
  if (spring_count_ == 4) {
    // Four springs, one per lane: the scalar loop's expressions with the
    // same parentheses (IEEE ops are lane-wise), then its three sums in
    // spring order.
    const V4 rb0 = Load4(spring_lanes_[0]), rb1 = Load4(spring_lanes_[1]), rb2 = Load4(spring_lanes_[2]);
    const V4 kk = Load4(spring_lanes_[3]), cc = Load4(spring_lanes_[4]);
    const V4 rw0 = Splat4(r00) * rb0 + Splat4(r01) * rb1 + Splat4(r02) * rb2;
    const V4 rw1 = Splat4(r10) * rb0 + Splat4(r11) * rb1 + Splat4(r12) * rb2;
    const V4 rw2 = Splat4(r20) * rb0 + Splat4(r21) * rb1 + Splat4(r22) * rb2;
    const V4 h = Splat4(pz) + rw2 - rb2;
    const V4 hdot = Splat4(vz) + Splat4(wx) * rw1 - Splat4(wy) * rw0;
    const V4 fz = -kk * (h - h0) - cc * hdot;
    const V4 m0 = rw1 * fz, m1 = rw0 * fz;
    for (int i = 0; i < 4; ++i) {
      f2 += fz[i];
      t0 += m0[i];
      t1 -= m1[i];
    }
    acc->f[2] = f2;
    acc->t[0] = t0;
    acc->t[1] = t1;
    return;
  }
  for (int i = 0; i < spring_count_; ++i) {
    const Spring& s = springs_[static_cast<std::size_t>(i)];
    const double* rb = s.rb;
    const double rw0 = r00 * rb[0] + r01 * rb[1] + r02 * rb[2];
    const double rw1 = r10 * rb[0] + r11 * rb[1] + r12 * rb[2];
    const double rw2 = r20 * rb[0] + r21 * rb[1] + r22 * rb[2];
    const double h = pz + rw2 - rb[2];
    const double hdot = vz + wx * rw1 - wy * rw0;
    const double fz = -s.k_N_per_m * (h - h0) - s.c_Ns_per_m * hdot;
    f2 += fz;
    t0 += rw1 * fz;
    t1 -= rw0 * fz;
  }
  acc->f[2] = f2;
  acc->t[0] = t0;
  acc->t[1] = t1;
}

void Plant::AddContact(const Kinematics& k, Accum* acc, double* normal_N, bool* touching) const {
  *normal_N = 0.0;
  *touching = false;
  if (!config_.contact.enabled) {
    return;
  }
  const double c = config_.contact.corner_half_size_m;
  // Levitated: the lowest corner is clearly above the surface (a lower bound
  // of the four heights below, with a 1 pm margin for round-off) -> no
  // contact, exactly what the corner loop would find.
  const double lowest = k.p[2] - c * (std::fabs(k.r[2][0]) + std::fabs(k.r[2][1])) - com_arm_m_ * (k.r[2][2] - 1.0);
  if (lowest > 1e-12) {
    return;
  }
  // The four corners (+c, +c), (-c, +c), (-c, -c), (+c, -c) one per vector
  // lane: per corner rw = R rb, its height h, its velocity v + omega x rw, the
  // one-sided normal force (the surface pushes, never pulls) and a regularized
  // Coulomb friction. IEEE ops are lane-wise, so each lane rounds as the
  // former per-corner loop did; a corner that does not touch computes values
  // nobody reads. The sums then run in corner order over the corners that
  // touch and push: the same additions as that loop.
  const V4 rbx = V4{c, -c, -c, c}, rby = V4{c, c, -c, -c};
  const V4 rbz = Splat4(-com_arm_m_);
  const double(&r)[3][3] = k.r;
  const V4 rw0 = Splat4(r[0][0]) * rbx + Splat4(r[0][1]) * rby + Splat4(r[0][2]) * rbz;
  const V4 rw1 = Splat4(r[1][0]) * rbx + Splat4(r[1][1]) * rby + Splat4(r[1][2]) * rbz;
  const V4 rw2 = Splat4(r[2][0]) * rbx + Splat4(r[2][1]) * rby + Splat4(r[2][2]) * rbz;
  const V4 h = Splat4(k.p[2]) + rw2 - rbz;
  const V4 w0 = Splat4(k.omega_w[0]), w1 = Splat4(k.omega_w[1]), w2 = Splat4(k.omega_w[2]);
  const V4 vel0 = Splat4(k.v[0]) + (w1 * rw2 - w2 * rw1);
  const V4 vel1 = Splat4(k.v[1]) + (w2 * rw0 - w0 * rw2);
  const V4 vel2 = Splat4(k.v[2]) + (w0 * rw1 - w1 * rw0);
  const V4 push = Splat4(-config_.contact.stiffness_N_per_m) * h - Splat4(config_.contact.damping_Ns_per_m) * vel2;
  const double vs = config_.contact.friction_velocity_m_per_s;
  const V4 speed2 = vel0 * vel0 + vel1 * vel1 + Splat4(vs * vs);
  for (int i = 0; i < 4; ++i) {
    if (h[i] >= 0.0) continue;
    const double fn = std::max(0.0, push[i]);
    *touching = true;
    if (fn <= 0.0) continue;
    const double scale = config_.contact.friction_coefficient * fn / std::sqrt(speed2[i]);
    const double f[3] = {-scale * vel0[i], -scale * vel1[i], fn};
    const double rw[3] = {rw0[i], rw1[i], rw2[i]};
    double tq[3];
    Cross(rw, f, tq);
    for (int a = 0; a < 3; ++a) {
      acc->f[a] += f[a];
      acc->t[a] += tq[a];
    }
    *normal_N += fn;
  }
}

Wrench Plant::ToWrench(const Kinematics& k, const Accum& acc) {
  Wrench w;
  for (int a = 0; a < 3; ++a) {
    w.force_world_N[a] = acc.f[a];
    // body torque = R^T * world torque
    w.torque_body_Nm[a] = k.r[0][a] * acc.t[0] + k.r[1][a] * acc.t[1] + k.r[2][a] * acc.t[2];
  }
  return w;
}

Wrench Plant::MagneticWrench(const BodyState& state, const double* currents_A) const {
  const Kinematics k = MakeKinematics(state);
  Accum acc{};
  AddMagnetic(k, currents_A, &acc);
  return ToWrench(k, acc);
}

Plant::ContactResult Plant::ContactWrench(const BodyState& state) const {
  const Kinematics k = MakeKinematics(state);
  Accum acc{};
  ContactResult out{};
  AddContact(k, &acc, &out.normal_N, &out.touching);
  out.wrench = ToWrench(k, acc);
  return out;
}

Wrench Plant::TotalWrench(const BodyState& state, const double* currents_A) const {
  const Kinematics k = MakeKinematics(state);
  Accum acc{};
  AddMagnetic(k, currents_A, &acc);
  AddSuspension(k, &acc);
  double normal = 0.0;
  bool touching = false;
  AddContact(k, &acc, &normal, &touching);
  if (config_.body.gravity_enabled) {
    acc.f[2] -= mass_ * config_.body.gravity_m_per_s2;
  }
  if (external_force_active_) {
    for (int i = 0; i < 3; ++i) acc.f[i] += external_force_N_[i];
  }
  if (floor_.active()) {
    for (int a = 0; a < FloorVibration::kAxes; ++a) acc.f[a] += floor_force_N_[a];
  }
  return ToWrench(k, acc);
}

void Plant::set_external_force(const Eigen::Vector3d& force_world_N) {
  external_force_N_ = force_world_N;
  external_force_active_ = !force_world_N.isZero(0.0);
  truth_wrench_stale_ = true;
}

BodyDerivative Plant::Derivative(const BodyState& state, const double* currents_A) const {
  const Wrench w = TotalWrench(state, currents_A);
  BodyDerivative d;
  d.velocity_m_per_s = state.velocity_m_per_s;
  d.acceleration_m_per_s2 = w.force_world_N / mass_;
  const Eigen::Quaterniond& q = state.attitude;
  const Eigen::Vector3d& om = state.omega_body_rad_per_s;
  // q_dot = 1/2 q (x) (0, omega_body)
  d.attitude_rate = {-0.5 * (q.x() * om.x() + q.y() * om.y() + q.z() * om.z()),
                     0.5 * (q.w() * om.x() + q.y() * om.z() - q.z() * om.y()),
                     0.5 * (q.w() * om.y() + q.z() * om.x() - q.x() * om.z()),
                     0.5 * (q.w() * om.z() + q.x() * om.y() - q.y() * om.x())};
  // Euler's equations in the principal body frame.
  if (full_inertia_) {
    const Eigen::Vector3d i_om = inertia_matrix_ * om;
    d.angular_acceleration_body = inertia_inverse_ * (w.torque_body_Nm - om.cross(i_om));
    return d;
  }
  const Eigen::Vector3d i_om = inertia_.cwiseProduct(om);
  d.angular_acceleration_body = (w.torque_body_Nm - om.cross(i_om)).cwiseQuotient(inertia_);
  return d;
}

double Plant::KineticEnergy(const BodyState& state) const {
  const Eigen::Vector3d& om = state.omega_body_rad_per_s;
  return 0.5 * mass_ * state.velocity_m_per_s.squaredNorm() + 0.5 * om.dot(inertia_.cwiseProduct(om));
}

// ---------------------------------------------------------------------------
// Integration
// ---------------------------------------------------------------------------
namespace {

BodyState Step(const BodyState& s, const BodyDerivative& d, double h) {
  BodyState o;
  o.position_m = s.position_m + h * d.velocity_m_per_s;
  o.velocity_m_per_s = s.velocity_m_per_s + h * d.acceleration_m_per_s2;
  o.attitude = Eigen::Quaterniond(s.attitude.w() + h * d.attitude_rate[0], s.attitude.x() + h * d.attitude_rate[1],
                                  s.attitude.y() + h * d.attitude_rate[2], s.attitude.z() + h * d.attitude_rate[3]);
  o.omega_body_rad_per_s = s.omega_body_rad_per_s + h * d.angular_acceleration_body;
  return o;
}

}  // namespace

void Plant::apply(const io::ActuatorCommand& command) {
  amplifiers_.Apply(command, &rng_, config_.amplifier.current_noise_scale > 0.0);
  UpdateTruthCurrents();  // the body did not move
}

// True when no corner can reach the surface within 2 dt: the lowest corner's
// height (AddContact's lower bound) exceeds 1 um plus twice the distance any
// corner can move in 2 dt at the present speeds (|v_z| + |omega| times the
// corner's distance from the CoM). Only then may kFast take a 400 us step.
bool Plant::ClearOfSurface(double dt_s) const {
  if (!config_.contact.enabled) return true;
  const Eigen::Matrix3d r = body_.attitude.toRotationMatrix();
  const double c = config_.contact.corner_half_size_m;
  const double lowest = body_.position_m.z() - c * (std::fabs(r(2, 0)) + std::fabs(r(2, 1))) - com_arm_m_ * (r(2, 2) - 1.0);
  const double reach_m = std::sqrt(2.0 * c * c + com_arm_m_ * com_arm_m_);
  const double speed = std::fabs(body_.velocity_m_per_s.z()) + body_.omega_body_rad_per_s.norm() * reach_m;
  return lowest > 1e-6 + 2.0 * (2.0 * dt_s) * speed;
}

void Plant::advance(double dt_s) {
  if (!(dt_s > 0.0)) {
    return;
  }
  // Sub-steps of at most tick / substeps_per_tick (kFast: tick / 1 while
  // clear of the surface).
  const bool fast = config_.integration.method == IntegrationConfig::Method::kFast;
  int per_tick = std::max(1, config_.integration.substeps_per_tick);
  if (fast && ClearOfSurface(dt_s)) per_tick = 1;
  const int n = std::max(1, static_cast<int>(std::ceil(dt_s / (tick_s_ / per_tick) - 1e-9)));
  const double h = dt_s / n;
  if (floor_.active()) {
    // In the base's frame the floor's acceleration u'' acts as -m u''.
    double a[FloorVibration::kAxes];
    floor_.Next(dt_s, a);
    for (int k = 0; k < FloorVibration::kAxes; ++k) floor_force_N_[k] = -mass_ * a[k];
  }
  double i0[kCoils];
  double i1[kCoils];
  double i2[kCoils];
  for (int step = 0; step < n; ++step) {
    amplifiers_.BeginSubstep(h, fast);
    for (int j = 0; j < kCoils; ++j) {
      i0[j] = amplifiers_.RkCurrent(j, 0);
      i1[j] = amplifiers_.RkCurrent(j, 1);
      i2[j] = amplifiers_.RkCurrent(j, 2);
    }
    // kFast: stage 1 evaluates the reference sides' sin/cos/exp with the
    // library (or derives them from the previous sub-step's, see
    // IntegrationConfig::field_chain_substeps) and keeps them; stages 2-4
    // derive theirs from them.
    if (fast) lane_ref_mode_ = ChainAnchor(&lane_chain_left_) ? LaneRefMode::kStore : LaneRefMode::kChain;
    const BodyDerivative k1 = Derivative(body_, i0);
    if (fast) lane_ref_mode_ = LaneRefMode::kFromStore;
    const BodyDerivative k2 = Derivative(Step(body_, k1, h / 2), i1);
    const BodyDerivative k3 = Derivative(Step(body_, k2, h / 2), i1);
    const BodyDerivative k4 = Derivative(Step(body_, k3, h), i2);
    lane_ref_mode_ = LaneRefMode::kLibrary;
    BodyDerivative sum;
    sum.velocity_m_per_s = k1.velocity_m_per_s + 2.0 * (k2.velocity_m_per_s + k3.velocity_m_per_s) + k4.velocity_m_per_s;
    sum.acceleration_m_per_s2 = k1.acceleration_m_per_s2 + 2.0 * (k2.acceleration_m_per_s2 + k3.acceleration_m_per_s2) +
                                k4.acceleration_m_per_s2;
    sum.attitude_rate = k1.attitude_rate + 2.0 * (k2.attitude_rate + k3.attitude_rate) + k4.attitude_rate;
    sum.angular_acceleration_body = k1.angular_acceleration_body +
                                    2.0 * (k2.angular_acceleration_body + k3.angular_acceleration_body) +
                                    k4.angular_acceleration_body;
    body_ = Step(body_, sum, h / 6.0);
    body_.attitude.normalize();
    amplifiers_.EndSubstep();
    truth_.time_s += h;
  }
  UpdateTruth();
}

bool Plant::ChainAnchor(int* left) const {
  if (*left > 0) {
    --*left;
    return false;
  }
  *left = std::max(1, config_.integration.field_chain_substeps) - 1;
  return true;
}

void Plant::UpdateTruth() {
  const Eigen::Matrix3d r = body_.attitude.toRotationMatrix();
  const Eigen::Vector3d ang = AnglesFromRotation(r);
  for (int a = 0; a < 3; ++a) {
    truth_.position_m[a] = body_.position_m[a];
    truth_.angles_rad[a] = ang[a];
    truth_.velocity_m_per_s[a] = body_.velocity_m_per_s[a];
    truth_.omega_body_rad_per_s[a] = body_.omega_body_rad_per_s[a];
  }
  UpdateTruthCurrents();
}

void Plant::UpdateTruthCurrents() {
  for (int j = 0; j < kCoils; ++j) {
    truth_.coil_current_A[j] = amplifiers_.current_A(j);
    truth_.coil_commanded_A[j] = amplifiers_.commanded_A(j);
  }
  truth_.amplifier_enable = amplifiers_.enabled();
  truth_wrench_stale_ = true;
}

void Plant::RefreshTruthWrench() const {
  double currents[kCoils];
  for (int j = 0; j < kCoils; ++j) {
    currents[j] = amplifiers_.current_A(j);
  }
  const Wrench m = MagneticWrench(body_, currents);
  for (int a = 0; a < 3; ++a) {
    truth_.magnetic_force_world_N[a] = m.force_world_N[a];
    truth_.magnetic_torque_body_Nm[a] = m.torque_body_Nm[a];
  }
  const ContactResult c = ContactWrench(body_);
  truth_.contact_force_N = c.normal_N;
  truth_.in_contact = c.touching;
  truth_wrench_stale_ = false;
}

// ---------------------------------------------------------------------------
// Sensors
// ---------------------------------------------------------------------------
// As built: mirror normals turned by the drawn angles, mirror faces and beams
// relative to the CoM (off the geometric centre), a bowed mirror; the reading
// is zeroed at the home pose (interferometer_zero_).
double Plant::AsBuiltInterferometer(int axis) const {
  const Eigen::Matrix3d r = body_.attitude.toRotationMatrix();
  const auto& ic = config_.interferometer;
  const AsBuiltConfig& ab = config_.as_built;
  const double d = ic.mirror_distance_m;
  const double zb = ic.beam_height_m;
  const double cx = ab.com_offset_m[0], cy = ab.com_offset_m[1];
  const Eigen::Vector3d& p = body_.position_m;
  if (axis == 0) {
    const Eigen::Vector3d nb = Eigen::Vector3d(1.0, ab.x_mirror_yaw_rad, ab.x_mirror_pitch_rad).normalized();
    const double yb = ic.x_beam_y_m;
    const Eigen::Vector3d m0(d - cx, -cy, 0.0);  // a point of the mirror face, CoM frame
    const Eigen::Vector3d n = r * nb;
    const double t = (n.dot(p) + nb.dot(m0) - n.y() * yb - n.z() * zb) / n.x();
    const Eigen::Vector3d hit = r.transpose() * (Eigen::Vector3d(t, yb, zb) - p);
    const double s = (hit.y() + cy) / ab.mirror_half_length_m;
    return t + ab.mirror_bow_m * s * s;
  }
  const double xb = ic.y_beam_x_m[axis - 1];
  const Eigen::Vector3d nb = Eigen::Vector3d(0.0, 1.0, ab.y_mirror_roll_rad).normalized();
  const Eigen::Vector3d m0(-cx, d - cy, 0.0);
  const Eigen::Vector3d n = r * nb;
  const double t = (n.dot(p) + nb.dot(m0) - n.x() * xb - n.z() * zb) / n.y();
  const Eigen::Vector3d hit = r.transpose() * (Eigen::Vector3d(xb, t, zb) - p);
  const double s = (hit.x() + cx) / ab.mirror_half_length_m;
  return t + ab.mirror_bow_m * s * s;
}

// Height offset of the LDS target (the magnet matrix top) under (x, y):
// one value per target_cell_m square, uniform in +-target_cell_height_m,
// from a hash of (target_seed, cell): no storage, any travel.
double Plant::TargetHeight(double x_m, double y_m) const {
  const AsBuiltConfig& ab = config_.as_built;
  if (ab.target_cell_height_m == 0.0) return 0.0;
  const auto i = static_cast<std::int64_t>(std::floor(x_m / ab.target_cell_m));
  const auto j = static_cast<std::int64_t>(std::floor(y_m / ab.target_cell_m));
  std::uint64_t z = ab.target_seed * 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(i) * 0xbf58476d1ce4e5b9ull +
                    static_cast<std::uint64_t>(j) * 0x94d049bb133111ebull;
  // splitmix64 finalizer
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  const double u = static_cast<double>(z >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
  return ab.target_cell_height_m * (2.0 * u - 1.0);
}

double Plant::InterferometerDisplacement(int axis) const {
  if (as_built_) return AsBuiltInterferometer(axis) - interferometer_zero_[axis];
  // Plane mirror on the platen at mirror_distance_m from the centre; the beam
  // is fixed in the world. Returns the beam's hit point along its axis minus
  // its value at the reference pose (exact, includes Abbe and cosine terms).
  const Eigen::Matrix3d r = body_.attitude.toRotationMatrix();
  const auto& ic = config_.interferometer;
  const double d = ic.mirror_distance_m;
  const double zb = ic.beam_height_m;
  const Eigen::Vector3d& p = body_.position_m;
  if (axis == 0) {
    const Eigen::Vector3d n = r.col(0);  // x beam along X at world y = x_beam_y_m
    const double t = (n.dot(p) + d - n.y() * ic.x_beam_y_m - n.z() * zb) / n.x();
    return t - d;
  }
  const double xb = ic.y_beam_x_m[axis - 1];
  const Eigen::Vector3d n = r.col(1);
  const double t = (n.dot(p) + d - n.x() * xb - n.z() * zb) / n.y();
  return t - d;
}

io::SensorSample Plant::sample() {
  io::SensorSample out{};
  std::uint16_t status = 0;
  const bool noisy = config_.sensor_noise_enabled;
  const Eigen::Matrix3d r = body_.attitude.toRotationMatrix();
  const double t = truth_.time_s;

  // --- interferometers: wrapping counters ------------------------------------
  for (int a = 0; a < io::kInterferometerAxes; ++a) {
    const double noise = noisy ? config_.interferometer.noise_of(a) * rng_.Normal() : 0.0;
    bool lost = manual_loss_[a];
    for (const BeamLossEvent& e : config_.interferometer.beam_loss_events) {
      lost = lost || (e.axis == a && t >= e.start_s && t < e.end_s);
    }
    const double displacement = InterferometerDisplacement(a);
    const double counted = config_.interferometer.sign[a] < 0 ? -displacement : displacement;
    const std::int64_t fresh = static_cast<std::int64_t>(config_.interferometer.start_count[a]) +
                               static_cast<std::int64_t>(std::floor((counted + noise) / lsb_m_));
    if (lost) {
      status = static_cast<std::uint16_t>(status | (io::kBeamLoss0 << a));
    } else {
      if (lost_prev_[a]) {
        // Incremental counter: motion during the loss is not counted, the
        // count resumes from where it froze.
        counter_adjust_[a] = last_count_[a] - fresh;
      }
      last_count_[a] = fresh + counter_adjust_[a];
    }
    lost_prev_[a] = lost;
    out.interferometer_counts[a] = static_cast<std::uint32_t>(static_cast<std::uint64_t>(last_count_[a]) & 0xffffffffu);
  }

  // --- laser displacement sensors ---------------------------------------------
  const auto& dc = config_.displacement;
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    Eigen::Vector3d rb(dc.sensor_x_m[i], dc.sensor_y_m[i], -com_arm_m_);
    double target = 0.0;
    if (as_built_) {
      rb.x() -= config_.as_built.com_offset_m[0];
      rb.y() -= config_.as_built.com_offset_m[1];
      const Eigen::Vector3d w = body_.position_m + r * rb;
      // A higher target under the spot reads as a lower platen.
      target = TargetHeight(w.x(), w.y()) - target_home_m_[i];
    }
    const double h = body_.position_m.z() + (r * rb).z() - rb.z() - target;
    const double noise = noisy ? dc.noise_of(i) * rng_.Normal() : 0.0;
    const double volts = (h + noise - dc.zero_height_m) / dc.scale_m_per_V;
    if (std::fabs(volts) > config_.adc.full_scale_V) {
      status = static_cast<std::uint16_t>(status | (io::kDisplacementOutOfRange0 << i));
    }
    out.displacement_adc[i] = QuantizeAdc(volts, config_.adc.full_scale_V);
  }

  // --- Hall sensors: A.Bx, A.By, B.Bx, B.By -------------------------------------
  const auto& hc = config_.hall;
  const double hall_xy[2][2] = {{hc.a_x_m, hc.a_y_m}, {hc.b_x_m, hc.b_y_m}};
  const double gamma1 = field_.gamma1_per_m();
  const bool anchor = ChainAnchor(&hall_chain_.left);
  for (int sensor = 0; sensor < 2; ++sensor) {
    Eigen::Vector3d rb(hall_xy[sensor][0], hall_xy[sensor][1], -com_arm_m_);
    if (as_built_) {
      rb.x() -= config_.as_built.com_offset_m[0];
      rb.y() -= config_.as_built.com_offset_m[1];
    }
    const Eigen::Vector3d w = body_.position_m + r * rb;
    const double height = hc.height_above_magnets_m + w.z() - rb.z();
    const double th[2] = {gamma1 * w.x(), gamma1 * w.y()};
    double sn[2], cs[2], decay;
    if (anchor) {
      decay = field_.PointDecay(height);
      for (int a = 0; a < 2; ++a) {
        sn[a] = std::sin(th[a]);
        cs[a] = std::cos(th[a]);
      }
    } else {
      // Angle addition from the last sample's (the platen moved < 0.2 mm:
      // gamma_1 ds < 0.02, SmallSinCos's Taylor branch; the library's sin/cos
      // of the step beyond).
      decay = hall_chain_.decay[sensor] * SmallExp(-gamma1 * (height - hall_chain_.height[sensor]));
      for (int a = 0; a < 2; ++a) {
        RotateBy(hall_chain_.sin[sensor][a], hall_chain_.cos[sensor][a], th[a] - hall_chain_.th[sensor][a], &sn[a],
                 &cs[a]);
      }
    }
    hall_chain_.height[sensor] = height;
    hall_chain_.decay[sensor] = decay;
    for (int a = 0; a < 2; ++a) {
      hall_chain_.th[sensor][a] = th[a];
      hall_chain_.sin[sensor][a] = sn[a];
      hall_chain_.cos[sensor][a] = cs[a];
    }
    const FieldSZ bx = field_.PointFieldFrom(sn[0], cs[0], decay);
    const FieldSZ by = field_.PointFieldFrom(sn[1], cs[1], decay);
    const Eigen::Vector3d b_body = r.transpose() * Eigen::Vector3d(bx.b_s_T, by.b_s_T, bx.b_z_T + by.b_z_T);
    for (int c = 0; c < 2; ++c) {
      const double noise = noisy ? hc.noise_T * rng_.Normal() : 0.0;
      out.hall_adc[2 * sensor + c] = QuantizeAdc(hc.sensitivity_V_per_T * (b_body[c] + noise), config_.adc.full_scale_V);
    }
  }

  // --- amplifier current monitors ------------------------------------------------
  const auto& ac = config_.amplifier;
  for (int j = 0; j < kCoils; ++j) {
    const double noise =
        noisy ? MonitorNoiseStd_A(ac, std::fabs(amplifiers_.commanded_A(j)), amplifiers_.force_noise_std_A()) * rng_.Normal()
              : 0.0;
    out.coil_current_adc[j] =
        QuantizeAdc(ac.monitor_gain_V_per_A * (amplifiers_.current_A(j) + noise), config_.adc.full_scale_V);
  }
  out.status_flags = status;
  return out;
}

}  // namespace maglev::hil
