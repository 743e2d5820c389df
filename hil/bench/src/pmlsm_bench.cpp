#include "maglev/bench/pmlsm_bench.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>

#include "maglev/control_design/imr_design.hpp"
#include "maglev/pmlsm_replay/pmlsm_replay_format.hpp"

namespace maglev::bench::pmlsm {

namespace ps = pmlsm_stage;
namespace sp = stage_profile;
namespace cd = control_design;
namespace fs = std::filesystem;
using ps::Axis;
using ps::CommandResult;
using ps::MotionCommand;
using ps::MotionType;

namespace {
double g_simulated_s = 0.0;  // single-threaded: the suite runs its benches one after another
constexpr double kPi = 3.14159265358979323846;
constexpr std::array<std::size_t, 5> kStateOf{0, 2, 4, 6, 8};  // plant state of each kernel axis
const char* const kAxisName[5] = {"gap", "x", "z", "phi", "theta"};
}  // namespace

bool PmlsmBench::Init(const sp::StageProfile& profile, const Variant& v, std::string* why) {
  sp::StageProfile p = profile;
  if (v.servo_rate_Hz > 0.0) p.servo_rate_Hz = v.servo_rate_Hz;
  for (int i = 0; i < p.sensor_count; ++i) p.sensors[i].resolution *= v.encoder_scale;
  if (!cd::PmlsmStageFromProfile(p, &stage_, why)) return false;
  if (!cd::BuildPmlsmKernelConfig(p, &design_, why)) return false;
  ps::PmlsmKernelConfig& c = design_.config;
  if (!v.rotation_loops) c.axis[3].closed = c.axis[4].closed = false;
  if (!v.antiwindup) {
    for (auto& r : c.axis) r.E[0] = r.E[1] = r.E[2] = 0.0f;
  }
  c.exact_vertical_inverse = v.exact_vertical_inverse;
  const ps::PmlsmConfigError e = ctl_.apply_config(c);
  if (e != ps::PmlsmConfigError::kOk) {
    *why = std::string("the kernel refused the configuration: ") + ps::to_string(e);
    return false;
  }
  plant_ = std::make_unique<pmlsm_plant::Plant>(stage_.stage, stage_.amplifier, stage_.encoder);
  pmlsm_plant::State x0{};
  x0[0] = stage_.stage.gap_max_m;  // resting on the stops
  plant_->Reset(x0);
  period_s_ = 1.0 / p.servo_rate_Hz;
  return true;
}

double PmlsmBench::total_simulated_s() { return g_simulated_s; }

std::array<double, 5> PmlsmBench::pose() const {
  std::array<double, 5> y{};
  for (std::size_t a = 0; a < 5; ++a) y[a] = plant_->state()[kStateOf[a]];
  return y;
}

CommandResult PmlsmBench::Command(const MotionCommand& c) {
  // The replay carries one command per tick: a second one waits a tick.
  if (rec_in_ != nullptr && has_pending_) Tick();
  const CommandResult r = ctl_.command(c);
  if (rec_in_ != nullptr) {
    has_pending_ = true;
    pending_ = c;
    pending_result_ = static_cast<std::uint8_t>(r);
  }
  return r;
}

void PmlsmBench::StartRecording(std::vector<unsigned char>* in, std::vector<unsigned char>* out) {
  rec_in_ = in;
  rec_out_ = out;
}

void PmlsmBench::StartTrace(std::FILE* f, int every) {
  trace_ = f;
  trace_every_ = std::max(1, every);
  std::fprintf(f, "t_s,state,gap_m,x_m,z_m,phi_rad,theta_rad,gap_meas_m,x_meas_m,z_meas_m,phi_meas_rad,theta_meas_rad,"
                  "gap_ref_m,x_ref_m,z_ref_m,phi_ref_rad,theta_ref_rad,i_d1_A,i_d2_A,i_d3_A,i_d4_A,u_x_A,u_z_A\n");
}

void PmlsmBench::Tick() {
  const auto counts = plant_->EncoderCounts();
  ps::SensorSample s{};
  for (int a = 0; a < 5; ++a) s.encoder_counts[a] = counts[static_cast<std::size_t>(a)];
  s.status_flags = 0;
  const ps::ActuatorCommand out = ctl_.step(s);
  if (rec_in_ != nullptr) {
    pmlsm_replay::InputRecord r;
    std::memset(static_cast<void*>(&r), 0, sizeof r);
    r.has_command = has_pending_ ? 1 : 0;
    if (has_pending_) r.command = pending_;
    r.sample = s;
    const auto* b = reinterpret_cast<const unsigned char*>(&r);
    rec_in_->insert(rec_in_->end(), b, b + sizeof r);
    const pmlsm_replay::OutputRecord o =
        pmlsm_replay::make_output(out, ctl_.status(), has_pending_ ? pending_result_ : 255);
    const auto* ob = reinterpret_cast<const unsigned char*>(&o);
    rec_out_->insert(rec_out_->end(), ob, ob + sizeof o);
    has_pending_ = false;
  }
  // The amplifier board: phase a, b from the DAC, c = -(a + b) (star).
  std::array<pmlsm_plant::PhaseCurrents, pmlsm_plant::kMotors> ph{};
  if (out.amplifier_enable) {
    const double k = config().amps_per_dac_code;
    for (std::size_t m = 0; m < pmlsm_plant::kMotors; ++m) {
      const double ia = out.dac_code[2 * m] * k, ib = out.dac_code[2 * m + 1] * k;
      ph[m].abc_A = {ia, ib, -(ia + ib)};
      for (double i : ph[m].abc_A) peak_phase_A_ = std::max(peak_phase_A_, std::abs(i));
    }
  }
  const double v_before = plant_->state()[1];
  plant_->StepPhases(ph, period_s_);
  if (plant_->last_step_saturated()) ++clamp_ticks_;
  if (plant_->state()[0] >= stage_.stage.gap_max_m && v_before > 0.0) touchdown_speed_ = v_before;
  ++tick_;
  g_simulated_s += period_s_;
  if (trace_ != nullptr && tick_ % trace_every_ == 0) {
    const auto& st = ctl_.status();
    const auto y = pose();
    std::fprintf(trace_, "%.4f,%s", t_s(), ps::to_string(st.state));
    for (double v : y) std::fprintf(trace_, ",%.9g", v);
    for (float v : st.pose) std::fprintf(trace_, ",%.9g", static_cast<double>(v));
    for (float v : st.reference) std::fprintf(trace_, ",%.9g", static_cast<double>(v));
    for (float v : st.i_d_A) std::fprintf(trace_, ",%.5g", static_cast<double>(v));
    std::fprintf(trace_, ",%.5g,%.5g\n", static_cast<double>(st.i_q_A[1]), static_cast<double>(st.i_q_A[0]));
  }
}

void PmlsmBench::RunFor(double seconds) {
  const long n = std::lround(seconds / period_s_);
  for (long i = 0; i < n; ++i) Tick();
}

// ---------------------------------------------------------------------------
// Experiments
namespace {

struct Verdict {
  std::string experiment, quantity, kind;  // kind: "spec" (a bound) or "ratio" (bench / paper in a band)
  double bench = 0.0, paper = 0.0, lo = 0.0, hi = 0.0;
  bool pass = false;
  std::string note;
};

struct Context {
  const sp::StageProfile* profile = nullptr;
  std::string dir;  // this experiment's output folder
  std::string name;
  std::vector<std::pair<std::string, double>> metrics;
  std::vector<Verdict>* verdicts = nullptr;
  std::string error;
  std::FILE* trace = nullptr;
  void metric(const std::string& k, double v) { metrics.emplace_back(k, v); }
  void spec(const std::string& q, double bench, double bound, bool below = true, const std::string& note = "") {
    Verdict v{name, q, "spec", bench, bound, below ? -HUGE_VAL : bound, below ? bound : HUGE_VAL,
              below ? bench < bound : bench > bound, note};
    verdicts->push_back(v);
  }
  void ratio(const std::string& q, double bench, double paper, double lo, double hi, const std::string& note = "") {
    const double r = bench / paper;
    verdicts->push_back({name, q, "ratio", bench, paper, lo, hi, r >= lo && r <= hi, note});
  }
};

bool Start(Context& c, PmlsmBench& b, const Variant& v) {
  if (!b.Init(*c.profile, v, &c.error)) return false;
  b.StartTrace(c.trace, std::max(1, static_cast<int>(std::lround(0.01 / b.period_s()))));
  MotionCommand lev;
  lev.type = MotionType::kLevitate;
  b.Tick();  // a first sample: the kernel needs a pose
  if (b.Command(lev) != CommandResult::kAccepted) {
    c.error = "levitate refused";
    return false;
  }
  for (int i = 0; i < 20000 && b.status().state != ps::StageState::kReady; ++i) b.Tick();
  if (b.status().state != ps::StageState::kReady) {
    c.error = std::string("not ready after lift-off: ") + ps::to_string(b.status().state);
    return false;
  }
  b.RunFor(1.0);
  return true;
}

bool MoveTo(Context& c, PmlsmBench& b, const std::array<double, 5>& target) {
  for (int a = 0; a < 5; ++a) {
    if (std::abs(static_cast<double>(b.status().reference[a]) - target[static_cast<std::size_t>(a)]) < 1e-9) continue;
    MotionCommand m;
    m.type = MotionType::kMoveTo;
    m.axis = static_cast<Axis>(a);
    m.target = static_cast<float>(target[static_cast<std::size_t>(a)]);
    m.velocity = b.config().max_ramp_speed[a];
    const CommandResult r = b.Command(m);
    if (r != CommandResult::kAccepted) {
      c.error = std::string("move to the start refused: ") + kernel::to_string(r);
      return false;
    }
  }
  for (int i = 0; i < 200000 && b.status().motion_active; ++i) b.Tick();
  b.RunFor(3.0);
  return b.status().state == ps::StageState::kReady;
}

struct StepMeasure {
  double overshoot = 0.0;    // fraction of the step
  double t_s = 0.0;          // within 0.1 mm / 0.1 mrad for good
  double t_enc = 0.0;        // the encoder reads within one count for good
  double final_error = 0.0;  // true, at the end
};

StepMeasure MeasureStep(Context& c, PmlsmBench& b, int axis, double step, double after_s) {
  MotionCommand m;
  m.type = MotionType::kStep;
  m.axis = static_cast<Axis>(axis);
  m.delta = static_cast<float>(step);
  const double target = static_cast<double>(b.status().reference[axis]) + step;
  const CommandResult r = b.Command(m);
  StepMeasure s;
  if (r != CommandResult::kAccepted) {
    c.error = std::string("step refused: ") + kernel::to_string(r);
    return s;
  }
  const bool rotation = axis >= 3;
  const double band = rotation ? 0.1e-3 : 0.1e-3;
  const double count = b.config().encoder_resolution[axis];
  const double t0 = b.t_s();
  double peak = 0.0;
  const long n = std::lround(after_s / b.period_s());
  for (long i = 0; i < n; ++i) {
    b.Tick();
    const double t = b.t_s() - t0;
    const double v = b.pose()[static_cast<std::size_t>(axis)];
    peak = std::max(peak, (v - target) / step);
    if (std::abs(v - target) >= band) s.t_s = t;
    const double meas = static_cast<double>(b.status().pose[axis]);
    if (std::abs(meas - target) > count * 1.5) s.t_enc = t;  // readings are whole counts: +-1 passes
    s.final_error = std::abs(v - target);
  }
  s.overshoot = std::max(0.0, peak);
  return s;
}

// Table III's three specifications on one step.
void TableIII(Context& c, const std::string& what, const StepMeasure& s) {
  c.spec(what + " overshoot (Table III < 30 %)", 100.0 * s.overshoot, 30.0);
  c.spec(what + " t_s to 0.1 mm/mrad (Table III < 3 s)", s.t_s, 3.0);
  c.spec(what + " t_enc to one count (Table III < 10 s)", s.t_enc, 10.0);
}

void StepMetrics(Context& c, const std::string& prefix, const StepMeasure& s) {
  c.metric(prefix + "overshoot_percent", 100.0 * s.overshoot);
  c.metric(prefix + "settling_time_s", s.t_s);
  c.metric(prefix + "encoder_time_s", s.t_enc);
  c.metric(prefix + "final_error", s.final_error);
}

const std::array<double, 5> kHome{25e-3, 0, 0, 0, 0};

bool GapStep7(Context& c) {
  PmlsmBench b;
  Variant v;
  v.rotation_loops = false;  // as the paper's 3-DOF tests
  if (!Start(c, b, v)) return false;
  if (!MoveTo(c, b, {20e-3, 0, 0, 0, 0})) return false;
  const StepMeasure s = MeasureStep(c, b, 0, 7e-3, 10.0);
  if (!c.error.empty()) return false;
  StepMetrics(c, "", s);
  c.metric("peak_phase_current_A", b.peak_phase_current_A());
  c.metric("amplifier_clamp_ticks", static_cast<double>(b.amplifier_clamp_ticks()));
  TableIII(c, "gap 20->27 mm", s);
  c.ratio("gap 20->27 mm overshoot vs Fig. 4 (14.3 %)", 100.0 * s.overshoot, 14.3, 0.5, 2.0);
  c.ratio("gap 20->27 mm t_enc vs Fig. 4 (about 5 s)", s.t_enc, 5.0, 0.5, 2.0);
  return true;
}

bool GapSteps5(Context& c) {
  PmlsmBench b;
  Variant v;
  v.rotation_loops = false;
  if (!Start(c, b, v)) return false;
  const double legs[][2] = {{20e-3, 5e-3}, {25e-3, 5e-3}, {30e-3, -5e-3}, {25e-3, -5e-3}};
  for (const auto& l : legs) {
    if (!MoveTo(c, b, {l[0], 0, 0, 0, 0})) return false;
    const StepMeasure s = MeasureStep(c, b, 0, l[1], 10.0);
    if (!c.error.empty()) return false;
    char what[64];
    std::snprintf(what, sizeof what, "gap %.0f->%.0f mm", l[0] * 1e3, (l[0] + l[1]) * 1e3);
    char prefix[64];
    std::snprintf(prefix, sizeof prefix, "gap_%.0f_to_%.0f_mm_", l[0] * 1e3, (l[0] + l[1]) * 1e3);
    StepMetrics(c, prefix, s);
    TableIII(c, what, s);
  }
  return true;
}

bool HorizontalStep(Context& c, int axis, bool antiwindup, StepMeasure* out) {
  PmlsmBench b;
  Variant v;
  v.rotation_loops = false;
  v.antiwindup = antiwindup;
  if (!Start(c, b, v)) return false;
  std::array<double, 5> start = kHome;
  start[static_cast<std::size_t>(axis)] = -15e-3;
  if (!MoveTo(c, b, start)) return false;
  *out = MeasureStep(c, b, axis, 30e-3, 10.0);
  if (!c.error.empty()) return false;
  StepMetrics(c, "", *out);
  c.metric("amplifier_clamp_ticks", static_cast<double>(b.amplifier_clamp_ticks()));
  return true;
}

bool XStep30(Context& c) {
  StepMeasure s;
  if (!HorizontalStep(c, 1, true, &s)) return false;
  TableIII(c, "x -15->+15 mm", s);
  return true;
}

bool ZStep30(Context& c) {
  StepMeasure s;
  if (!HorizontalStep(c, 2, true, &s)) return false;
  TableIII(c, "z -15->+15 mm", s);
  return true;
}

bool AntiWindup(Context& c) {
  StepMeasure on, off;
  if (!HorizontalStep(c, 1, true, &on)) return false;
  Context scratch = c;
  scratch.metrics.clear();
  if (!HorizontalStep(scratch, 1, false, &off)) {
    c.error = scratch.error;
    return false;
  }
  c.metrics.clear();
  StepMetrics(c, "with_antiwindup_", on);
  StepMetrics(c, "without_antiwindup_", off);
  c.spec("x 30 mm step: t_s with (17) minus without (s)", on.t_s - off.t_s, 1e-9, true,
         "(17) must not settle later");
  c.spec("x 30 mm step: overshoot with (17) minus without (points)", 100.0 * (on.overshoot - off.overshoot), 1e-9,
         true, "(17) must not overshoot more");
  return true;
}

bool ThetaStep(Context& c, double start, double step, bool ten) {
  PmlsmBench b;
  Variant v;
  if (!Start(c, b, v)) return false;
  if (!MoveTo(c, b, {25e-3, 0, 0, 0, start})) return false;
  const StepMeasure s = MeasureStep(c, b, 4, step, 10.0);
  if (!c.error.empty()) return false;
  StepMetrics(c, "", s);
  char what[64];
  std::snprintf(what, sizeof what, "theta %.0f->%.0f mrad", start * 1e3, (start + step) * 1e3);
  TableIII(c, what, s);
  if (ten) {
    c.ratio(std::string(what) + " overshoot vs Fig. 5 (22 %)", 100.0 * s.overshoot, 22.0, 0.5, 2.0,
            "the paper blames the vertical guides for its 10 mrad transient; ours are ideal springs");
    c.spec(std::string(what) + " t_s to 0.1 mrad (Fig. 5: < 5 s)", s.t_s, 5.0);
  }
  return true;
}
bool Theta5(Context& c) { return ThetaStep(c, 0.0, 5e-3, false); }
bool Theta10(Context& c) { return ThetaStep(c, -5e-3, 10e-3, true); }

struct TrackingOutcome {
  std::array<double, 5> mean_abs_meas{}, mean_abs_true{};
};

bool Tracking(Context& c, const Variant& v, bool four_dof, TrackingOutcome* o) {
  PmlsmBench b;
  if (!Start(c, b, v)) return false;
  const double w = 1.5 * kPi;
  // x1 = 5 mm sin(wt - pi/2) + 25 mm, x3 = 30 mm sin(wt - pi/2), x5 = 30 mm sin(wt), x9 = 10 mrad sin(wt).
  struct S {
    int axis;
    double center, amplitude, phase;
  };
  std::vector<S> sines{{0, 25e-3, 5e-3, -kPi / 2}, {1, 0.0, 30e-3, -kPi / 2}, {2, 0.0, 30e-3, 0.0}};
  if (four_dof) sines.push_back({4, 0.0, 10e-3, 0.0});
  if (!MoveTo(c, b, {20e-3, -30e-3, 0, 0, 0})) return false;
  for (const S& s : sines) {
    MotionCommand m;
    m.type = MotionType::kSinusoid;
    m.axis = static_cast<Axis>(s.axis);
    m.center = static_cast<float>(s.center);
    m.amplitude = static_cast<float>(s.amplitude);
    m.omega_rad_per_s = static_cast<float>(w);
    m.phase_rad = static_cast<float>(s.phase);
    const CommandResult r = b.Command(m);
    if (r != CommandResult::kAccepted) {
      c.error = std::string("sinusoid refused: ") + kernel::to_string(r);
      return false;
    }
  }
  b.RunFor(10.0);
  const long n = std::lround(60.0 / b.period_s());
  for (long i = 0; i < n; ++i) {
    // The true pose at the instant the encoders sampled it, against that
    // tick's reference (after the tick the plant is one period further).
    const auto y = b.pose();
    b.Tick();
    for (std::size_t a = 0; a < 5; ++a) {
      const double r = static_cast<double>(b.status().reference[a]);
      o->mean_abs_true[a] += std::abs(y[a] - r);
      o->mean_abs_meas[a] += std::abs(static_cast<double>(b.status().pose[a]) - r);
    }
    if (b.status().state != ps::StageState::kReady) {
      c.error = std::string("left Ready while tracking: ") + kernel::to_string(b.status().fault);
      return false;
    }
  }
  for (std::size_t a = 0; a < 5; ++a) {
    o->mean_abs_true[a] /= static_cast<double>(n);
    o->mean_abs_meas[a] /= static_cast<double>(n);
    c.metric(std::string("mean_abs_error_") + kAxisName[a] + "_measured", o->mean_abs_meas[a]);
    c.metric(std::string("mean_abs_error_") + kAxisName[a] + "_true", o->mean_abs_true[a]);
  }
  c.metric("peak_phase_current_A", b.peak_phase_current_A());
  return true;
}

bool Tracking3(Context& c) {
  Variant v;
  v.rotation_loops = false;
  TrackingOutcome o;
  if (!Tracking(c, v, false, &o)) return false;
  const char* note = "encoder-measured mean |e| over 60 s after 10 s, as the paper";
  c.ratio("3-DOF y (gap) mean |e| vs Fig. 6 (33.04 um)", o.mean_abs_meas[0] * 1e6, 33.04, 0.0, 1.5, note);
  c.ratio("3-DOF x mean |e| vs Fig. 6 (78.33 um)", o.mean_abs_meas[1] * 1e6, 78.33, 0.0, 1.5, note);
  c.ratio("3-DOF z mean |e| vs Fig. 6 (68.25 um)", o.mean_abs_meas[2] * 1e6, 68.25, 0.0, 1.5, note);
  return true;
}

bool Tracking4(Context& c) {
  Variant v;
  TrackingOutcome o;
  if (!Tracking(c, v, true, &o)) return false;
  const char* note = "encoder-measured mean |e| over 60 s after 10 s, as the paper";
  c.ratio("4-DOF y (gap) mean |e| vs Figs. 7-8 (47.03 um)", o.mean_abs_meas[0] * 1e6, 47.03, 0.0, 1.5, note);
  c.ratio("4-DOF x mean |e| vs Figs. 7-8 (77.98 um)", o.mean_abs_meas[1] * 1e6, 77.98, 0.0, 1.5, note);
  c.ratio("4-DOF z mean |e| vs Figs. 7-8 (76.85 um)", o.mean_abs_meas[2] * 1e6, 76.85, 0.0, 1.5, note);
  c.ratio("4-DOF theta mean |e| vs Figs. 7-8 (123.9 urad)", o.mean_abs_meas[4] * 1e6, 123.9, 0.0, 1.5, note);
  return true;
}

// Ours, separate from the reproduction: (2) inverted with its i_d^2 term, a
// 5 kHz servo and encoders ten times finer (1 um, 2 urad), all set in the
// profile / kernel configuration. Reported, not judged against the paper.
bool OursTracking(Context& c) {
  Variant v;
  v.exact_vertical_inverse = true;
  v.servo_rate_Hz = 5000.0;
  v.encoder_scale = 0.1;
  TrackingOutcome o;
  if (!Tracking(c, v, true, &o)) return false;
  c.spec("ours 4-DOF y (gap) mean |e| (um), reported", o.mean_abs_true[0] * 1e6, 47.03, true,
         "true error; below the paper's 47.03 um");
  c.spec("ours 4-DOF x mean |e| (um), reported", o.mean_abs_true[1] * 1e6, 77.98, true, "true error");
  c.spec("ours 4-DOF z mean |e| (um), reported", o.mean_abs_true[2] * 1e6, 76.85, true, "true error");
  c.spec("ours 4-DOF theta mean |e| (urad), reported", o.mean_abs_true[4] * 1e6, 123.9, true, "true error");
  return true;
}

// The closed-loop poles of the loop the kernel runs: after (12) each axis
// is e'' = w; the plant's ZOH over one tick, the kernel's derivative filter,
// its ZOH internal model and the gains it received, as one discrete system;
// its eigenvalues mapped back by s = ln(z) / T and compared with the paper's.
bool Poles(Context& c) {
  PmlsmBench b;
  if (!b.Init(*c.profile, Variant{}, &c.error)) return false;
  const ps::PmlsmKernelConfig& k = b.config();
  const double T = 1.0 / static_cast<double>(k.servo_rate_Hz);
  for (int a = 0; a < 5; ++a) {
    if (!k.axis[a].closed) continue;
    double K[5];
    for (int i = 0; i < 5; ++i) K[i] = static_cast<double>(k.axis[a].Ks[i]);
    const double wf = static_cast<double>(k.derivative_filter_rad_per_s);
    const double al = static_cast<double>(k.derivative_filter_alpha);
    // State [e v xi1 xi2 xi3 f]; w = K0 e + K1 wf (e - f) + K2 xi1 + K3 xi2 + K4 xi3 + xi1.
    Eigen::RowVectorXd wrow = Eigen::RowVectorXd::Zero(6);
    wrow << K[0] + K[1] * wf, 0.0, K[2] + 1.0, K[3], K[4], -K[1] * wf;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6, 6);
    A(0, 0) = 1.0;
    A(0, 1) = T;
    A.row(0) += 0.5 * T * T * wrow;
    A(1, 1) = 1.0;
    A.row(1) += T * wrow;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) A(2 + i, 2 + j) = static_cast<double>(k.xi_Ad_minus_I[i][j]) + (i == j ? 1.0 : 0.0);
      A(2 + i, 0) = static_cast<double>(k.xi_Bd[i][2]);
    }
    A(5, 0) = al;
    A(5, 5) = 1.0 - al;
    const Eigen::VectorXcd z = A.eigenvalues();
    std::vector<std::complex<double>> s;
    for (int i = 0; i < z.size(); ++i) s.push_back(std::log(z(i)) / T);
    std::sort(s.begin(), s.end(), [](auto x, auto y) { return std::abs(x) < std::abs(y); });
    const auto paper = cd::PaperPoles(static_cast<cd::Axis>(a));
    // The four slow poles (the internal model's and the slow plant pair)
    // each against the nearest pole of the loop; the fast real pole sits
    // next to the derivative filter's pole (2 pi 50 Hz, ours) and the two
    // become a pair: reported, not judged (the paper's filter is not printed).
    std::vector<bool> used(s.size(), false);
    double worst = 0.0;
    int idx = 0;
    for (const auto& pp : paper) {
      if (pp.imag() == 0.0) continue;
      std::size_t bi = 0;
      double bd = HUGE_VAL;
      for (std::size_t i = 0; i < s.size(); ++i) {
        if (!used[i] && std::abs(s[i] - pp) < bd) {
          bd = std::abs(s[i] - pp);
          bi = i;
        }
      }
      used[bi] = true;
      worst = std::max(worst, bd / std::abs(pp));
      c.metric(std::string(kAxisName[a]) + "_slow_pole" + std::to_string(idx) + "_re", s[bi].real());
      c.metric(std::string(kAxisName[a]) + "_slow_pole" + std::to_string(idx++) + "_im", s[bi].imag());
    }
    double fastest = 0.0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (!used[i]) fastest = std::max(fastest, std::abs(s[i]));
    }
    const double design_err = cd::WorstRelativePoleError(b.design().poles[static_cast<std::size_t>(a)], paper);
    c.metric(std::string(kAxisName[a]) + "_design_pole_error", design_err);
    c.metric(std::string(kAxisName[a]) + "_slow_pole_error", worst);
    c.metric(std::string(kAxisName[a]) + "_fast_poles_abs_max_rad_per_s", fastest);
    c.spec(std::string(kAxisName[a]) + ": design poles (gains from the profile's weights) vs printed, worst rel. error",
           design_err, 1e-3);
    c.spec(std::string(kAxisName[a]) + ": the 1 kHz loop's four slow poles vs printed, worst rel. error", worst, 0.15,
           true, "ZOH plant + the kernel's discrete internal model, derivative filter and gains");
  }
  return true;
}

