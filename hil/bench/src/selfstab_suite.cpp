// The paper-001 bench: selfstab kernel x hil/selfstab_plant in lockstep, and
// the experiments of docs/PAPER-001.md with a verdict each.
#include "maglev/bench/selfstab_suite.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "maglev/bench/overrides.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/selfstab_plant/linearize.hpp"
#include "maglev/selfstab_plant/plant.hpp"
#include "maglev/stage_profile/selfstab_config.hpp"

namespace maglev::bench {
namespace {

namespace fs = std::filesystem;
namespace sp = maglev::stage_profile;
namespace ss = maglev::selfstab;
namespace pl = maglev::selfstab_plant;
constexpr double kPi = 3.14159265358979323846;
// Lever that turns an angle into the displacement a PSD sees (the ring
// radius of the profile's PSDs, 0.1 m): coupling of the angles in um.
double ring_radius(const sp::StageProfile& p) { return std::hypot(p.sensors[0].x_m, p.sensors[0].y_m); }

// Paper axis -> plant state index of its velocity.
constexpr int kVelocityIndex[6] = {6, 7, 8, 9, 10, 11};

struct Row {
  double t;
  pl::Pose truth;
  float pose[6], feedback[6], reference[6], effort[6], current[9];
  int mode;
};

// One lockstep bench: sample the PSDs (codes), tick the kernel, hold the
// amplifier voltages R i_cmd for one tick on the plant.
class Bench {
 public:
  Bench(const sp::StageProfile& prof, const pl::StageParams& pp) : plant_(pp) {
    ok_ = sp::MakeSelfstabKernelConfig(prof, &cfg_) == sp::ProfileError::kOk &&
          kernel_.configure(cfg_) == ss::SelfstabConfigError::kOk;
    plant_.ResetDocked();
    R_ = prof.solenoid.coil_resistance_Ohm;
    lsb_ = prof.sensors[0].resolution;
    T_ = 1.0 / prof.servo_rate_Hz;
  }
  bool ok() const { return ok_; }
  ss::SelfstabKernel& kernel() { return kernel_; }
  pl::Plant& plant() { return plant_; }
  double t() const { return t_; }
  double T() const { return T_; }
  const std::vector<Row>& rows() const { return rows_; }
  double peak_current_A() const { return peak_current_; }

  void tick() {
    const ss::SelfstabCoilCommand cmd = kernel_.tick(SelfstabSampleFromPsd(plant_.Measure(), lsb_));
    const pl::CoilVector u = SelfstabAmplifierVoltages(cmd, cfg_.dac_A_per_code, R_);
    for (double v : u) peak_current_ = std::max(peak_current_, std::fabs(v / R_));
    plant_.Step(u, T_);
    t_ += T_;
    const ss::SelfstabTelemetry& k = kernel_.telemetry();
    Row r{};
    r.t = t_;
    r.truth = plant_.pose();
    for (int a = 0; a < 6; ++a) {
      r.pose[a] = k.pose[a];
      r.feedback[a] = k.feedback[a];
      r.reference[a] = k.reference[a];
      r.effort[a] = k.effort_A[a];
    }
    for (int j = 0; j < 9; ++j) r.current[j] = k.current_A[j];
    r.mode = static_cast<int>(k.mode);
    rows_.push_back(r);
  }
  void run(double seconds) {
    const long n = std::lround(seconds / T_);
    for (long i = 0; i < n; ++i) tick();
  }
  // Lift-off from the dock; true once the loops are closed. Then settles.
  bool lift_off(double settle_s) {
    if (kernel_.lift_off() != ss::SelfstabResult::kOk) return false;
    for (int i = 0; i < 10000 && kernel_.mode() != ss::SelfstabMode::kLevitated; ++i) tick();
    if (kernel_.mode() != ss::SelfstabMode::kLevitated) return false;
    run(settle_s);
    return kernel_.mode() == ss::SelfstabMode::kLevitated;
  }
  void write_trace(const std::string& path) const {
    std::ofstream f(path);
    f << "t_s,x_m,y_m,z_m,alpha_rad,beta_rad,gamma_rad,psd_x_m,psd_y_m,psd_z_m,psd_alpha_rad,psd_beta_rad,"
         "psd_gamma_rad,feedback_x_m,feedback_z_m,ref_x_m,ref_z_m,effort_x_A,effort_z_A";
    for (int j = 0; j < 9; ++j) f << ",i_" << pl::CoilName(j) << "_A";
    f << ",mode\n";
    char buf[64];
    for (const Row& r : rows_) {
      f << r.t;
      for (double v : r.truth) {
        std::snprintf(buf, sizeof buf, ",%.9g", v);
        f << buf;
      }
      for (float v : r.pose) {
        std::snprintf(buf, sizeof buf, ",%.9g", static_cast<double>(v));
        f << buf;
      }
      const float extra[] = {r.feedback[0], r.feedback[2], r.reference[0], r.reference[2], r.effort[0], r.effort[2]};
      for (float v : extra) {
        std::snprintf(buf, sizeof buf, ",%.9g", static_cast<double>(v));
        f << buf;
      }
      for (float v : r.current) {
        std::snprintf(buf, sizeof buf, ",%.6g", static_cast<double>(v));
        f << buf;
      }
      f << "," << r.mode << "\n";
    }
  }

