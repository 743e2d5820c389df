#include "maglev/metrics/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace maglev::metrics {

double mean(std::span<const double> v) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double rms_about(std::span<const double> v, double reference) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (double x : v) s += (x - reference) * (x - reference);
  return std::sqrt(s / static_cast<double>(v.size()));
}

double rms_about_mean(std::span<const double> v) { return rms_about(v, mean(v)); }

std::vector<double> moving_average(std::span<const double> v, std::size_t n) {
  std::vector<double> out;
  if (n == 0 || v.size() < n) return out;
  out.reserve(v.size() - n + 1);
  double sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) sum += v[i];
  out.push_back(sum / static_cast<double>(n));
  for (std::size_t i = n; i < v.size(); ++i) {
    sum += v[i] - v[i - n];
    out.push_back(sum / static_cast<double>(n));
  }
  return out;
}

double peak_to_peak(std::span<const double> v) {
  if (v.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

double max_abs(std::span<const double> v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

Window window(std::span<const double> t_s, double t_begin_s, double t_end_s) {
  const auto first = std::lower_bound(t_s.begin(), t_s.end(), t_begin_s);
  const auto last = std::lower_bound(first, t_s.end(), t_end_s);
  return {static_cast<std::size_t>(first - t_s.begin()), static_cast<std::size_t>(last - t_s.begin())};
}

std::span<const double> slice(std::span<const double> v, Window w) {
  return v.subspan(w.first, w.last - w.first);
}

StepMetrics analyze_step(std::span<const double> t_s, std::span<const double> y,
                         double t_step_s, double t_end_s, double target,
                         double pre_window_s, double band_fraction) {
  StepMetrics m{};
  const Window pre = window(t_s, t_step_s - pre_window_s, t_step_s);
  const Window post = window(t_s, t_step_s, t_end_s);
  m.initial_value = pre.size() > 0 ? mean(slice(y, pre)) : (post.size() > 0 ? y[post.first] : 0.0);
  m.step_size = target - m.initial_value;
  if (post.size() < 2 || m.step_size == 0.0) return m;

  const std::size_t tail = std::max<std::size_t>(1, post.size() / 10);
  m.final_value = mean(y.subspan(post.last - tail, tail));

  // Work in the normalized direction of the step: 0 = initial, 1 = target.
  const double dir = m.step_size > 0 ? 1.0 : -1.0;
  const double mag = std::abs(m.step_size);
  auto progress = [&](std::size_t i) { return dir * (y[i] - m.initial_value) / mag; };
  const double final_progress = dir * (m.final_value - m.initial_value) / mag;

  // Rise time 10% -> 90% of the commanded step: first crossings.
  double t10 = -1.0, t90 = -1.0;
  for (std::size_t i = post.first; i < post.last; ++i) {
    const double p = progress(i);
    if (t10 < 0 && p >= 0.1) t10 = t_s[i];
    if (t90 < 0 && p >= 0.9) { t90 = t_s[i]; break; }
  }
  m.rise_found = t10 >= 0 && t90 >= 0;
  m.rise_time_s = m.rise_found ? t90 - t10 : 0.0;

  // Overshoot: largest excursion beyond the final value, in % of the step.
  std::size_t i_peak = post.first;
  double p_peak = -1e300;
  for (std::size_t i = post.first; i < post.last; ++i) {
    if (progress(i) > p_peak) { p_peak = progress(i); i_peak = i; }
  }
  m.overshoot_percent = std::max(0.0, (p_peak - final_progress) * 100.0);

  // 2% settling (band_fraction): after the last sample outside the band.
  const double band = band_fraction;
  std::size_t last_out = post.first;
  bool any_out = false;
  for (std::size_t i = post.first; i < post.last; ++i) {
    if (std::abs(progress(i) - final_progress) > band) { last_out = i; any_out = true; }
  }
  m.settled = !any_out || last_out + 1 < post.last;
  m.settling_time_s = any_out ? (last_out + 1 < post.last ? t_s[last_out + 1] : t_s[post.last - 1]) - t_step_s : 0.0;

  // Peak time: time of the overshoot peak when the response overshoots by more
  // than the 2% band's quarter (0.5% of the step: above interferometer noise);
  // a response that does not overshoot (shaped moves, paper 003 Figs 17, 20)
  // has its "peak" where it first reaches the 2% band around its final value.
  // An "overshoot" no larger than the rest noise (6 x its rms before the
  // step) is a noise maximum, not a peak: its time would be random (a 2 um
  // step with 3 nm rms noise peaked anywhere in the window).
  const double pre_rms = pre.size() > 2 ? rms_about_mean(slice(y, pre)) : 0.0;
  const bool above_noise = (p_peak - final_progress) * mag > 6.0 * pre_rms;
  if (m.overshoot_percent > 0.5 && above_noise) {
    m.peak_time_s = t_s[i_peak] - t_step_s;
  } else {
    m.peak_time_s = m.settling_time_s;
    for (std::size_t i = post.first; i < post.last; ++i) {
      if (std::abs(progress(i) - final_progress) <= band) { m.peak_time_s = t_s[i] - t_step_s; break; }
    }
  }
  return m;
}

AveragedStep average_steps(std::span<const double> t_s, std::span<const double> y,
                           std::span<const double> step_times_s, std::span<const double> signs,
                           double pre_s, double post_s) {
  AveragedStep a;
  if (t_s.size() < 2 || step_times_s.size() != signs.size()) return a;
  const double dt = (t_s.back() - t_s.front()) / static_cast<double>(t_s.size() - 1);
  const auto n_pre = static_cast<std::size_t>(std::lround(pre_s / dt));
  const auto n_post = static_cast<std::size_t>(std::lround(post_s / dt));
  if (n_pre == 0 || n_post < 5) return a;
  std::vector<double> sum(n_pre + n_post, 0.0);
  const std::size_t tail = std::max<std::size_t>(1, n_post / 5);
  for (std::size_t k = 0; k < step_times_s.size(); ++k) {
    const auto i0 = static_cast<std::size_t>(std::lower_bound(t_s.begin(), t_s.end(), step_times_s[k]) - t_s.begin());
    if (i0 < n_pre || i0 + n_post > t_s.size()) continue;
    const double level = mean(y.subspan(i0 - n_pre, n_pre));
    for (std::size_t j = 0; j < n_pre + n_post; ++j) sum[j] += signs[k] * (y[i0 - n_pre + j] - level);
    a.measured.push_back(signs[k] * (mean(y.subspan(i0 + n_post - tail, tail)) - level));
    ++a.count;
  }
  if (a.count == 0) return a;
  a.t_s.resize(sum.size());
  a.y.resize(sum.size());
  for (std::size_t j = 0; j < sum.size(); ++j) {
    a.t_s[j] = (static_cast<double>(j) - static_cast<double>(n_pre)) * dt;
    a.y[j] = sum[j] / static_cast<double>(a.count);
  }
  return a;
}

std::string ccq_unit(AxisKind primary, AxisKind perturbed) {
  if (primary == AxisKind::kTranslational && perturbed == AxisKind::kTranslational) return "s";
  if (primary == AxisKind::kTranslational && perturbed == AxisKind::kRotational) return "rad*s/m";
  if (primary == AxisKind::kRotational && perturbed == AxisKind::kTranslational) return "m*s/rad";
  return "s";
}

Ccq cross_coupling_quantity(double peak_time_s, double perturbed_peak_to_peak,
                            double primary_displacement, AxisKind primary,
                            AxisKind perturbed) {
  const double d = std::abs(primary_displacement);
  return {d > 0 ? peak_time_s * perturbed_peak_to_peak / d : 0.0, ccq_unit(primary, perturbed)};
}

std::vector<std::complex<double>> frequency_response(std::span<const double> input,
                                                     std::span<const double> output,
                                                     double fs_Hz,
                                                     std::span<const double> freqs_Hz) {
  std::vector<std::complex<double>> h;
  h.reserve(freqs_Hz.size());
  const std::size_t n_all = std::min(input.size(), output.size());
  for (double f : freqs_Hz) {
    // Largest whole number of periods of f in the record (correlation over
    // whole periods makes the sin/cos basis orthogonal to DC and to f).
    const double samples_per_period = fs_Hz / f;
    const auto periods = static_cast<std::size_t>(std::floor(static_cast<double>(n_all) / samples_per_period));
    const auto n = static_cast<std::size_t>(std::llround(static_cast<double>(periods) * samples_per_period));
    const std::size_t start = n_all - std::min(n, n_all);  // use the END of the record: transients decayed
    std::complex<double> x{0, 0}, yv{0, 0};
    for (std::size_t i = start; i < n_all; ++i) {
      const double ph = 2.0 * std::numbers::pi * f * static_cast<double>(i) / fs_Hz;
      const std::complex<double> e{std::cos(ph), -std::sin(ph)};
      x += input[i] * e;
      yv += output[i] * e;
    }
    h.push_back(std::abs(x) > 0 ? yv / x : std::complex<double>{0, 0});
  }
  return h;
}

std::vector<FrfPoint> frequency_response_segments(std::span<const double> input, std::span<const double> output,
                                                  double fs_Hz, std::span<const double> freqs_Hz,
                                                  std::size_t segment) {
  std::vector<FrfPoint> out;
  out.reserve(freqs_Hz.size());
  const std::size_t n_all = std::min(input.size(), output.size());
  const std::size_t segments = segment == 0 ? 0 : n_all / segment;
  for (double f : freqs_Hz) {
    std::complex<double> sxy{0, 0};
    double sxx = 0.0, syy = 0.0;
    for (std::size_t s = 0; s < segments; ++s) {
      std::complex<double> x{0, 0}, y{0, 0};
      for (std::size_t i = 0; i < segment; ++i) {
        const std::size_t k = s * segment + i;
        const double ph = 2.0 * std::numbers::pi * f * static_cast<double>(i) / fs_Hz;
        const std::complex<double> e{std::cos(ph), -std::sin(ph)};
        x += input[k] * e;
        y += output[k] * e;
      }
      sxy += y * std::conj(x);
      sxx += std::norm(x);
      syy += std::norm(y);
    }
    FrfPoint p{};
    p.h = sxx > 0 ? sxy / sxx : std::complex<double>{0, 0};
    p.coherence = sxx > 0 && syy > 0 ? std::norm(sxy) / (sxx * syy) : 0.0;
    out.push_back(p);
  }
  return out;
}

LoopMargins loop_margins(std::span<const double> f, std::span<const std::complex<double>> L) {
  LoopMargins m{};
  const std::size_t n = std::min(f.size(), L.size());
  // Crossover: first k with |L_k| >= 1 > |L_k+1|; interpolate log|L| vs log f.
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double a0 = std::abs(L[k]), a1 = std::abs(L[k + 1]);
    if (a0 >= 1.0 && a1 < 1.0) {
      const double s = std::log(a0) / (std::log(a0) - std::log(a1));
      m.crossover_Hz = std::exp(std::log(f[k]) + s * (std::log(f[k + 1]) - std::log(f[k])));
      // Phase: interpolate the unwrapped difference between neighbours.
      const double p0 = std::arg(L[k]);
      double p1 = std::arg(L[k + 1]);
      while (p1 - p0 > std::numbers::pi) p1 -= 2 * std::numbers::pi;
      while (p1 - p0 < -std::numbers::pi) p1 += 2 * std::numbers::pi;
      double ph = p0 + s * (p1 - p0);
      while (ph > 0) ph -= 2 * std::numbers::pi;
      while (ph <= -2 * std::numbers::pi) ph += 2 * std::numbers::pi;
      m.phase_margin_deg = 180.0 + ph * 180.0 / std::numbers::pi;
      m.crossover_found = true;
      break;
    }
  }
  // Closed loop T = L / (1 + L).
  double peak = -1e300;
  for (std::size_t k = 0; k < n; ++k) {
    const double t_db = 20.0 * std::log10(std::abs(L[k] / (1.0 + L[k])));
    if (t_db > peak) { peak = t_db; m.closed_loop_peak_Hz = f[k]; }
  }
  m.closed_loop_peak_dB = n > 0 ? peak : 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double t0 = 20.0 * std::log10(std::abs(L[k] / (1.0 + L[k])));
    const double t1 = 20.0 * std::log10(std::abs(L[k + 1] / (1.0 + L[k + 1])));
    if (t0 >= -3.0 && t1 < -3.0) {
      const double s = (t0 + 3.0) / (t0 - t1);
      m.closed_loop_bandwidth_Hz = std::exp(std::log(f[k]) + s * (std::log(f[k + 1]) - std::log(f[k])));
      m.bandwidth_found = true;
      break;
    }
  }
  // Phase crossover: where the unwrapped phase of L (starting in (-360, 0])
  // crosses -180 deg, either way (a conditionally stable loop, e.g. PID on a
  // double integrator, starts below -180 and crosses upwards at low
  // frequency); log-interpolated in f, |L| in dB. The crossing nearest the
  // gain crossover (in log f) is reported; gain margin = -|L| there in dB
  // (negative: the gain may only be LOWERED by that much, a lower margin).
  double prev = 0.0;
  double best = 1e300;
  for (std::size_t k = 0; k < n; ++k) {
    double ph = std::arg(L[k]);
    if (k == 0) {
      while (ph > 0) ph -= 2 * std::numbers::pi;
      while (ph <= -2 * std::numbers::pi) ph += 2 * std::numbers::pi;
    } else {
      while (ph - prev > std::numbers::pi) ph -= 2 * std::numbers::pi;
      while (ph - prev < -std::numbers::pi) ph += 2 * std::numbers::pi;
      const double a = prev + std::numbers::pi, b = ph + std::numbers::pi;  // relative to -180 deg
      if ((a > 0 && b <= 0) || (a <= 0 && b > 0)) {
        const double s = a / (a - b);
        const double fp = std::exp(std::log(f[k - 1]) + s * (std::log(f[k]) - std::log(f[k - 1])));
        const double g0 = 20.0 * std::log10(std::abs(L[k - 1])), g1 = 20.0 * std::log10(std::abs(L[k]));
        const double distance = m.crossover_found ? std::abs(std::log(fp / m.crossover_Hz)) : fp;
        if (distance < best) {
          best = distance;
          m.phase_crossover_Hz = fp;
          m.gain_margin_dB = -(g0 + s * (g1 - g0));
          m.gain_margin_found = true;
        }
      }
    }
    prev = ph;
  }
  return m;
}

}  // namespace maglev::metrics