bool LiftAndLand(Context& c) {
  PmlsmBench b;
  if (!Start(c, b, Variant{})) return false;
  c.metric("lift_off_time_s", b.t_s());
  MotionCommand land;
  land.type = MotionType::kLand;
  if (b.Command(land) != CommandResult::kAccepted) {
    c.error = "land refused";
    return false;
  }
  for (int i = 0; i < 20000 && b.status().state != ps::StageState::kLanded; ++i) b.Tick();
  b.RunFor(0.5);
  c.metric("touchdown_speed_m_per_s", b.touchdown_speed_m_per_s());
  c.spec("landed", b.status().state == ps::StageState::kLanded ? 1.0 : 0.0, 0.5, false);
  c.spec("touchdown speed (m/s) below the profile's landing speed", b.touchdown_speed_m_per_s(),
         c.profile->limits.landing_speed_m_per_s);
  return true;
}

// Set-points outside the operating range (1) are refused with a result code
// and change nothing; saturation alone is not a fault.
bool BadInput(Context& c) {
  PmlsmBench b;
  if (!Start(c, b, Variant{})) return false;
  const auto before = b.status();
  struct Case {
    const char* what;
    MotionCommand m;
    CommandResult expect;
  };
  auto step = [](int a, float d) {
    MotionCommand m;
    m.type = MotionType::kStep;
    m.axis = static_cast<Axis>(a);
    m.delta = d;
    return m;
  };
  auto move = [](int a, float t, float v) {
    MotionCommand m;
    m.type = MotionType::kMoveTo;
    m.axis = static_cast<Axis>(a);
    m.target = t;
    m.velocity = v;
    return m;
  };
  MotionCommand sine;
  sine.type = MotionType::kSinusoid;
  sine.axis = Axis::kGap;
  sine.center = 25e-3f;
  sine.amplitude = 6e-3f;
  sine.omega_rad_per_s = 4.7f;
  MotionCommand nan_step = step(1, NAN);
  const Case cases[] = {
      {"gap reference 17 mm (below the 18 mm stop)", move(0, 17e-3f, 5e-3f), CommandResult::kRefusedOutOfRange},
      {"gap reference 19 mm (outside (1): 20..30 mm)", move(0, 19e-3f, 5e-3f), CommandResult::kRefusedOutOfRange},
      {"gap step to 31 mm", step(0, 6e-3f), CommandResult::kRefusedOutOfRange},
      {"x step to 40 mm", step(1, 40e-3f), CommandResult::kRefusedOutOfRange},
      {"theta step to 12 mrad", step(4, 12e-3f), CommandResult::kRefusedOutOfRange},
      {"gap sinusoid 25 +- 6 mm", sine, CommandResult::kRefusedOutOfRange},
      {"x step NaN", nan_step, CommandResult::kRefusedOutOfRange},
      {"x move at 1 m/s", move(1, 10e-3f, 1.0f), CommandResult::kRefusedBadProfile},
  };
  int ok = 0;
  for (const Case& k : cases) {
    const CommandResult r = b.Command(k.m);
    const bool pass = r == k.expect;
    ok += pass;
    c.metric(std::string("refused: ") + k.what, static_cast<double>(static_cast<int>(r)));
  }
  b.RunFor(1.0);
  bool unchanged = true;
  for (int a = 0; a < 5; ++a) unchanged = unchanged && b.status().reference[a] == before.reference[a];
  c.spec("bad set-points refused with their result code (count)", ok, static_cast<double>(std::size(cases)) - 0.5,
         false);
  c.spec("references unchanged after the refused commands", unchanged ? 1.0 : 0.0, 0.5, false);
  c.spec("still levitated (no fault)", b.status().state == ps::StageState::kReady ? 1.0 : 0.0, 0.5, false);
  return true;
}