 private:
  pl::Plant plant_;
  ss::SelfstabKernel kernel_;
  ss::SelfstabKernelConfig cfg_{};
  bool ok_ = false;
  double R_ = 0, lsb_ = 0, T_ = 0, t_ = 0, peak_current_ = 0;
  std::vector<Row> rows_;
};

void add(SelfstabSuiteResult* r, const std::string& exp, const std::string& q, double value, double reference,
         double lo, double hi, const std::string& note) {
  const double ratio = reference != 0.0 ? value / reference : 0.0;
  r->verdicts.push_back({exp, q, value, reference, ratio, lo, hi, std::isfinite(ratio) && ratio >= lo && ratio <= hi,
                         note});
}

// Least-squares slope of y over x.
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// Free response d(t) (equilibrium removed): damped frequency from the
// zero crossings (regression), damping ratio from the decay of the
// half-cycle peaks (regression of their logarithm), using the half-cycles
// whose peak is above min_peak (the quantization is a fraction of it).
struct FreeFit {
  bool ok;
  double fn_Hz, zeta, fd_Hz;
  int half_cycles;
};
FreeFit fit_free_response(const std::vector<double>& t, const std::vector<double>& d, double min_peak) {
  FreeFit f{};
  std::vector<double> cross_t, peaks;
  int sign = 0;
  std::size_t last_nonzero = 0;
  double peak = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const int s = d[i] > 0 ? 1 : (d[i] < 0 ? -1 : 0);
    if (s == 0) continue;
    if (sign != 0 && s != sign) {
      // Crossing between the last sample of the old sign and this one.
      const double t0 = t[last_nonzero], t1 = t[i];
      const double y0 = d[last_nonzero], y1 = d[i];
      cross_t.push_back(t0 + (t1 - t0) * y0 / (y0 - y1));
      peaks.push_back(peak);
      peak = 0;
    }
    sign = s;
    last_nonzero = i;
    peak = std::max(peak, std::fabs(d[i]));
  }
  // peaks[k] is the half-cycle that ENDS at cross_t[k]; the first one starts
  // at the impulse. Use the consecutive half-cycles whose peak exceeds
  // min_peak.
  std::vector<double> k_idx, ln_peak, ct, ck;
  // The peaks of e^(-sigma t) sin(w_d t) are w_d-spaced from the first on,
  // so the first half-cycle (from the impulse) counts as well.
  std::size_t first = 0;  // a residual wiggle before the impulse took over is skipped
  while (first < peaks.size() && peaks[first] < min_peak) ++first;
  for (std::size_t k = first; k < peaks.size(); ++k) {
    if (peaks[k] < min_peak) break;
    k_idx.push_back(static_cast<double>(k));
    ln_peak.push_back(std::log(peaks[k]));
    ct.push_back(cross_t[k]);
    ck.push_back(static_cast<double>(k));
  }
  if (k_idx.size() < 4) return f;
  const double half_period = slope(ck, ct);
  const double s = slope(k_idx, ln_peak);  // = -pi zeta / sqrt(1 - zeta^2) per half-cycle
  f.fd_Hz = 1.0 / (2.0 * half_period);
  f.zeta = -s / std::sqrt(kPi * kPi + s * s);
  f.fn_Hz = f.fd_Hz / std::sqrt(1.0 - f.zeta * f.zeta);
  f.half_cycles = static_cast<int>(k_idx.size());
  f.ok = true;
  return f;
}

struct StepMetrics {
  double final_ratio, overshoot, rise_s, settle_s, coupling_um[6];
};
// From the true pose (the coupling the paper looks for is below its sensor).
StepMetrics step_metrics(const std::vector<Row>& rows, std::size_t step_index, double step, double band, double lever) {
  StepMetrics m{};
  pl::Pose pre{};
  const std::size_t n_pre = std::min<std::size_t>(step_index, 500);
  for (std::size_t i = step_index - n_pre; i < step_index; ++i)
    for (std::size_t a = 0; a < 6; ++a) pre[a] += rows[i].truth[a] / static_cast<double>(n_pre);
  const double t0 = rows[step_index].t;
  double peak = -1e9, t10 = -1, t90 = -1, last_out = t0;
  const std::size_t n = rows.size();
  double final_sum = 0;
  int final_n = 0;
  for (std::size_t i = step_index; i < n; ++i) {
    const double z = (rows[i].truth[2] - pre[2]) / step;
    peak = std::max(peak, z);
    if (t10 < 0 && z >= 0.1) t10 = rows[i].t;
    if (t90 < 0 && z >= 0.9) t90 = rows[i].t;
    if (std::fabs(rows[i].truth[2] - pre[2] - step) > band) last_out = rows[i].t;
    if (rows[i].t > rows[n - 1].t - 0.5) {
      final_sum += z;
      ++final_n;
    }
    for (std::size_t a = 0; a < 6; ++a) {
      if (a == 2) continue;
      const double d = std::fabs(rows[i].truth[a] - pre[a]) * (a >= 3 ? lever : 1.0) * 1e6;
      m.coupling_um[a] = std::max(m.coupling_um[a], d);
    }
  }
  m.final_ratio = final_sum / final_n;
  m.overshoot = std::max(0.0, peak - 1.0);
  m.rise_s = (t10 >= 0 && t90 >= 0) ? t90 - t10 : -1;
  m.settle_s = last_out - t0;
  return m;
}

void write_metrics(const std::string& dir, const SelfstabSuiteResult& r, const std::string& prefix) {
  if (dir.empty()) return;
  std::ofstream js((fs::path(dir) / "metrics.json").string());
  js << "{";
  bool first = true;
  char buf[64];
  for (const auto& [k, v] : r.metrics) {
    if (k.rfind(prefix, 0) != 0) continue;
    std::snprintf(buf, sizeof buf, "%.9g", v);
    js << (first ? "\n" : ",\n") << "  \"" << k << "\": " << (std::isfinite(v) ? buf : "null");
    first = false;
  }
  for (const auto& v : r.verdicts) {
    if (v.experiment.rfind(prefix, 0) != 0 && !prefix.empty()) continue;
    std::snprintf(buf, sizeof buf, "%.6g", v.ratio);
    js << (first ? "\n" : ",\n") << "  \"" << v.experiment << "." << v.quantity << ".verdict\": \""
       << (v.pass ? "pass" : "FAIL") << "\"";
    first = false;
  }
  js << "\n}\n";
}

sp::StageProfile free_vibration_profile(sp::StageProfile p) {
  // Fig. 8(b): only x closed-loop; z is left passive like the others.
  p.axis[3].mode = sp::AxisMode::kPassive;
  p.axis[3].controller.kind = sp::ControllerKind::kNone;
  return p;
}

// Our own improvements (separated from the reproduction), each a variant of
// the profile: the loop without the 10 Hz filter (gains designed for it by
// the same rule as the paper set: >= 45 deg on (13) with the tick, ours),
// and a 16-bit A/D over the same 4.7 mm (71.7 nm per count, ours).
sp::StageProfile no_filter_profile(sp::StageProfile p) {
  for (int a : {0, 3}) p.axis[a].controller.filter_count = 0;
  p.axis[0].controller.kp = 150;
  p.axis[0].controller.ki = 200;
  p.axis[0].controller.kd = 3;
  p.axis[3].controller.kp = 300;
  p.axis[3].controller.ki = 1600;
  p.axis[3].controller.kd = 6;
  return p;
}
sp::StageProfile better_sensor_profile(sp::StageProfile p) {
  for (int k = 0; k < p.sensor_count; ++k) p.sensors[k].resolution = 4.7e-3 / 65536.0;
  return p;
}

// Settling band: 2 % of the step, but at least 2 counts: a reference
// between two codes makes the integrating loop dither by +-1 count.
double settle_band(double step, double lsb) { return std::max(0.02 * step, 2.0 * lsb); }

bool z_step(const sp::StageProfile& prof, double step, bool filter, const std::string& exp,
            const std::string& out_dir, SelfstabSuiteResult* r, StepMetrics* out) {
  const pl::StageParams pp = SelfstabPlantParams(prof);
  Bench b(prof, pp);
  if (!b.ok() || !b.lift_off(2.0)) return false;
  b.kernel().set_feedback_filter(filter && b.kernel().config().feedback_filter_enabled);
  b.run(0.5);
  const std::size_t i0 = b.rows().size();
  if (b.kernel().move_to(ss::kZ, static_cast<float>(step)) != ss::SelfstabResult::kOk) return false;
  b.run(3.0);
  const double lsb = prof.sensors[0].resolution;
  const StepMetrics m = step_metrics(b.rows(), i0, step, settle_band(step, lsb), ring_radius(prof));
  *out = m;
  const std::string k = exp + ".";
  r->metrics[k + "final_ratio"] = m.final_ratio;
  r->metrics[k + "overshoot_percent"] = 100 * m.overshoot;
  r->metrics[k + "rise_10_90_s"] = m.rise_s;
  r->metrics[k + "settling_s"] = m.settle_s;
  r->metrics[k + "settling_band_m"] = settle_band(step, lsb);
  static const char* kNames[6] = {"x", "y", "z", "alpha", "beta", "gamma"};
  for (int a = 0; a < 6; ++a)
    if (a != 2) r->metrics[k + "coupling_" + kNames[a] + "_um"] = m.coupling_um[a];
  r->metrics[k + "peak_coil_current_A"] = b.peak_current_A();
  r->metrics[k + "stayed_levitated"] = b.kernel().mode() == ss::SelfstabMode::kLevitated;
  if (!out_dir.empty()) {
    fs::create_directories(fs::path(out_dir) / exp);
    b.write_trace((fs::path(out_dir) / exp / "trace.csv").string());
  }
  return b.kernel().mode() == ss::SelfstabMode::kLevitated;
}

void step_verdicts(const std::string& exp, double step, double lsb, const StepMetrics& m, SelfstabSuiteResult* r,
                   bool settling = true) {
  const double tol = lsb / step;
  add(r, exp, "final value / step", m.final_ratio, 1.0, 1.0 - tol, 1.0 + tol, "true z, band +-1 sensor LSB");
  if (settling) add(r, exp, "settling time / 1.5 s", m.settle_s, 1.5, 0.0, 1.0, "band max(2 %, 2 LSB) (ours)");
  double worst = 0;
  for (int a : {1, 3, 4, 5}) worst = std::max(worst, m.coupling_um[a]);
  add(r, exp, "coupling y,alpha,beta,gamma / 1 um", worst, 1.0, 0.0, 1.0,
      "peak, true pose, angles x PSD radius (paper: below its 1 um sensor)");
}

}  // namespace

