#include "maglev/control_design/paper002_sim.hpp"

#include <algorithm>
#include <cmath>

namespace maglev::control_design {

GapStepResult RunGapStep(const GapStepScenario& s, const Paper002ControllerConfig& cfg) {
  AxisStepScenario a;
  a.axis = Axis::kY;
  a.start = {s.gap_start_m, 0, 0, 0, 0};
  a.step = s.gap_step_m;
  a.hold_before_s = s.hold_before_s;
  a.duration_after_s = s.duration_after_s;
  a.rotation_loops_enabled = s.rotation_loops_enabled;
  a.quantize_encoders = s.quantize_encoders;
  return RunAxisStep(a, cfg);
}

GapStepResult RunAxisStep(const AxisStepScenario& s, const Paper002ControllerConfig& cfg) {
  Paper002ControllerConfig c = cfg;
  c.rotation_loops_enabled = s.rotation_loops_enabled;
  Paper002Controller ctl(c);
  pmlsm_plant::Plant plant(c.model);
  const auto ax = static_cast<std::size_t>(s.axis);
  // Plant state index of each output y[a] (Table II).
  constexpr std::array<std::size_t, 5> kStateOf{0, 2, 4, 6, 8};
  pmlsm_plant::State x0{};
  for (std::size_t a = 0; a < 5; ++a) x0[kStateOf[a]] = s.start[a];
  plant.Reset(x0);
  const bool rotation = s.axis == Axis::kPhi || s.axis == Axis::kTheta;
  const double settle_band = 0.1e-3;  // 0.1 mm, or 0.1 mrad on a rotation
  const double encoder_band = rotation ? 20e-6 : 10e-6;
  GapStepResult r;
  const double T = c.period_s;
  const auto hold = static_cast<long>(std::lround(s.hold_before_s / T));
  const auto after = static_cast<long>(std::lround(s.duration_after_s / T));
  ctl.SetReference(s.start);
  std::array<double, 5> target_ref = s.start;
  target_ref[ax] += s.step;
  const double target = target_ref[ax];
  double peak = 0.0;
  double last_above_ts = 0.0, last_above_enc = 0.0;
  for (long k = 0; k < hold + after; ++k) {
    if (k == hold) ctl.SetReference(target_ref);
    std::array<double, 5> y{};
    if (s.quantize_encoders) {
      y = plant.Measure().y;
    } else {
      const auto& x = plant.state();
      for (std::size_t a = 0; a < 5; ++a) y[a] = x[kStateOf[a]];
    }
    const pmlsm_plant::MotorCurrents cmd = ctl.Step(y);
    const auto delivered = plant.Step(cmd, T);
    if (plant.last_step_saturated()) ++r.saturated_ticks;
    for (const auto& d : delivered) r.peak_direct_current_A = std::max(r.peak_direct_current_A, std::abs(d.d_A));
    const double gap = plant.state()[0];
    if (gap <= c.model.gap_min_m || gap >= c.model.gap_max_m) r.hit_stop = true;
    if (k >= hold) {
      const double t = static_cast<double>(k + 1 - hold) * T;
      const double v = plant.state()[kStateOf[ax]];
      const double e = std::abs(v - target);
      peak = std::max(peak, (v - target) / s.step);
      if (e >= settle_band) last_above_ts = t;
      if (e >= encoder_band) last_above_enc = t;
      r.final_error_m = e;
    }
  }
  r.overshoot_fraction = std::max(0.0, peak);
  r.settling_time_s = last_above_ts;
  r.encoder_time_s = last_above_enc;
  return r;
}

TrackingResult RunTracking(const TrackingScenario& s, const Paper002ControllerConfig& cfg) {
  Paper002ControllerConfig c = cfg;
  c.rotation_loops_enabled = s.four_dof;
  Paper002Controller ctl(c);
  pmlsm_plant::Plant plant(c.model);
  const double w = c.omega0_rad_per_s;
  const double half_pi = 1.5707963267948966;
  auto ref = [&](double t) {
    return std::array<double, 5>{5e-3 * std::sin(w * t - half_pi) + 25e-3, 30e-3 * std::sin(w * t - half_pi),
                                 30e-3 * std::sin(w * t), 0.0, s.four_dof ? 10e-3 * std::sin(w * t) : 0.0};
  };
  constexpr std::array<std::size_t, 5> kStateOf{0, 2, 4, 6, 8};
  pmlsm_plant::State x0{};
  const auto r0 = ref(0.0);
  for (std::size_t a = 0; a < 5; ++a) x0[kStateOf[a]] = r0[a];
  plant.Reset(x0);
  TrackingResult out;
  const double T = c.period_s;
  const auto settle = static_cast<long>(std::lround(s.settle_s / T));
  const auto total = settle + static_cast<long>(std::lround(s.measure_s / T));
  for (long k = 0; k < total; ++k) {
    const double t = static_cast<double>(k) * T;
    ctl.SetReference(ref(t));
    std::array<double, 5> y{};
    if (s.quantize_encoders) {
      y = plant.Measure().y;
    } else {
      for (std::size_t a = 0; a < 5; ++a) y[a] = plant.state()[kStateOf[a]];
    }
    plant.Step(ctl.Step(y), T);
    const double gap = plant.state()[0];
    if (gap <= c.model.gap_min_m || gap >= c.model.gap_max_m) out.hit_stop = true;
    if (k >= settle) {
      const auto r = ref(t + T);  // state after the step is at t + T
      for (std::size_t a = 0; a < 5; ++a) out.mean_abs_error[a] += std::abs(plant.state()[kStateOf[a]] - r[a]);
    }
  }
  for (double& e : out.mean_abs_error) e /= static_cast<double>(total - settle);
  return out;
}

}  // namespace maglev::control_design