struct Experiment {
  const char* name;
  const char* title;
  bool (*run)(Context&);
};

const Experiment kExperiments[] = {
    {"poles", "closed-loop poles of the kernel's 1 kHz loops vs Section IV-A", Poles},
    {"lift_off_and_land", "lift-off from the stops to 25 mm and landing", LiftAndLand},
    {"gap_step_7mm", "Fig. 4: air gap 20 -> 27 mm, 3-DOF (Table III)", GapStep7},
    {"gap_steps_5mm", "Table III: 5 mm gap steps within [20, 30] mm", GapSteps5},
    {"x_step_30mm", "Table III: X -15 -> +15 mm", XStep30},
    {"z_step_30mm", "Table III: Z -15 -> +15 mm", ZStep30},
    {"antiwindup_x_30mm", "(17) on and off on the 30 mm X step", AntiWindup},
    {"theta_step_5mrad", "Table III: Z rotation 0 -> 5 mrad", Theta5},
    {"theta_step_10mrad", "Fig. 5: Z rotation -5 -> +5 mrad", Theta10},
    {"tracking_3dof", "Fig. 6: the 3-DOF ellipse, mean |e| over 60 s", Tracking3},
    {"tracking_4dof", "Figs. 7-8: 4-DOF with Z rotation, mean |e| over 60 s", Tracking4},
    {"bad_input", "set-points outside (1) refused, nothing changed", BadInput},
    {"ours_tracking_4dof", "ours: exact (2) inverse, 5 kHz, 1 um encoders (not the paper's)", OursTracking},
};

