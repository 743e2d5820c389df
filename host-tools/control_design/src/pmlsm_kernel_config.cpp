#include "maglev/control_design/pmlsm_kernel_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "maglev/control_design/imr_design.hpp"
#include "maglev/control_design/lqr.hpp"
#include "maglev/pmlsm_plant/force_law.hpp"

namespace maglev::control_design {
namespace sp = stage_profile;
namespace ps = pmlsm_stage;

namespace {
constexpr double kPi = 3.14159265358979323846;

// The sensor that reads profile axis `axis` directly, or nullptr.
const sp::Sensor* DirectSensor(const sp::StageProfile& p, int axis) {
  for (int i = 0; i < p.sensor_count; ++i) {
    if (p.sensors[i].measured_axis == axis) return &p.sensors[i];
  }
  return nullptr;
}
}  // namespace

bool PmlsmStageFromProfile(const sp::StageProfile& p, PmlsmStage* out, std::string* why) {
  if (p.family != sp::ActuatorFamily::kIronCorePmlsm) {
    *why = "not an iron_core_pmlsm profile";
    return false;
  }
  const sp::PmlsmParameters& m = p.pmlsm;
  PmlsmStage s;
  s.stage.motor.slot_width_b0_m = m.slot_width_m;
  s.stage.motor.slot_pitch_t1_m = m.slot_pitch_m;
  s.stage.motor.turns_per_phase_W = m.turns_per_phase;
  s.stage.motor.pole_pairs_p = m.pole_pairs;
  s.stage.motor.pm_height_hm_m = m.magnet_height_m;
  s.stage.motor.pm_length_LA_m = m.magnet_length_m;
  s.stage.motor.pm_count_pm = m.magnets_per_motor;
  s.stage.motor.pole_pitch_tau_m = m.pole_pitch_m;
  s.stage.motor.pm_width_taup_m = m.magnet_width_m;
  s.stage.motor.pm_coercivity_Hc_A_per_m = m.coercivity_A_per_m;
  s.stage.motor.winding_factor_kw1 = m.winding_factor;
  s.stage.motor.pm_recoil_permeability_mu_rec = m.recoil_permeability;
  s.stage.motor.kv3_scale = m.vertical_attraction_scale;
  s.stage.gravity_G_m_per_s2 = p.body.gravity_m_per_s2;
  auto eff = [&](int axis, double fallback) {
    return p.body.effective_mass_kg[axis] > 0.0 ? p.body.effective_mass_kg[axis] : fallback;
  };
  s.stage.mass_y_kg = p.body.mass_kg;
  s.stage.mass_x_kg = eff(0, p.body.mass_kg);
  s.stage.mass_z_kg = eff(1, p.body.mass_kg);
  s.stage.inertia_x_kg_m2 = eff(4, p.body.inertia_kgm2[0]);
  s.stage.inertia_z_kg_m2 = eff(5, p.body.inertia_kgm2[1]);
  s.stage.radius_to_movers_r_m = m.radius_to_movers_m;
  s.stage.guide_torsion_phi_per_s2 = m.guide_torsion_phi_per_s2;
  s.stage.guide_torsion_theta_per_s2 = m.guide_torsion_theta_per_s2;
  s.stage.gap_min_m = m.min_gap_m;
  s.stage.gap_max_m = m.max_gap_m;
  s.amplifier.phase_peak_A = p.limits.peak_current_A;
  s.amplifier.phase_continuous_A = p.limits.rms_current_A;
  const sp::Sensor* gap = DirectSensor(p, 3);
  const sp::Sensor* tilt = DirectSensor(p, 5);
  if (gap == nullptr || tilt == nullptr || !(gap->resolution > 0.0) || !(tilt->resolution > 0.0)) {
    *why = "needs encoders with `axis = z` (the gap) and `axis = theta_y` and a positive resolution";
    return false;
  }
  s.encoder.translation_resolution_m = gap->resolution;
  s.encoder.rotation_resolution_rad = tilt->resolution;
  if (!(m.min_gap_m > 0.0 && m.min_gap_m < m.nominal_gap_m && m.nominal_gap_m < m.max_gap_m)) {
    *why = "[pmlsm] needs 0 < min_gap_m < nominal_gap_m < max_gap_m";
    return false;
  }
  *out = s;
  return true;
}

bool BuildPmlsmKernelConfig(const sp::StageProfile& p, PmlsmDesign* out, std::string* why) {
  PmlsmStage st;
  if (!PmlsmStageFromProfile(p, &st, why)) return false;
  PmlsmDesign d;
  ps::PmlsmKernelConfig& c = d.config;
  std::memset(&c, 0, sizeof c);  // padding included: the replay compares bytes
  c.servo_rate_Hz = static_cast<float>(p.servo_rate_Hz);
  const double T = 1.0 / p.servo_rate_Hz;
  for (int a = 0; a < ps::kAxes; ++a) {
    const int pa = kProfileAxisOf[static_cast<std::size_t>(a)];
    const sp::Sensor* s = DirectSensor(p, pa);
    if (s == nullptr || !(s->resolution > 0.0)) {
      *why = std::string("no encoder reads axis ") + std::to_string(pa) + " (`[sensor N] axis = ...`)";
      return false;
    }
    c.encoder_resolution[a] = static_cast<float>(s->resolution);
  }
  // Force-law tables over every gap a motor can see: the stops' range
  // widened by the radius times the largest tilt the supervision window
  // allows (travel + 4 mrad, below), plus 0.5 mm.
  const pmlsm_plant::MotorParams& mp = st.stage.motor;
  const pmlsm_plant::ForceConstants k = pmlsm_plant::ComputeForceConstants(mp);
  double tilt_max = 0.0;
  for (int pa : {4, 5}) {
    tilt_max = std::max({tilt_max, std::abs(p.axis[pa].travel_min), std::abs(p.axis[pa].travel_max)});
  }
  const double margin = st.stage.radius_to_movers_r_m * (tilt_max + 4e-3) + 0.5e-3;
  const double g0 = p.pmlsm.min_gap_m - margin;
  const double step = (p.pmlsm.max_gap_m - p.pmlsm.min_gap_m + 2.0 * margin) / (ps::kGapTablePoints - 1);
  c.force.gap0_m = static_cast<float>(g0);
  c.force.step_m = static_cast<float>(step);
  for (int i = 0; i < ps::kGapTablePoints; ++i) {
    // The knots where the kernel will look: at its own float gap0 + i step.
    const double g = static_cast<double>(c.force.gap0_m) + i * static_cast<double>(c.force.step_m);
    c.force.attraction_N[i] = static_cast<float>(k.Kv1 * pmlsm_plant::Lv1(mp, g));
    c.force.direct_N_per_A[i] = static_cast<float>(k.Kv2 * pmlsm_plant::Lv2(mp, g));
    c.force.quadratic_N_per_A2[i] = static_cast<float>(k.Kv3 * pmlsm_plant::Lv3(mp, g));
    c.force.thrust_N_per_A[i] = static_cast<float>(k.Kh * pmlsm_plant::Lh(mp, g));
  }
  c.mass_gap_kg = static_cast<float>(st.stage.mass_y_kg);
  c.mass_x_kg = static_cast<float>(st.stage.mass_x_kg);
  c.mass_z_kg = static_cast<float>(st.stage.mass_z_kg);
  c.inertia_phi_kgm2 = static_cast<float>(st.stage.inertia_x_kg_m2);
  c.inertia_theta_kgm2 = static_cast<float>(st.stage.inertia_z_kg_m2);
  c.radius_m = static_cast<float>(st.stage.radius_to_movers_r_m);
  c.torsion_phi_per_s2 = static_cast<float>(st.stage.guide_torsion_phi_per_s2);
  c.torsion_theta_per_s2 = static_cast<float>(st.stage.guide_torsion_theta_per_s2);
  c.gravity_m_per_s2 = static_cast<float>(st.stage.gravity_G_m_per_s2);
  auto phase_per_count = [&](double res) {
    return static_cast<std::uint32_t>(std::llround(res / (2.0 * mp.pole_pitch_tau_m) * 4294967296.0));
  };
  c.phase_per_count_x = phase_per_count(c.encoder_resolution[1]);
  c.phase_per_count_z = phase_per_count(c.encoder_resolution[2]);
  // Internal models and gains.
  double omega0 = -1.0;
  for (int a = 0; a < ps::kAxes; ++a) {
    const sp::Axis& ax = p.axis[kProfileAxisOf[static_cast<std::size_t>(a)]];
    const sp::AxisController& ctl = ax.controller;
    if (ax.mode != sp::AxisMode::kActive) continue;
    if (ctl.kind != sp::ControllerKind::kInternalModel || !ctl.feedback_linearization) {
      *why = "every active axis of this family needs `controller = internal_model` and `feedback_linearization = on`";
      return false;
    }
    if (omega0 < 0.0) omega0 = ctl.imr_omega0_rad_per_s;
    if (ctl.imr_omega0_rad_per_s != omega0 || !(omega0 > 0.0)) {
      *why = "every axis needs the same imr_omega0_rad_per_s > 0 (one internal model, (14))";
      return false;
    }
  }
  if (omega0 <= 0.0) {
    *why = "no active axis";
    return false;
  }
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(3, 3);
  Phi(0, 1) = 1.0;
  Phi(1, 2) = 1.0;
  Phi(2, 1) = -omega0 * omega0;
  const Discrete xi = DiscretizeZoh(Phi, Eigen::MatrixXd::Identity(3, 3), T);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      c.xi_Ad_minus_I[i][j] = static_cast<float>(xi.Ad(i, j) - (i == j ? 1.0 : 0.0));
      c.xi_Bd[i][j] = static_cast<float>(xi.Bd(i, j));
    }
  }
  double filter_Hz = -1.0;
  for (int a = 0; a < ps::kAxes; ++a) {
    const sp::Axis& ax = p.axis[kProfileAxisOf[static_cast<std::size_t>(a)]];
    ps::RegulatorConfig& r = c.axis[a];
    const bool active = ax.mode == sp::AxisMode::kActive;
    r.closed = active;
    if (!active) continue;
    Eigen::RowVectorXd h(5);
    for (int i = 0; i < 5; ++i) h(i) = ax.controller.lqr_weight_h[i];
    if (h.norm() == 0.0) {
      *why = "an active axis needs lqr_weight_h";
      return false;
    }
    const AxisDesign ad = DesignAxisFromWeights(static_cast<Axis>(a), omega0, h.transpose() * h,
                                                Eigen::MatrixXd::Identity(1, 1));
    if (ad.error != DesignError::kOk) {
      *why = std::string("the Riccati equation has no stabilizing solution: ") + ToString(ad.error);
      return false;
    }
    for (int i = 0; i < 5; ++i) r.Ks[i] = static_cast<float>(ad.Ks[static_cast<std::size_t>(i)]);
    d.poles[static_cast<std::size_t>(a)] = ad.poles;
    const float e = static_cast<float>(ax.controller.antiwindup_gain);
    r.E[0] = r.E[1] = r.E[2] = e;
    if (filter_Hz < 0.0) filter_Hz = ax.controller.derivative_filter_Hz;
  }
  const double wf = 2.0 * kPi * filter_Hz;
  c.derivative_filter_rad_per_s = static_cast<float>(wf);
  c.derivative_filter_alpha = static_cast<float>(1.0 - std::exp(-wf * T));
  c.exact_vertical_inverse = false;
  c.horizontal_limit_A = static_cast<float>(p.limits.peak_current_A);
  c.phase_peak_A = static_cast<float>(p.limits.peak_current_A);
  c.amps_per_dac_code = static_cast<float>(p.limits.hardware_current_A / 32767.0);
  for (int a = 0; a < ps::kAxes; ++a) {
    const sp::Axis& ax = p.axis[kProfileAxisOf[static_cast<std::size_t>(a)]];
    c.reference_min[a] = static_cast<float>(ax.travel_min);
    c.reference_max[a] = static_cast<float>(ax.travel_max);
    c.max_ramp_speed[a] = static_cast<float>(ax.max_velocity);
    // Supervision window (ours): the gap inside the stops +-0.5 mm (the
    // guides cannot leave them: beyond is a sensor fault); X, Z 20 mm beyond
    // the operating range (the rig's stops sit at +-50 mm); tilts 4 mrad beyond.
    const bool rotation = a >= 3;
    const double widen = a == 0 ? 0.0 : (rotation ? 4e-3 : 20e-3);
    c.window_min[a] = static_cast<float>(a == 0 ? p.pmlsm.min_gap_m - 0.5e-3 : ax.travel_min - widen);
    c.window_max[a] = static_cast<float>(a == 0 ? p.pmlsm.max_gap_m + 0.5e-3 : ax.travel_max + widen);
    // Count-step plausibility (ours): 2 m/s or 2 rad/s, above anything the
    // motors' 7 A can do within one tick, far below a corrupted counter.
    c.max_speed[a] = 2.0f;
  }
  c.rest_gap_m = static_cast<float>(p.pmlsm.max_gap_m);
  c.nominal_gap_m = static_cast<float>(p.pmlsm.nominal_gap_m);
  c.lift_speed_m_per_s = static_cast<float>(p.limits.landing_speed_m_per_s);
  c.max_saturated_ticks = static_cast<std::uint32_t>(std::lround(p.servo_rate_Hz));  // 1 s in a row
  c.max_stale_ticks = 10;
  *out = d;
  return true;
}

}  // namespace maglev::control_design
