#include "maglev/bench/metrics_registry.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <span>

#include "maglev/bench/runner.hpp"
#include "maglev/bench/units.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/metrics/metrics.hpp"

namespace maglev::bench {

namespace {

using Results = std::map<std::string, double>;

// What every metric function gets: the inputs, the window of its spec, and
// the rest window (from Ready + 0.5 s to the first point-to-point motion),
// the CCQ's noise reference.
struct Context {
  const MetricInputs& in;
  std::span<const double> t;
  double rest_begin = 0.0;
  double rest_end = 0.0;
  std::size_t in_band_average_ticks = 0;  // 10 ms boxcar: 50 Hz noise bandwidth
  Results& M;
  std::vector<std::string>& warnings;
};

const std::vector<double>& pose(const Context& c, Axis a) { return c.in.trace.pose[index(a)]; }
const std::vector<double>& reference(const Context& c, Axis a) { return c.in.trace.reference[index(a)]; }

void noise(const MetricSpec& s, const metrics::Window& w, Context& c) {
  const std::string u = si_unit(s.axis);
  const auto y = metrics::slice(pose(c, s.axis), w);
  c.M[s.name + "_rms_noise_" + u] = metrics::rms_about_mean(y);
  c.M[s.name + "_pp_noise_" + u] = metrics::peak_to_peak(y);
  const std::vector<double> ya = metrics::moving_average(y, c.in_band_average_ticks);
  if (ya.size() > 2) c.M[s.name + "_rms_noise_50Hz_" + u] = metrics::rms_about_mean(ya);
}

// The step (or move) is the first point-to-point command on this axis inside the window.
const TimelineAction* command_of(const MetricSpec& s, const Context& c) {
  for (const auto& a : c.in.actions) {
    if (a.axis == s.axis && a.t_s >= s.t0 && a.t_s < s.t1 && a.is_point_to_point()) return &a;
  }
  return nullptr;
}
double command_time(const MetricSpec& s, const Context& c) {
  const TimelineAction* a = command_of(s, c);
  return a != nullptr ? a->t_s : s.t0;
}

const char* ccq_suffix(const std::string& unit) {
  if (unit == "s") return "s";
  if (unit == "rad*s/m") return "rad_s_per_m";
  if (unit == "m*s/rad") return "m_s_per_rad";
  return "si";
}

void step_or_ccq(const MetricSpec& s, const metrics::Window&, Context& c) {
  const double fs = c.in.servo_rate_Hz;
  const std::string u = si_unit(s.axis);
  // A refused command moved nothing: whatever the window holds is noise (or
  // a stage that never lifted), not this metric.
  if (const TimelineAction* a = command_of(s, c); a != nullptr && a->refused) {
    c.warnings.push_back("metric " + s.name + ": not measured, its command at t = " + std::to_string(a->t_s) +
                         " s ('" + a->text + "') was refused");
    return;
  }
  const double t_cmd = command_time(s, c);
  const metrics::Window wend = metrics::window(c.t, s.t1 - 1.0 / fs, s.t1 + 1.0 / fs);
  const metrics::Window wpre = metrics::window(c.t, t_cmd - 2.0 / fs, t_cmd);
  if (wend.size() == 0 || wpre.size() == 0) return;
  const double target = reference(c, s.axis)[wend.first];
  const double initial_ref = reference(c, s.axis)[wpre.first];
  const double pre = std::min(0.05, t_cmd - s.t0 > 0 ? t_cmd - s.t0 : 0.05);
  const metrics::StepMetrics sm = metrics::analyze_step(c.t, pose(c, s.axis), t_cmd, s.t1, target, pre);
  const double size = target - initial_ref;
  auto& M = c.M;
  // step_resolution: a step within a few rms of the noise (10 nm, paper 000
  // Fig. 7(a)): only what one such step shows -- it is resolved (measured
  // size, step over noise). Its overshoot and settling are the noise's; the
  // step_avg metric reports those from averaged steps.
  if (s.kind == "step" || s.kind == "step_resolution") {
    if (s.kind == "step") {
      M[s.name + "_overshoot_percent"] = sm.overshoot_percent;
      M[s.name + "_rise_time_s"] = sm.rise_time_s;
      M[s.name + "_peak_time_s"] = sm.peak_time_s;
      M[s.name + "_settling_time_s"] = sm.settled ? sm.settling_time_s : s.t1 - t_cmd;
      M[s.name + "_settled"] = sm.settled ? 1.0 : 0.0;
    }
    M[s.name + "_commanded_" + u] = size;
    M[s.name + "_measured_" + u] = sm.final_value - sm.initial_value;
    // Resolution: the measured step over the rms noise in the 0.2 s before it,
    // and over the in-band (10 ms averaged, 50 Hz) noise.
    const auto pre_noise = metrics::slice(pose(c, s.axis), metrics::window(c.t, t_cmd - 0.2, t_cmd));
    const double n = pre_noise.size() > 2 ? metrics::rms_about_mean(pre_noise) : 0.0;
    const double step = std::fabs(sm.final_value - sm.initial_value);
    M[s.name + "_step_to_rms_noise_ratio"] = n > 0 ? step / n : 0.0;
    const std::vector<double> pa = metrics::moving_average(pre_noise, c.in_band_average_ticks);
    const double na = pa.size() > 2 ? metrics::rms_about_mean(pa) : 0.0;
    M[s.name + "_step_to_rms_noise_50Hz_ratio"] = na > 0 ? step / na : 0.0;
    return;
  }
  // ccq: paper 003 Sec. 3.3, against every other axis.
  const double tp = sm.peak_time_s > 0 ? sm.peak_time_s : s.t1 - t_cmd;
  M[s.name + "_peak_time_s"] = tp;
  M[s.name + "_primary_" + u] = size;
  const auto kind = [](Axis a) { return is_rotation(a) ? metrics::AxisKind::kRotational : metrics::AxisKind::kTranslational; };
  // One perturbed series: its p-p over the motion and its CCQ, and the same
  // from the REST p-p over an equally long window before the first motion
  // (a CCQ close to that is noise, not coupling). `label` names it in the
  // keys: the axis, or z_sensor_mean below.
  const auto perturbed = [&](const std::string& label, const char* unit, const std::vector<double>& y,
                             metrics::AxisKind perturbed_kind) {
    const double pp = metrics::peak_to_peak(metrics::slice(y, metrics::window(c.t, t_cmd, s.t1)));
    const metrics::Ccq cq = metrics::cross_coupling_quantity(tp, pp, size, kind(s.axis), perturbed_kind);
    const std::string suffix = ccq_suffix(cq.unit);
    M[s.name + "_pp_" + label + "_" + unit] = pp;
    M[s.name + "_ccq_" + label + "_" + suffix] = cq.value;
    if (c.rest_end > c.rest_begin) {
      const double len = std::min(s.t1 - t_cmd, c.rest_end - c.rest_begin);
      const auto rq = metrics::slice(y, metrics::window(c.t, c.rest_end - len, c.rest_end));
      if (rq.size() > 2) {
        const double rpp = metrics::peak_to_peak(rq);
        M[s.name + "_rest_pp_" + label + "_" + unit] = rpp;
        M[s.name + "_ccq_rest_noise_" + label + "_" + suffix] =
            metrics::cross_coupling_quantity(tp, rpp, size, kind(s.axis), perturbed_kind).value;
      }
    }
  };
  // z as the mean of the three height sensors (MetricInputs::
  // height_sensor_centroid_m): the measured plane's z at their centroid. A
  // controller that averages its height sensors reports this as z, and a
  // tilt then reads as z: (x_c, y_c) = (-20.5, 20.5) mm on the seed stage.
  const double xc = c.in.height_sensor_centroid_m[0], yc = c.in.height_sensor_centroid_m[1];
  if (s.axis != Axis::kZ && std::isfinite(xc) && std::isfinite(yc)) {
    const std::vector<double>& z = pose(c, Axis::kZ);
    const std::vector<double>& tx = pose(c, Axis::kThetaX);
    const std::vector<double>& ty = pose(c, Axis::kThetaY);
    std::vector<double> zm(z.size());
    for (std::size_t i = 0; i < z.size(); ++i) zm[i] = z[i] + yc * tx[i] - xc * ty[i];
    perturbed(kZSensorMeanLabel, "m", zm, metrics::AxisKind::kTranslational);
  }
  for (Axis q : kDisplayOrder) {
    if (q != s.axis) perturbed(axis_name(q), si_unit(q), pose(c, q), kind(q));
  }
}

// step_avg: every `step` command on the axis inside the window, averaged
// (metrics::average_steps: each response in its step's direction, from its
// own pre-step level, up to the next command), then the classical step
// figures of the average. The settling band is 2% of the step, or 3x the
// rms noise left in the average before the step when that is wider (2% of
// 10 nm is 0.2 nm: below what any average of a few tens of steps resolves);
// the band used is reported.
void step_avg(const MetricSpec& s, const metrics::Window&, Context& c) {
  const std::string u = si_unit(s.axis);
  std::vector<double> times, signs;
  double size_sum = 0.0;
  for (const auto& a : c.in.actions) {
    if (a.axis != s.axis || a.t_s < s.t0 || a.t_s >= s.t1 || !a.is(can::HostCommandCode::kStep)) continue;
    const double delta = a.command.args.step.delta;
    if (delta == 0.0) continue;
    times.push_back(a.t_s);
    signs.push_back(delta > 0 ? 1.0 : -1.0);
    size_sum += std::fabs(delta);
  }
  if (times.size() < 2) {
    c.warnings.push_back("metric '" + s.name + "': step_avg needs at least two steps on the axis in its window");
    return;
  }
  // Each response runs to the next command (the shortest gap), the last to t1.
  double post = s.t1 - times.back();
  for (std::size_t k = 1; k < times.size(); ++k) post = std::min(post, times[k] - times[k - 1]);
  const double pre = std::min(0.05, post / 2);
  const metrics::AveragedStep a = metrics::average_steps(c.t, pose(c, s.axis), times, signs, pre, post - pre);
  if (a.count < 2) {
    c.warnings.push_back("metric '" + s.name + "': fewer than two steps inside the trace");
    return;
  }
  const double size = size_sum / static_cast<double>(times.size());
  const auto n_pre = static_cast<std::size_t>(std::lower_bound(a.t_s.begin(), a.t_s.end(), 0.0) - a.t_s.begin());
  const double residual = metrics::rms_about_mean(std::span<const double>(a.y).first(n_pre));
  const double band = std::max(0.02, 3.0 * residual / size);
  const metrics::StepMetrics sm = metrics::analyze_step(a.t_s, a.y, 0.0, a.t_s.back() + 1e-9, size, pre, band);
  double spread = 0.0;
  const double measured_mean = metrics::mean(a.measured);
  for (double m : a.measured) spread += (m - measured_mean) * (m - measured_mean);
  spread = std::sqrt(spread / static_cast<double>(a.measured.size() - 1));
  auto& M = c.M;
  M[s.name + "_count"] = static_cast<double>(a.count);
  M[s.name + "_commanded_" + u] = size;
  M[s.name + "_measured_" + u] = sm.final_value - sm.initial_value;
  M[s.name + "_measured_spread_" + u] = spread;  // one step's plateau, 1 sigma over the steps
  M[s.name + "_residual_rms_noise_" + u] = residual;
  M[s.name + "_overshoot_percent"] = sm.overshoot_percent;
  // An overshoot below this is within the average's own noise (3 x its rms).
  M[s.name + "_noise_floor_percent"] = 300.0 * residual / size;
  M[s.name + "_rise_time_s"] = sm.rise_time_s;
  M[s.name + "_peak_time_s"] = sm.peak_time_s;
  M[s.name + "_settling_band_" + u] = band * size;
  M[s.name + "_settling_time_s"] = sm.settled ? sm.settling_time_s : post - pre;
  M[s.name + "_settled"] = sm.settled ? 1.0 : 0.0;
}

void tracking(const MetricSpec& s, const metrics::Window& w, Context& c) {
  const std::string u = si_unit(s.axis);
  std::vector<double> e;
  e.reserve(w.size());
  for (std::size_t i = w.first; i < w.last; ++i) e.push_back(reference(c, s.axis)[i] - pose(c, s.axis)[i]);
  c.M[s.name + "_rms_tracking_error_" + u] = metrics::rms_about(e, 0.0);
  c.M[s.name + "_max_tracking_error_" + u] = metrics::max_abs(e);
}

void currents(const MetricSpec& s, const metrics::Window& w, Context& c) {
  double peak = 0.0, rms = 0.0;
  for (const auto& coil : c.in.trace.current_A) {
    const auto i = metrics::slice(coil, w);
    peak = std::max(peak, metrics::max_abs(i));
    rms = std::max(rms, metrics::rms_about(i, 0.0));
  }
  c.M[s.name + "_peak_coil_current_A"] = peak;
  c.M[s.name + "_max_rms_coil_current_A"] = rms;
}

void loop(const MetricSpec& s, const metrics::Window&, Context& c) {
  const Multisine* x = nullptr;
  for (const auto& e : c.in.excitations) {
    if (e.axis == s.axis) x = &e;
  }
  if (x == nullptr) {
    c.warnings.push_back("metric 'loop " + std::string(axis_name(s.axis)) + "': no 'excite' on that axis");
    return;
  }
  // Skip the first 0.5 s (transient), then whole 1-s periods.
  const double span = std::floor(x->t1 - x->t0 - 0.5);
  const metrics::Window lw = metrics::window(c.t, x->t1 - span, x->t1);
  const auto d = metrics::slice(c.in.trace.disturbance_A[index(s.axis)], lw);
  const auto u_eff = metrics::slice(c.in.trace.effort_A[index(s.axis)], lw);
  const auto h = metrics::frequency_response(d, u_eff, c.in.servo_rate_Hz, x->freqs);
  std::vector<std::complex<double>> l(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) l[i] = -h[i] / (1.0 + h[i]);  // u = -L (u + d)
  const metrics::LoopMargins lm = metrics::loop_margins(x->freqs, l);
  const std::string& n = s.name;
  if (lm.crossover_found) {
    c.M[n + "_loop_crossover_Hz"] = lm.crossover_Hz;
    c.M[n + "_loop_phase_margin_deg"] = lm.phase_margin_deg;
  } else {
    c.warnings.push_back(n + " loop: no crossover inside the excited band");
  }
  if (lm.bandwidth_found) c.M[n + "_closed_loop_bandwidth_Hz"] = lm.closed_loop_bandwidth_Hz;
  else c.warnings.push_back(n + " loop: closed-loop bandwidth outside the excited band");
  c.M[n + "_closed_loop_peak_dB"] = lm.closed_loop_peak_dB;
  c.M[n + "_closed_loop_peak_Hz"] = lm.closed_loop_peak_Hz;
}

void levitation(const MetricSpec&, const metrics::Window&, Context& c) {
  c.M["levitated"] = c.in.ready_t >= 0 ? 1.0 : 0.0;
  c.M["levitation_time_s"] = c.in.ready_t >= 0 && c.in.levitate_t >= 0 ? c.in.ready_t - c.in.levitate_t : -1.0;
  const double tend = c.t.empty() ? 0.0 : c.t.back();
  const auto z = metrics::slice(pose(c, Axis::kZ), metrics::window(c.t, std::max(0.0, tend - 0.2), tend + 1.0));
  const double zm = z.empty() ? 0.0 : metrics::mean(z);
  c.M["z_final_height_m"] = zm;
  c.M["z_height_error_m"] = zm - io::stage::kNominalHeight_m;
}

// kind -> (arguments, computation). Window-less kinds (loop, levitation)
// run even when their window holds no samples.
struct Kind {
  const char* name;
  enum Args : std::uint8_t { kAxisWindowName, kWindowName, kAxisOnly, kNone } args;
  bool needs_window;
  void (*compute)(const MetricSpec&, const metrics::Window&, Context&);
};
constexpr Kind kKinds[] = {
    {"noise", Kind::kAxisWindowName, true, noise},
    {"step", Kind::kAxisWindowName, true, step_or_ccq},
    {"step_resolution", Kind::kAxisWindowName, true, step_or_ccq},
    {"step_avg", Kind::kAxisWindowName, true, step_avg},
    {"ccq", Kind::kAxisWindowName, true, step_or_ccq},
    {"tracking", Kind::kAxisWindowName, true, tracking},
    {"currents", Kind::kWindowName, true, currents},
    {"loop", Kind::kAxisOnly, false, loop},
    {"levitation", Kind::kNone, false, levitation},
};

const Kind* find_kind(const std::string& k) {
  for (const auto& x : kKinds) {
    if (k == x.name) return &x;
  }
  return nullptr;
}

}  // namespace

std::string metric_kinds() {
  std::string l;
  for (const auto& k : kKinds) l += std::string(l.empty() ? "" : ", ") + k.name;
  return l;
}

bool parse_metric(const scenario::MetricRequest& m, MetricSpec* out, std::string* err) {
  MetricSpec s;
  s.kind = m.kind;
  s.line = m.line;
  const auto& a = m.args;
  const Kind* k = find_kind(m.kind);
  if (k == nullptr) {
    *err = "unknown metric '" + m.kind + "' (" + metric_kinds() + ")";
    return false;
  }
  auto time = [&](std::size_t i, double* dst) {
    const auto r = parse_quantity(a[i], Dim::kTime, err);
    if (r) *dst = *r;
    return r.has_value();
  };
  auto axis = [&](std::size_t i) {
    if (parse_axis(a[i], &s.axis)) return true;
    *err = "unknown axis '" + a[i] + "'";
    return false;
  };
  switch (k->args) {
    case Kind::kAxisWindowName:
      if (a.size() != 4) {
        *err = "'" + m.kind + "' takes AXIS T_BEGIN T_END NAME";
        return false;
      }
      if (!axis(0) || !time(1, &s.t0) || !time(2, &s.t1)) return false;
      s.name = a[3];
      break;
    case Kind::kWindowName:
      if (a.size() != 3) {
        *err = "'" + m.kind + "' takes T_BEGIN T_END NAME";
        return false;
      }
      if (!time(0, &s.t0) || !time(1, &s.t1)) return false;
      s.name = a[2];
      break;
    case Kind::kAxisOnly:
      if (a.size() != 1) {
        *err = "'" + m.kind + "' takes AXIS (analyses that axis' 'excite' window)";
        return false;
      }
      if (!axis(0)) return false;
      s.name = axis_name(s.axis);
      break;
    case Kind::kNone:
      if (!a.empty()) {
        *err = "'" + m.kind + "' takes no arguments";
        return false;
      }
      s.name = m.kind;
      break;
  }
  if (s.t1 < s.t0) {
    *err = "metric window ends before it begins";
    return false;
  }
  *out = s;
  return true;
}

void compute_metrics(const scenario::Scenario& sc, const MetricInputs& in, std::map<std::string, double>* out,
                     std::vector<std::string>* warnings) {
  Context c{in, std::span<const double>(in.trace.t_s), 0.0, in.duration_s,
            static_cast<std::size_t>(std::lround(0.010 * in.servo_rate_Hz)), *out, *warnings};
  // Rest: from Ready + 0.5 s to the first point-to-point motion after it. A
  // motion commanded before that (the ccq scenarios level the as-built
  // platen right after Ready) moves the start to 1 s after it.
  double begin = in.ready_t >= 0.0 ? in.ready_t + 0.5 : -1.0;
  for (const auto& a : in.actions) {
    if (begin >= 0.0 && a.is_point_to_point() && a.t_s < begin) begin = std::max(begin, a.t_s + 1.0);
  }
  for (const auto& a : in.actions) {
    if (a.is_point_to_point() && (begin < 0.0 || a.t_s >= begin)) c.rest_end = std::min(c.rest_end, a.t_s);
  }
  c.rest_begin = begin >= 0.0 ? begin : c.rest_end;
  for (const auto& req : sc.metrics) {
    MetricSpec s;
    std::string err;
    if (!parse_metric(req, &s, &err)) continue;  // validate() reported it
    const Kind& k = *find_kind(s.kind);
    const metrics::Window w = metrics::window(c.t, s.t0, s.t1);
    if (k.needs_window && w.size() < 2) {
      warnings->push_back("metric '" + s.name + "': window has no samples");
      continue;
    }
    k.compute(s, w, c);
  }
}

}  // namespace maglev::bench