void WriteJson(const std::string& path, const Context& c) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return;
  std::fprintf(f, "{\n  \"experiment\": \"%s\",\n  \"profile\": \"%s\"", c.name.c_str(), c.profile->name);
  for (const auto& [k, v] : c.metrics) std::fprintf(f, ",\n  \"%s\": %.9g", k.c_str(), v);
  std::fprintf(f, "\n}\n");
  std::fclose(f);
}

}  // namespace

void list_experiments() {
  for (const Experiment& e : kExperiments) std::printf("  %-28s %s\n", e.name, e.title);
}

int suite_main(const sp::StageProfile& profile, const std::string& out_dir, const std::string& only) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double sim0 = PmlsmBench::total_simulated_s();
  std::vector<Verdict> verdicts;
  int failed_runs = 0, ran = 0;
  for (const Experiment& e : kExperiments) {
    if (!only.empty() && only != e.name) continue;
    ++ran;
    Context c;
    c.profile = &profile;
    c.name = e.name;
    c.dir = (fs::path(out_dir) / e.name).string();
    c.verdicts = &verdicts;
    fs::create_directories(c.dir);
    c.trace = std::fopen((fs::path(c.dir) / "trace.csv").string().c_str(), "w");
    std::printf("== %s: %s\n", e.name, e.title);
    std::fflush(stdout);
    const bool ok = e.run(c);
    if (c.trace != nullptr) std::fclose(c.trace);
    if (!ok) {
      std::printf("   FAILED: %s\n", c.error.c_str());
      ++failed_runs;
    }
    c.metric("ran", ok ? 1.0 : 0.0);
    WriteJson((fs::path(c.dir) / "metrics.json").string(), c);
  }
  if (ran == 0) {
    std::fprintf(stderr, "maglev-hil: no experiment '%s' for %s; `maglev-hil list --profile %s`:\n", only.c_str(),
                 profile.name, profile.name);
    list_experiments();
    return 2;
  }
  std::printf("\n%-20s %-62s %12s %10s %14s %s\n", "experiment", "quantity", "bench", "paper", "verdict", "");
  int failed = 0;
  std::FILE* j = std::fopen((fs::path(out_dir) / "verdicts.json").string().c_str(), "w");
  if (j != nullptr) std::fprintf(j, "[\n");
  for (std::size_t i = 0; i < verdicts.size(); ++i) {
    const Verdict& v = verdicts[i];
    char verdict[64];
    if (v.kind == "ratio") {
      std::snprintf(verdict, sizeof verdict, "%.2fx [%.2g,%.2g] %s", v.bench / v.paper, v.lo, v.hi,
                    v.pass ? "ok" : "OUT");
    } else {
      std::snprintf(verdict, sizeof verdict, "%s %.3g %s", std::isinf(v.lo) ? "<" : ">", v.paper,
                    v.pass ? "ok" : "FAIL");
    }
    std::printf("%-20s %-62s %12.4g %10.4g %14s\n", v.experiment.c_str(), v.quantity.c_str(), v.bench, v.paper,
                verdict);
    failed += !v.pass;
    if (j != nullptr) {
      std::fprintf(j,
                   "  {\"experiment\": \"%s\", \"quantity\": \"%s\", \"kind\": \"%s\", \"bench\": %.9g, "
                   "\"paper\": %.9g, \"pass\": %s, \"note\": \"%s\"}%s\n",
                   v.experiment.c_str(), v.quantity.c_str(), v.kind.c_str(), v.bench, v.paper,
                   v.pass ? "true" : "false", v.note.c_str(), i + 1 < verdicts.size() ? "," : "");
    }
  }
  if (j != nullptr) {
    std::fprintf(j, "]\n");
    std::fclose(j);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double sim = PmlsmBench::total_simulated_s() - sim0;
  std::printf("\n%d experiment(s), %d failed to run; %zu verdicts, %d outside their band\n", ran, failed_runs,
              verdicts.size(), failed);
  std::printf("simulated %.1f s in %.2f s wall: %.0fx real time\n", sim, wall, wall > 0.0 ? sim / wall : 0.0);
  return failed_runs == 0 && failed == 0 ? 0 : 1;
}