ss::SelfstabSensorSample SelfstabSampleFromPsd(const pl::PsdReading& y, double lsb_m) {
  ss::SelfstabSensorSample s{};
  for (std::size_t c = 0; c < static_cast<std::size_t>(ss::kPsdChannels); ++c) {
    const double code = std::max(-32767.0, std::min(32767.0, std::round(y[c] / lsb_m)));
    s.psd_code[c] = static_cast<std::int16_t>(code);
  }
  s.status = ss::kPsdValid;
  return s;
}

pl::CoilVector SelfstabAmplifierVoltages(const ss::SelfstabCoilCommand& cmd, float dac_A_per_code, double R_ohm) {
  pl::CoilVector u{};
  for (std::size_t j = 0; j < static_cast<std::size_t>(ss::kCoils); ++j) {
    const double i = cmd.enable ? cmd.dac_code[j] * static_cast<double>(dac_A_per_code) : 0.0;
    u[j] = R_ohm * i;
  }
  return u;
}

bool selfstab_accepts(const sp::StageProfile& p) {
  ss::SelfstabKernelConfig k{};
  return sp::MakeSelfstabKernelConfig(p, &k) == sp::ProfileError::kOk;
}

int selfstab_check_profile(const sp::StageProfile& p) {
  ss::SelfstabKernelConfig k{};
  const sp::ProfileError e = sp::MakeSelfstabKernelConfig(p, &k);
  std::printf("  paper-000 kernel: not this family (the checks above are its own)\n");
  if (e != sp::ProfileError::kOk) {
    std::printf("  selfstab kernel (paper 001): REFUSES this profile: %s\n", sp::to_string(e));
    return 1;
  }
  const pl::StageParams pp = SelfstabPlantParams(p);
  for (double z : {-2e-3, 0.0, 2e-3}) {
    const SelfstabMargins m = ZLoopMargins(k, pp, z, true);
    std::printf("  selfstab z loop at z %+.1f mm: crossover %.3g Hz, phase margin %.3g deg (bench plant linearized)\n",
                z * 1e3, m.crossover_Hz, m.phase_margin_deg);
  }
  std::printf("  selfstab kernel (paper 001): accepts this profile; bench: plant built from it "
              "(maglev-hil suite --profile %s)\n", p.name);
  return 0;
}

