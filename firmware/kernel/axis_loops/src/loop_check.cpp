#include "maglev/io/code_placement.hpp"
#include "maglev/axis_loops/loop_check.hpp"

#include <cmath>
#include "maglev/numeric/elementary.hpp"

namespace maglev::kernel {

MAGLEV_CONFIG_CODE LoopMargins Pid2DofLoopMargins(const Pid2DofConfig& pid, const LoopPlant& plant, double servo_rate_Hz,
                               const BiquadConfig* filters, int filter_count) {
  constexpr double kPi = 3.14159265358979323846;
  LoopMargins m;
  BiquadDesign stage[kMaxBiquadStages];
  int stages = 0;
  for (int k = 0; filters != nullptr && k < filter_count && k < kMaxBiquadStages; ++k) {
    if (filters[k].type == BiquadType::kNone) continue;
    if (design_biquad_double(filters[k], servo_rate_Hz, &stage[stages]) != LoopDesignError::kOk) return m;
    ++stages;
  }
  const double kp = static_cast<double>(pid.kp), ki = static_cast<double>(pid.ki), kd = static_cast<double>(pid.kd);
  const double wf = 2.0 * kPi * static_cast<double>(pid.derivative_filter_hz);
  const double T = 1.0 / servo_rate_Hz;
  // |L(jw)| and arg L(jw) without complex types (target-friendly).
  auto loop = [&](double w, double* mag, double* phase) {
    const double den = 1.0 + (w / wf) * (w / wf);
    const double d_re = kd * w * (w / wf) / den, d_im = kd * w / den;
    const double c_re = kp + d_re, c_im = -ki / w + d_im;
    const double p_re = plant.stiffness_per_s2 - w * w, p_im = plant.damping_per_s * w;
    *mag = std::sqrt(c_re * c_re + c_im * c_im) * plant.gain / std::sqrt(p_re * p_re + p_im * p_im);
    *phase = numeric::datan2(c_im, c_re) - numeric::datan2(p_im, p_re) - 0.5 * T * w;
    // Each filter stage: (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2) at z = e^{jwT}.
    const double c1 = numeric::dcos(w * T), s1 = numeric::dsin(w * T), c2 = numeric::dcos(2.0 * w * T), s2 = numeric::dsin(2.0 * w * T);
    for (int k = 0; k < stages; ++k) {
      const BiquadDesign& d = stage[k];
      const double n_re = d.b0 + d.b1 * c1 + d.b2 * c2, n_im = -(d.b1 * s1 + d.b2 * s2);
      const double q_re = 1.0 + d.a1 * c1 + d.a2 * c2, q_im = -(d.a1 * s1 + d.a2 * s2);
      *mag *= std::sqrt(n_re * n_re + n_im * n_im) / std::sqrt(q_re * q_re + q_im * q_im);
      *phase += numeric::datan2(n_im, n_re) - numeric::datan2(q_im, q_re);
    }
  };
  const double f_lo = 0.1, f_hi = 0.5 * servo_rate_Hz;
  constexpr int kSteps = 1000;
  const double ratio = numeric::dpow(f_hi / f_lo, 1.0 / kSteps);
  double prev_mag = 0.0, prev_f = f_lo, f = f_lo;
  for (int i = 0; i <= kSteps; ++i, f *= ratio) {
    double mag = 0.0, ph = 0.0;
    loop(2.0 * kPi * f, &mag, &ph);
    if (i > 0 && prev_mag >= 1.0 && mag < 1.0) {
      // Log-linear interpolation between the two samples.
      const double t = numeric::dlog(prev_mag) / (numeric::dlog(prev_mag) - numeric::dlog(mag));
      const double fc = prev_f * numeric::dpow(f / prev_f, t);
      double mc = 0.0, pc = 0.0;
      loop(2.0 * kPi * fc, &mc, &pc);
      double deg = pc * 180.0 / kPi;  // unwrapped into (-360, 0]
      while (deg > 0.0) deg -= 360.0;
      while (deg <= -360.0) deg += 360.0;
      m.crossover_found = true;
      m.crossover_Hz = fc;
      m.phase_margin_deg = 180.0 + deg;
      m.delay_margin_ticks = m.phase_margin_deg / (360.0 * fc) * servo_rate_Hz;
    }
    prev_mag = mag;
    prev_f = f;
  }
  return m;
}

}  // namespace maglev::kernel