int record_main(const sp::StageProfile& profile, const std::string& vectors, const std::string& outputs) {
  PmlsmBench b;
  std::string why;
  if (!b.Init(profile, Variant{}, &why)) {
    std::fprintf(stderr, "record-pmlsm: %s\n", why.c_str());
    return 2;
  }
  std::vector<unsigned char> in, out;
  b.StartRecording(&in, &out);
  auto cmd = [&](MotionCommand m) { b.Command(m); };
  b.Tick();
  MotionCommand m;
  m.type = MotionType::kLevitate;
  cmd(m);
  for (int i = 0; i < 20000 && b.status().state != ps::StageState::kReady; ++i) b.Tick();
  b.RunFor(0.5);
  // A step on every axis, a 4-DOF sinusoid, a refused command, landing.
  const float steps[5] = {2e-3f, 10e-3f, -10e-3f, 1e-3f, 5e-3f};
  for (int a = 0; a < 5; ++a) {
    m = MotionCommand{};
    m.type = MotionType::kStep;
    m.axis = static_cast<Axis>(a);
    m.delta = steps[a];
    cmd(m);
    b.RunFor(1.5);
  }
  m = MotionCommand{};
  m.type = MotionType::kMoveTo;
  m.axis = Axis::kGap;
  m.target = 17e-3f;  // refused
  m.velocity = 1e-3f;
  cmd(m);
  const float centers[5] = {25e-3f, 0.0f, 0.0f, 0.0f, 0.0f};
  const float amps[5] = {2e-3f, 10e-3f, 10e-3f, 0.0f, 5e-3f};
  for (int a = 0; a < 5; ++a) {
    if (amps[a] == 0.0f) continue;
    m = MotionCommand{};
    m.type = MotionType::kSinusoid;
    m.axis = static_cast<Axis>(a);
    m.center = centers[a];
    m.amplitude = amps[a];
    m.omega_rad_per_s = 4.71238898f;
    m.phase_rad = 0.5f * static_cast<float>(a);
    cmd(m);
  }
  b.RunFor(3.0);
  m = MotionCommand{};
  m.type = MotionType::kLand;
  cmd(m);
  for (int i = 0; i < 20000 && b.status().state != ps::StageState::kLanded; ++i) b.Tick();
  b.RunFor(0.2);
  const std::uint32_t ticks = static_cast<std::uint32_t>(in.size() / sizeof(pmlsm_replay::InputRecord));
  pmlsm_replay::Header h{};
  std::memcpy(h.magic, pmlsm_replay::kMagic, sizeof h.magic);
  h.config_bytes = sizeof(ps::PmlsmKernelConfig);
  h.tick_count = ticks;
  std::FILE* fv = std::fopen(vectors.c_str(), "wb");
  std::FILE* fo = std::fopen(outputs.c_str(), "wb");
  if (fv == nullptr || fo == nullptr) {
    std::fprintf(stderr, "record-pmlsm: cannot write %s / %s\n", vectors.c_str(), outputs.c_str());
    return 2;
  }
  std::fwrite(&h, sizeof h, 1, fv);
  std::fwrite(&b.config(), sizeof(ps::PmlsmKernelConfig), 1, fv);
  std::fwrite(in.data(), 1, in.size(), fv);
  std::fwrite(out.data(), 1, out.size(), fo);
  std::fclose(fv);
  std::fclose(fo);
  std::printf("record-pmlsm: %s, %u ticks (final state %s)\n", profile.name, ticks,
              ps::to_string(b.status().state));
  return b.status().state == ps::StageState::kLanded ? 0 : 1;
}