bool SelfstabSuiteResult::all_pass() const {
  for (const auto& v : verdicts)
    if (!v.pass) return false;
  return !verdicts.empty();
}

pl::StageParams SelfstabPlantParams(const sp::StageProfile& p) {
  pl::StageParams s = pl::BenchParams();
  s.mass_kg = p.body.mass_kg;
  s.inertia_xx_kg_m2 = p.body.inertia_kgm2[0];
  s.inertia_yy_kg_m2 = p.body.inertia_kgm2[1];
  s.inertia_zz_kg_m2 = p.body.inertia_kgm2[2];
  s.gravity_m_per_s2 = p.body.gravity_m_per_s2;
  const sp::SolenoidParameters& q = p.solenoid;
  s.L_m = q.length_m;
  s.r1_m = q.radius_r1_m;
  s.r2_m = q.radius_r2_m;
  s.magnet.magnetization_M_A_per_m = q.magnetization_A_per_m;
  s.magnet.volume_m3 = q.magnet_volume_m3;
  s.in_plane.nominal_current_A = q.nominal_current_in_plane_A;
  s.out_of_plane.nominal_current_A = q.nominal_current_out_of_plane_A;
  s.in_plane.turns_N = q.turns_in_plane;
  s.out_of_plane.turns_N = q.turns_out_of_plane;
  s.coil.resistance_R_ohm = q.coil_resistance_Ohm;
  // PSDs: ring radius and first angle from sensor 1; the A/D's bits from the
  // resolution over the paper's 4.7 mm active area.
  s.psd.ring_radius_m = std::hypot(p.sensors[0].x_m, p.sensors[0].y_m);
  s.psd.first_angle_rad = std::atan2(p.sensors[0].y_m, p.sensors[0].x_m);
  s.psd.adc_bits = static_cast<int>(std::lround(std::log2(s.psd.range_m / p.sensors[0].resolution)));
  return s;
}

SelfstabAxisModel LinearizeZAt(const pl::StageParams& p, double z0) {
  pl::Pose pose{};
  pose[2] = z0;
  const std::array<double, 6> zero{};
  pl::CoilVector i0 = pl::NominalCurrents(p);
  auto zdd = [&](const pl::Pose& q, const std::array<double, 6>& v, const pl::CoilVector& i) {
    return pl::Accelerations(p, q, v, i)[2];
  };
  // The effort (A on each of A, B, C) that holds z0: z'' is linear in it.
  const double du = 1e-3;
  pl::CoilVector ip = i0;
  for (int j = 0; j < 3; ++j) ip[static_cast<std::size_t>(j)] += du;
  const double g = (zdd(pose, zero, ip) - zdd(pose, zero, i0)) / du;
  const double hold = -zdd(pose, zero, i0) / g;
  for (int j = 0; j < 3; ++j) i0[static_cast<std::size_t>(j)] += hold;
  SelfstabAxisModel m{};
  m.gain = g;
  m.hold_current_A = hold;
  const double h = 1e-6;
  pl::Pose a = pose, b = pose;
  a[2] += h;
  b[2] -= h;
  m.stiffness_per_s2 = -(zdd(a, zero, i0) - zdd(b, zero, i0)) / (2 * h);
  pl::CoilVector u0 = i0;
  for (double& v : u0) v *= p.coil.resistance_R_ohm;
  std::array<double, 6> va{}, vb{};
  va[2] = h;
  vb[2] = -h;
  m.damping_per_s = -(zdd(pose, va, pl::QuasiStaticCurrents(p, pose, va, u0)) -
                      zdd(pose, vb, pl::QuasiStaticCurrents(p, pose, vb, u0))) / (2 * h);
  return m;
}

