#include "maglev/control_design/paper002_sim.hpp"

#include <algorithm>
#include <cmath>

namespace maglev::control_design {

GapStepResult RunGapStep(const GapStepScenario& s, const Paper002ControllerConfig& cfg) {
  Paper002ControllerConfig c = cfg;
  c.rotation_loops_enabled = s.rotation_loops_enabled;
  Paper002Controller ctl(c);
  pmlsm_plant::Plant plant(c.model);
  pmlsm_plant::State x0{};
  x0[0] = s.gap_start_m;
  plant.Reset(x0);
  GapStepResult r;
  const double T = c.period_s;
  const int substeps = std::max(1, static_cast<int>(s.rk4_substeps));
  const auto hold = static_cast<long>(std::lround(s.hold_before_s / T));
  const auto after = static_cast<long>(std::lround(s.duration_after_s / T));
  ctl.SetReference({s.gap_start_m, 0, 0, 0, 0});
  const double target = s.gap_start_m + s.gap_step_m;
  double peak = 0.0;
  double last_above_ts = 0.0, last_above_enc = 0.0;
  for (long k = 0; k < hold + after; ++k) {
    if (k == hold) ctl.SetReference({target, 0, 0, 0, 0});
    std::array<double, 5> y{};
    if (s.quantize_encoders) {
      y = plant.Measure().y;
    } else {
      const auto& x = plant.state();
      y = {x[0], x[2], x[4], x[6], x[8]};
    }
    const pmlsm_plant::MotorCurrents cmd = ctl.Step(y);
    bool sat = false;
    for (int j = 0; j < substeps; ++j) {
      const auto delivered = plant.Step(cmd, T / substeps);
      sat = sat || plant.last_step_saturated();
      for (const auto& d : delivered) r.peak_direct_current_A = std::max(r.peak_direct_current_A, std::abs(d.d_A));
    }
    if (sat) ++r.saturated_ticks;
    const double gap = plant.state()[0];
    if (gap <= c.model.gap_min_m || gap >= c.model.gap_max_m) r.hit_stop = true;
    if (k >= hold) {
      const double t = static_cast<double>(k + 1 - hold) * T;
      const double e = std::abs(gap - target);
      peak = std::max(peak, (gap - target) / s.gap_step_m);
      if (e >= 0.1e-3) last_above_ts = t;
      if (e >= 10e-6) last_above_enc = t;
      r.final_error_m = e;
    }
  }
  r.overshoot_fraction = std::max(0.0, peak);
  r.settling_time_s = last_above_ts;
  r.encoder_time_s = last_above_enc;
  return r;
}

}  // namespace maglev::control_design