int check_profile_main(const sp::StageProfile& profile) {
  cd::PmlsmDesign d;
  std::string why;
  if (!cd::BuildPmlsmKernelConfig(profile, &d, &why)) {
    std::printf("%s: the PMLSM kernel cannot run it: %s\n", profile.name, why.c_str());
    return 1;
  }
  std::printf("%s: iron_core_pmlsm, %g Hz; internal-model regulators, LQR from lqr_weight_h:\n", profile.name,
              static_cast<double>(d.config.servo_rate_Hz));
  for (int a = 0; a < 5; ++a) {
    if (!d.config.axis[a].closed) continue;
    std::printf("  %-6s Ks =", kAxisName[a]);
    for (float k : d.config.axis[a].Ks) std::printf(" %.6g", static_cast<double>(k));
    std::printf("\n         poles =");
    for (const auto& p : d.poles[static_cast<std::size_t>(a)]) std::printf(" (%.3f%+.3fi)", p.real(), p.imag());
    std::printf("\n");
  }
  ps::PmlsmController ctl;
  const ps::PmlsmConfigError e = ctl.apply_config(d.config);
  std::printf("verdict: the kernel %s it%s%s; the bench builds its plant (pmlsm_plant)\n",
              e == ps::PmlsmConfigError::kOk ? "accepts" : "REFUSES", e == ps::PmlsmConfigError::kOk ? "" : ": ",
              e == ps::PmlsmConfigError::kOk ? "" : ps::to_string(e));
  return e == ps::PmlsmConfigError::kOk ? 0 : 1;
}

}  // namespace maglev::bench::pmlsm