namespace {
// The kernel's z loop at frequency hz around the plant linearized at z0,
// with the given kp and kd scales, split into the parts the schedule solves
// for: L = (sp kp + I(z) + sd kd D(z)) * rest.
struct ZLoopParts {
  std::complex<double> integral, derivative, rest;  // derivative: per unit kd
  double kp, kd;
};
ZLoopParts z_loop_parts(const ss::SelfstabKernelConfig& k, const SelfstabAxisModel& m, const pl::StageParams& p,
                        double hz) {
  const ss::SelfstabLoopConfig& l = k.loop[ss::kZ];
  const double T = 1.0 / static_cast<double>(k.servo_rate_Hz);
  kernel::BiquadDesign f;
  kernel::design_biquad_double(l.feedback_filter, static_cast<double>(k.servo_rate_Hz), &f);
  const bool filt = k.feedback_filter_enabled != 0 && f.enabled;
  const double wf = 2 * kPi * static_cast<double>(l.derivative_filter_Hz);
  const double ad = (2 - wf * T) / (2 + wf * T), bd = 2 * wf / (2 + wf * T);
  const double tau = p.coil.inductance_L_H / p.coil.resistance_R_ohm;
  using C = std::complex<double>;
  const C s(0, 2 * kPi * hz);
  const C z = std::exp(s * T);
  ZLoopParts r{};
  r.kp = static_cast<double>(l.kp);
  r.kd = static_cast<double>(l.kd);
  r.integral = static_cast<double>(l.ki) * T / 2.0 * (z + 1.0) / (z - 1.0);
  r.derivative = bd * (z - 1.0) / (z - ad);
  const C F = filt ? (f.b0 + f.b1 / z + f.b2 / (z * z)) / (1.0 + f.a1 / z + f.a2 / (z * z)) : C(1.0);
  const C P = m.gain / (s * s + m.damping_per_s * s + m.stiffness_per_s2);
  r.rest = F * P * std::exp(-s * T / 2.0) / (1.0 + s * tau);
  return r;
}
std::complex<double> z_loop(const ZLoopParts& q, double sp, double sd) {
  return (sp * q.kp + q.integral + sd * q.kd * q.derivative) * q.rest;
}
SelfstabMargins margins_of(const ss::SelfstabKernelConfig& k, const pl::StageParams& p, double z0, double sp,
                           double sd) {
  const SelfstabAxisModel m = LinearizeZAt(p, z0);
  const double T = 1.0 / static_cast<double>(k.servo_rate_Hz);
  SelfstabMargins r{};
  double prev = std::abs(z_loop(z_loop_parts(k, m, p, 0.05), sp, sd));
  for (double hz = 0.05; hz < 0.5 / T; hz *= 1.0005) {
    const double mag = std::abs(z_loop(z_loop_parts(k, m, p, hz * 1.0005), sp, sd));
    if (prev > 1.0 && mag <= 1.0) {
      r.crossover_found = true;
      r.crossover_Hz = hz;
      r.phase_margin_deg = 180.0 + std::arg(z_loop(z_loop_parts(k, m, p, hz), sp, sd)) * 180.0 / kPi;
      if (r.phase_margin_deg > 180) r.phase_margin_deg -= 360;
    }
    prev = mag;
  }
  return r;
}
}  // namespace

std::vector<std::array<double, 3>> SelfstabZSchedule(const ss::SelfstabKernelConfig& k, const pl::StageParams& p,
                                                     const std::vector<double>& at) {
  // At each height the two scales make the loop at the nominal crossover
  // w0 what it is at z = 0 (magnitude and phase: two real equations, two
  // unknowns), so crossover and margin stay the nominal ones at the points:
  //   sp kp + sd kd D(w0) = C0(w0) P0(w0) / Pz(w0) - I(w0).
  const SelfstabMargins m0 = margins_of(k, p, 0.0, 1.0, 1.0);
  const ZLoopParts q0 = z_loop_parts(k, LinearizeZAt(p, 0.0), p, m0.crossover_Hz);
  const std::complex<double> L0 = z_loop(q0, 1.0, 1.0);
  std::vector<std::array<double, 3>> s;
  for (double z : at) {
    const ZLoopParts q = z_loop_parts(k, LinearizeZAt(p, z), p, m0.crossover_Hz);
    const std::complex<double> X = L0 / q.rest - q.integral;
    const double sd = X.imag() / (q.kd * q.derivative.imag());
    const double sp = (X.real() - sd * q.kd * q.derivative.real()) / q.kp;
    s.push_back({z, sp, sd});
  }
  return s;
}

SelfstabMargins ZLoopMargins(const ss::SelfstabKernelConfig& k, const pl::StageParams& p, double z0, bool scheduled) {
  const ss::SelfstabLoopConfig& l = k.loop[ss::kZ];
  // The scales the kernel would use at z0 (linear interpolation, as tick()).
  double sp_ = 1, sd_ = 1;
  if (scheduled && l.schedule_points >= 2) {
    const int n = l.schedule_points;
    auto interp = [&](const float* s) {
      auto at = [&](int i) { return static_cast<double>(l.schedule_at[i]); };
      auto v = [&](int i) { return static_cast<double>(s[i]); };
      if (z0 <= at(0)) return v(0);
      if (z0 >= at(n - 1)) return v(n - 1);
      int i = 0;
      while (i < n - 2 && z0 >= at(i + 1)) ++i;
      const double w = (z0 - at(i)) / (at(i + 1) - at(i));
      return v(i) + w * (v(i + 1) - v(i));
    };
    sp_ = interp(l.kp_scale);
    sd_ = interp(l.kd_scale);
  }
  return margins_of(k, p, z0, sp_, sd_);
}

std::vector<std::string> SelfstabExperiments() {
  return {"free_vibration", "z_step_10um", "z_step_100um", "lift_off", "schedule_margins", "filter_cost", "ours"};
}

bool RunSelfstabExperiment(const std::string& name, const sp::StageProfile& prof, const std::string& out_dir,
                           SelfstabSuiteResult* r) {
  const double lsb = prof.sensors[0].resolution;
  const double lever = ring_radius(prof);
  if (name == "free_vibration") {
    // Fig. 9: x controlled, a small impulse, the uncontrolled axes ring at
    // the frequencies and damping of (13). One run per axis.
    const sp::StageProfile p = free_vibration_profile(prof);
    const pl::StageParams pp = SelfstabPlantParams(p);
    static const char* kNames[6] = {"x", "y", "z", "alpha", "beta", "gamma"};
    for (int a : {1, 2, 3, 4, 5}) {
      Bench b(p, pp);
      // The lift-off leaves the passive axes ringing; z, the least damped
      // (zeta omega = 1.4 /s), gets longer to decay before the impulse.
      if (!b.ok() || !b.lift_off(a == 2 ? 8.0 : 4.0)) return false;
      const int pa = sp::ProfileAxisOfSelfstabAxis(a);
      const double k13 = p.axis[pa].open_loop_stiffness_per_s2, c13 = p.axis[pa].open_loop_damping_per_s;
      const double wn = std::sqrt(k13);
      const bool angle = a >= 3;
      const double amplitude = angle ? 1e-3 : 100e-6;  // (ours) ~87 PSD counts, 5 % of the +-2 mm range
      double pre = 0;
      const std::size_t n0 = b.rows().size();
      for (std::size_t i = n0 - 500; i < n0; ++i) pre += static_cast<double>(b.rows()[i].pose[a]) / 500.0;
      pl::State x = b.plant().state();
      x[static_cast<std::size_t>(kVelocityIndex[a])] += amplitude * wn;  // the impulse
      b.plant().Reset(x);
      b.run(8.0);
      std::vector<double> t, d;
      for (std::size_t i = n0; i < b.rows().size(); ++i) {
        t.push_back(b.rows()[i].t);
        d.push_back(static_cast<double>(b.rows()[i].pose[a]) - pre);
      }
      const double axis_lsb = angle ? lsb / lever : lsb;
      const FreeFit f = fit_free_response(t, d, 5.0 * axis_lsb);
      const double fn13 = wn / (2 * kPi), z13 = c13 / (2 * wn);
      const std::string k = std::string("free_vibration.") + kNames[a] + ".";
      r->metrics[k + "fn_Hz"] = f.fn_Hz;
      r->metrics[k + "zeta"] = f.zeta;
      r->metrics[k + "fd_Hz"] = f.fd_Hz;
      r->metrics[k + "half_cycles_used"] = f.half_cycles;
      r->metrics[k + "eq13_fn_Hz"] = fn13;
      r->metrics[k + "eq13_zeta"] = z13;
      add(r, "free_vibration", std::string(kNames[a]) + " f_n / eq (13)", f.ok ? f.fn_Hz : std::nan(""), fn13, 0.9, 1.1,
          "from the PSD pose (as the paper), x under control");
      add(r, "free_vibration", std::string(kNames[a]) + " zeta / eq (13)", f.ok ? f.zeta : std::nan(""), z13, 0.9, 1.1,
          "log decrement of the half-cycle peaks");
      if (!out_dir.empty()) {
        fs::create_directories(fs::path(out_dir) / "free_vibration");
        b.write_trace((fs::path(out_dir) / "free_vibration" / (std::string("trace_") + kNames[a] + ".csv")).string());
      }
    }
    return true;
  }
  if (name == "z_step_10um" || name == "z_step_100um") {
    const double step = name == "z_step_10um" ? 10e-6 : 100e-6;
    StepMetrics m{};
    if (!z_step(prof, step, true, name, out_dir, r, &m)) return false;
    step_verdicts(name, step, lsb, m, r);
    return true;
  }
  if (name == "lift_off") {
    const pl::StageParams pp = SelfstabPlantParams(prof);
    Bench b(prof, pp);
    if (!b.ok()) return false;
    if (b.kernel().lift_off() != ss::SelfstabResult::kOk) return false;
    b.run(6.0);
    double closed_t = -1, last_out = 0, peak_x = 0, z_max = -1, sum = 0;
    int n = 0;
    for (const Row& row : b.rows()) {
      if (closed_t < 0 && row.mode == static_cast<int>(ss::SelfstabMode::kLevitated)) closed_t = row.t;
      if (std::fabs(row.truth[2]) > 2 * lsb) last_out = row.t;
      peak_x = std::max(peak_x, std::fabs(row.truth[0]));
      if (closed_t >= 0) z_max = std::max(z_max, row.truth[2]);
      if (row.t > b.t() - 0.5) {
        sum += row.truth[2];
        ++n;
      }
    }
    const double final_err = std::fabs(sum / n);
    r->metrics["lift_off.loops_closed_s"] = closed_t;
    r->metrics["lift_off.settled_within_2lsb_s"] = last_out;
    r->metrics["lift_off.final_z_error_m"] = final_err;
    r->metrics["lift_off.peak_z_after_close_m"] = z_max;
    r->metrics["lift_off.peak_abs_x_m"] = peak_x;
    r->metrics["lift_off.peak_coil_current_A"] = b.peak_current_A();
    r->metrics["lift_off.levitated"] = b.kernel().mode() == ss::SelfstabMode::kLevitated;
    add(r, "lift_off", "final |z| / 1 LSB", final_err, lsb, 0.0, 1.0, "true z, mean of the last 0.5 s");
    add(r, "lift_off", "settled (|z| < 2 LSB) / 4 s", last_out, 4.0, 0.0, 1.0, "from the dock at -2.5 mm (ours)");
    if (!out_dir.empty()) {
      fs::create_directories(fs::path(out_dir) / "lift_off");
      b.write_trace((fs::path(out_dir) / "lift_off" / "trace.csv").string());
    }
    return b.kernel().mode() == ss::SelfstabMode::kLevitated;
  }
  if (name == "schedule_margins") {
    ss::SelfstabKernelConfig k{};
    if (sp::MakeSelfstabKernelConfig(prof, &k) != sp::ProfileError::kOk) return false;
    const pl::StageParams pp = SelfstabPlantParams(prof);
    const std::vector<double> grid = {-2e-3, -1.5e-3, -1e-3, -0.5e-3, 0.0, 0.5e-3, 1e-3, 1.5e-3, 2e-3};
    const SelfstabMargins s0 = ZLoopMargins(k, pp, 0.0, true);
    double drift_s = 0, drift_f = 0;
    for (double z : grid) {
      const SelfstabMargins s = ZLoopMargins(k, pp, z, true), f = ZLoopMargins(k, pp, z, false);
      char key[64];
      std::snprintf(key, sizeof key, "schedule_margins.z_%+.1fmm.", z * 1e3);
      r->metrics[std::string(key) + "scheduled_crossover_Hz"] = s.crossover_Hz;
      r->metrics[std::string(key) + "scheduled_phase_margin_deg"] = s.phase_margin_deg;
      r->metrics[std::string(key) + "fixed_crossover_Hz"] = f.crossover_Hz;
      r->metrics[std::string(key) + "fixed_phase_margin_deg"] = f.phase_margin_deg;
      char q[64];
      std::snprintf(q, sizeof q, "z %+.1f mm crossover / at 0", z * 1e3);
      add(r, "schedule_margins", q, s.crossover_Hz, s0.crossover_Hz, 0.9, 1.1, "scheduled");
      std::snprintf(q, sizeof q, "z %+.1f mm phase margin / at 0", z * 1e3);
      add(r, "schedule_margins", q, s.phase_margin_deg, s0.phase_margin_deg, 0.9, 1.1, "scheduled");
      drift_s = std::max({drift_s, std::fabs(s.crossover_Hz / s0.crossover_Hz - 1),
                          std::fabs(s.phase_margin_deg / s0.phase_margin_deg - 1)});
      drift_f = std::max({drift_f, std::fabs(f.crossover_Hz / s0.crossover_Hz - 1),
                          std::fabs(f.phase_margin_deg / s0.phase_margin_deg - 1)});
    }
    r->metrics["schedule_margins.scheduled_max_drift"] = drift_s;
    r->metrics["schedule_margins.fixed_max_drift"] = drift_f;
    add(r, "schedule_margins", "fixed drift / scheduled drift", drift_f, drift_s, 1.0, 1e9,
        "max relative change of crossover or margin over +-2 mm");
    // The profile's table is the plant's (no hand-made numbers).
    const auto& l = k.loop[ss::kZ];
    std::vector<double> at;
    for (int i = 0; i < l.schedule_points; ++i) at.push_back(l.schedule_at[i]);
    // Designed with the profile's base gains: the table's own scales at 1.
    ss::SelfstabKernelConfig base = k;
    base.loop[ss::kZ].schedule_points = 0;
    const auto plant_table = SelfstabZSchedule(base, pp, at);
    double worst = 0;
    for (std::size_t i = 0; i < at.size(); ++i) {
      worst = std::max(worst, std::fabs(static_cast<double>(l.kp_scale[i]) / plant_table[i][1] - 1.0));
      worst = std::max(worst, std::fabs(static_cast<double>(l.kd_scale[i]) / plant_table[i][2] - 1.0));
    }
    r->metrics["schedule_margins.profile_table_vs_plant_max_rel"] = worst;
    add(r, "schedule_margins", "profile schedule / plant's", 1.0 + worst, 1.0, 0.999, 1.001,
        "worst point of the table");
    return true;
  }
  if (name == "filter_cost") {
    // Section 4: the 10 Hz Butterworth in the feedback path slows the
    // transient. Same gains with and without it (its lag alone), and the
    // loop each allows (without it, gains for that loop: the real cost).
    StepMetrics on{}, off{}, own{};
    const sp::StageProfile nf = no_filter_profile(prof);
    if (!z_step(prof, 100e-6, true, "filter_cost.with_filter", out_dir, r, &on)) return false;
    if (!z_step(prof, 100e-6, false, "filter_cost.without_filter_same_gains", out_dir, r, &off)) return false;
    if (!z_step(nf, 100e-6, true, "filter_cost.without_filter_own_gains", out_dir, r, &own)) return false;
    step_verdicts("filter_cost.with_filter", 100e-6, lsb, on, r);
    step_verdicts("filter_cost.without_filter_same_gains", 100e-6, lsb, off, r);
    step_verdicts("filter_cost.without_filter_own_gains", 100e-6, lsb, own, r);
    ss::SelfstabKernelConfig k{}, knf{};
    if (sp::MakeSelfstabKernelConfig(prof, &k) != sp::ProfileError::kOk) return false;
    if (sp::MakeSelfstabKernelConfig(nf, &knf) != sp::ProfileError::kOk) return false;
    const pl::StageParams pp = SelfstabPlantParams(prof);
    ss::SelfstabKernelConfig k_off = k;
    k_off.feedback_filter_enabled = 0;
    const SelfstabMargins m_on = ZLoopMargins(k, pp, 0.0, true), m_off = ZLoopMargins(k_off, pp, 0.0, true),
                          m_own = ZLoopMargins(knf, pp, 0.0, true);
    r->metrics["filter_cost.with_filter.crossover_Hz"] = m_on.crossover_Hz;
    r->metrics["filter_cost.with_filter.phase_margin_deg"] = m_on.phase_margin_deg;
    r->metrics["filter_cost.without_filter_same_gains.crossover_Hz"] = m_off.crossover_Hz;
    r->metrics["filter_cost.without_filter_same_gains.phase_margin_deg"] = m_off.phase_margin_deg;
    r->metrics["filter_cost.without_filter_own_gains.crossover_Hz"] = m_own.crossover_Hz;
    r->metrics["filter_cost.without_filter_own_gains.phase_margin_deg"] = m_own.phase_margin_deg;
    add(r, "filter_cost", "phase margin with / without filter, same gains", m_on.phase_margin_deg,
        m_off.phase_margin_deg, 0.0, 0.99, "the filter's lag at the 5 Hz crossover");
    add(r, "filter_cost", "settling with filter / without (own gains)", on.settle_s, own.settle_s, 1.0, 1e9,
        "the transient the filter costs: the loop it allows vs the loop without it");
    return true;
  }
  if (name == "ours") {
    // Separated from the reproduction: a better sensor alone, and a better
    // sensor with the loop without the 10 Hz filter.
    const sp::StageProfile sensor = better_sensor_profile(prof);
    const sp::StageProfile both = better_sensor_profile(no_filter_profile(prof));
    const double lsb_ours = sensor.sensors[0].resolution;
    for (double step : {10e-6, 100e-6}) {
      const std::string tag = step < 50e-6 ? "z_step_10um" : "z_step_100um";
      StepMetrics paper{}, s_only{}, m{};
      SelfstabSuiteResult tmp;
      if (!z_step(prof, step, true, "paper", "", &tmp, &paper)) return false;
      if (!z_step(sensor, step, true, "ours.sensor_only." + tag, out_dir, r, &s_only)) return false;
      if (!z_step(both, step, true, "ours.sensor_and_no_filter." + tag, out_dir, r, &m)) return false;
      // The better sensor alone: the paper's loop, only finer counts. Its
      // settling is reported, not judged: with 72 nm counts the 2 % band of
      // a 10 um step (0.2 um) shows the PID's slow integral tail, which the
      // 12-bit sensor's 2-count band (2.3 um) hides.
      step_verdicts("ours.sensor_only." + tag, step, lsb_ours, s_only, r, false);
      step_verdicts("ours.sensor_and_no_filter." + tag, step, lsb_ours, m, r);
      r->metrics["ours." + tag + ".paper_set_settling_s"] = paper.settle_s;
      add(r, "ours.sensor_and_no_filter." + tag, "settling time ours / paper set", m.settle_s, paper.settle_s, 0.0,
          1.0, "16-bit PSD A/D, no 10 Hz filter, gains for that loop (ours)");
    }
    return true;
  }
  return false;
}

void PrintSelfstabVerdicts(const SelfstabSuiteResult& r) {
  std::printf("\n%-28s %-40s %12s %12s %9s %15s  %s\n", "experiment", "quantity", "bench", "reference", "ratio",
              "band", "verdict");
  for (const auto& v : r.verdicts) {
    char band[32];
    if (v.hi >= 1e8) std::snprintf(band, sizeof band, ">= %.3g", v.lo);
    else std::snprintf(band, sizeof band, "[%.3g, %.3g]", v.lo, v.hi);
    std::printf("%-28s %-40s %12.5g %12.5g %9.4f %15s  %s  (%s)\n", v.experiment.c_str(), v.quantity.c_str(), v.value,
                v.reference, v.ratio, band, v.pass ? "pass" : "FAIL", v.note.c_str());
  }
}

bool selfstab_dispatch(const std::string& cmd, const std::vector<std::string>& positional, const std::string& profile,
                       const std::string& out_dir, int* rc) {
  const profile::ProfileParse parsed = profile::find_profile(profile, profile_dir());
  if (!parsed.ok() || parsed.profile.family != sp::ActuatorFamily::kSolenoidMagnet) return false;
  const sp::StageProfile& p = parsed.profile;
  if (cmd == "selfstab-schedule") {
    // The z schedule the profile should carry (paste into its [axis z]).
    ss::SelfstabKernelConfig k{};
    if (sp::MakeSelfstabKernelConfig(p, &k) != sp::ProfileError::kOk) {
      *rc = 1;
      return true;
    }
    k.loop[ss::kZ].schedule_points = 0;
    const auto t = SelfstabZSchedule(k, SelfstabPlantParams(p), {-2e-3, -1e-3, 0.0, 1e-3, 2e-3});
    std::printf("schedule =");
    for (std::size_t i = 0; i < t.size(); ++i)
      std::printf("%s %g %.4f %.4f", i ? ";" : "", t[i][0], t[i][1], t[i][2]);
    std::printf("\n");
    *rc = 0;
    return true;
  }
  if (cmd == "list") {
    for (const auto& n : SelfstabExperiments()) std::printf("  %s\n", n.c_str());
    *rc = 0;
    return true;
  }
  if (cmd != "run" && cmd != "suite") return false;
  if (out_dir.empty()) {
    std::fprintf(stderr, "maglev-hil %s: needs --out DIR\n", cmd.c_str());
    *rc = 2;
    return true;
  }
  std::vector<std::string> names = SelfstabExperiments();
  if (cmd == "run") {
    if (positional.size() != 1 ||
        std::find(names.begin(), names.end(), positional[0]) == names.end()) {
      std::fprintf(stderr, "maglev-hil run --profile %s: one of", p.name);
      for (const auto& n : names) std::fprintf(stderr, " %s", n.c_str());
      std::fprintf(stderr, "\n");
      *rc = 2;
      return true;
    }
    names = {positional[0]};
  }
  fs::create_directories(out_dir);
  SelfstabSuiteResult r;
  bool ran = true;
  for (const auto& n : names) {
    std::printf("%s: %s ...\n", p.name, n.c_str());
    std::fflush(stdout);
    if (!RunSelfstabExperiment(n, p, out_dir, &r)) {
      std::fprintf(stderr, "%s: the stage did not stay levitated or the kernel refused it\n", n.c_str());
      ran = false;
    }
  }
  write_metrics(out_dir, r, "");
  PrintSelfstabVerdicts(r);
  int pass = 0;
  for (const auto& v : r.verdicts) pass += v.pass;
  std::printf("%d of %zu verdicts pass\n", pass, r.verdicts.size());
  *rc = ran && r.all_pass() ? 0 : 1;
  return true;
}

}  // namespace maglev::bench
