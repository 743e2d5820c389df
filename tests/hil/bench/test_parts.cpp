// The bench runner's parts on their own: the typed timeline (verbs and
// arguments from the one host-command table), the metrics registry on a
// synthetic trace, the overrides' field-by-field errors.
#include <cmath>
#include <string>
#include <vector>

#include "maglev/bench/metrics_registry.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/scenario/scenario.hpp"

// CppUTest last: its new/delete macros must not meet the STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::bench;

namespace {
scenario::TimelineEntry entry(const std::string& verb, std::vector<std::string> args) {
  scenario::TimelineEntry e;
  e.t_s = 1.0;
  e.line = 12;
  e.verb = verb;
  e.args = std::move(args);
  return e;
}
}  // namespace

TEST_GROUP(Timeline){};

TEST(Timeline, EveryHostCommandIsAVerbWithItsNamedFields) {
  for (const auto& spec : can::kHostCommandSpecs) {
    if (spec.code == can::HostCommandCode::kShutdown) continue;
    std::vector<std::string> args;
    if (spec.takes_axis) args.push_back("y");
    for (int i = 0; i < spec.field_count; ++i) args.push_back(std::to_string(i + 2));  // bare numbers are SI
    TimelineAction a;
    std::string err;
    CHECK_TEXT(parse_action(entry(spec.name, args), &a, &err), (std::string(spec.name) + ": " + err).c_str());
    CHECK_TRUE(a.is(spec.code));
    LONGS_EQUAL(spec.takes_axis ? 1 : 0, a.command.axis);  // kernel::Axis::kY = 1
    can::with_args(spec.code, a.command.args, [&](auto& f) {
      using A = std::remove_reference_t<decltype(f)>;
      for (std::size_t i = 0; i < A::kFields.size(); ++i) DOUBLES_EQUAL(static_cast<double>(i + 2), f.*A::kFields[i].member, 0.0);
    });
    // One argument too few (or one too many): the usage line names every field.
    if (args.empty()) args.push_back("1");
    else args.pop_back();
    CHECK_FALSE(parse_action(entry(spec.name, args), &a, &err));
    CHECK_TRUE(err.find(usage_of(spec.name)) != std::string::npos);
  }
}

TEST(Timeline, SinusoidCarriesItsDurationAndUnitsFollowTheAxis) {
  TimelineAction a;
  std::string err;
  CHECK_TRUE(parse_action(entry("sinusoid", {"x", "2um", "2Hz", "1s"}), &a, &err));
  DOUBLES_EQUAL(2e-6, a.command.args.sinusoid.amplitude, 1e-18);
  DOUBLES_EQUAL(2.0, a.command.args.sinusoid.frequency_Hz, 0.0);
  DOUBLES_EQUAL(1.0, a.command.args.sinusoid.duration_s, 0.0);
  STRCMP_EQUAL("sinusoid x 2um 2Hz 1s", a.text.c_str());
  // A rotation takes an angle, a translation a length.
  CHECK_FALSE(parse_action(entry("step", {"theta_z", "2um"}), &a, &err));
  CHECK_TRUE(parse_action(entry("step", {"theta_z", "2urad"}), &a, &err));
  LONGS_EQUAL(2, a.command.axis);  // kernel::Axis::kThetaZ
  // Sign rules from the table.
  CHECK_FALSE(parse_action(entry("circle", {"6mm", "-2s", "1"}), &a, &err));
  STRCMP_CONTAINS("period_s must be > 0", err.c_str());
  CHECK_FALSE(parse_action(entry("shutdown", {}), &a, &err));
  STRCMP_CONTAINS("unknown command", err.c_str());
}

TEST(Timeline, BenchExciteIsAMultisineOnAOneHertzGrid) {
  TimelineAction a;
  std::string err;
  CHECK_TRUE(parse_action(entry("excite", {"x", "10mA", "5Hz", "200Hz", "3s", "8"}), &a, &err));
  CHECK_TRUE(a.kind == TimelineAction::Kind::kBenchExcite);
  const Multisine m = make_multisine(a);
  CHECK_TRUE(m.freqs.size() >= 2);
  for (double f : m.freqs) DOUBLES_EQUAL(std::round(f), f, 0.0);
  DOUBLES_EQUAL(0.0, m.value(0.5), 0.0);   // before
  DOUBLES_EQUAL(0.0, m.value(4.0), 0.0);   // after
  CHECK_TRUE(std::fabs(m.value(1.3)) > 0.0);
  CHECK_FALSE(parse_action(entry("excite", {"x", "10mA", "5Hz", "2000Hz", "3s"}), &a, &err));
}

TEST_GROUP(MetricsRegistry){};

TEST(MetricsRegistry, StepAndNoiseOnASyntheticTrace) {
  // x holds 0 until t = 1 s, then follows a first-order step to 8 um (tau 10 ms).
  Trace tr;
  const double fs = 2500.0;
  for (int n = 0; n < 5000; ++n) {
    const double t = n / fs;
    tr.t_s.push_back(t);
    for (int i = 0; i < kAxes; ++i) {
      const bool x = i == index(Axis::kX);
      const double ref = x && t >= 1.0 ? 8e-6 : 0.0;
      tr.pose[i].push_back(x && t >= 1.0 ? 8e-6 * (1.0 - std::exp(-(t - 1.0) / 0.01)) : 0.0);
      tr.reference[i].push_back(ref);
      tr.effort_A[i].push_back(0.0);
      tr.disturbance_A[i].push_back(0.0);
    }
    for (int j = 0; j < 8; ++j) { tr.current_A[j].push_back(j == 3 ? 1.5 : 0.0); tr.current_cmd_A[j].push_back(0.0); }
    tr.state.push_back(0);
  }
  auto parsed = scenario::parse_scenario("[scenario]\nname = m\nduration_s = 2\n[timeline]\n1.0 step x 8um\n"
                                         "[metrics]\nstep x 1.0 2.0 s\ncurrents 0 2 c\nnoise y 0.1 0.9 n\n", "m.scenario");
  CHECK_TRUE(parsed.ok());
  std::vector<TimelineAction> actions;
  std::vector<std::string> errs;
  CHECK_TRUE(parse_timeline(*parsed.scenario, &actions, &errs));
  std::map<std::string, double> M;
  std::vector<std::string> warnings;
  compute_metrics(*parsed.scenario, MetricInputs{actions, tr, {}, -1.0, 0.0, 2.0, fs}, &M, &warnings);
  DOUBLES_EQUAL(8e-6, M.at("s_commanded_m"), 1e-15);
  DOUBLES_EQUAL(0.0, M.at("s_overshoot_percent"), 1e-9);
  // 2 % settling of a first-order lag: 4 tau = 40 ms.
  DOUBLES_EQUAL(0.040, M.at("s_settling_time_s"), 0.002);
  DOUBLES_EQUAL(1.5, M.at("c_peak_coil_current_A"), 0.0);
  DOUBLES_EQUAL(0.0, M.at("n_rms_noise_m"), 0.0);
  std::string err;
  MetricSpec spec;
  scenario::MetricRequest bad;
  bad.kind = "wobble";
  CHECK_FALSE(parse_metric(bad, &spec, &err));
  STRCMP_CONTAINS(metric_kinds().c_str(), err.c_str());
}

TEST_GROUP(Overrides){};

namespace {
// A scenario's [controller] lines through apply_overrides: true if all applied.
bool ApplyControllerLines(const char* lines, Overrides* o, std::vector<ScenarioError>* errs) {
  auto parsed = scenario::parse_scenario(std::string("[scenario]\nname = t\nduration_s = 1\n[controller]\n") + lines,
                                         "t.scenario");
  CHECK_TRUE(parsed.ok());
  return apply_overrides(*parsed.scenario, o, errs);
}
}  // namespace

TEST(Overrides, UnknownKeysAndBadValuesAreReportedFieldByField) {
  auto parsed = scenario::parse_scenario(
      "[scenario]\nname = o\nduration_s = 1\n[plant]\nwobble = 3\n[controller]\nx.kp = 12\nq.kp = 1\nz.kq = 2\n",
      "o.scenario");
  CHECK_TRUE(parsed.ok());
  Overrides o;
  std::vector<ScenarioError> errs;
  CHECK_FALSE(apply_overrides(*parsed.scenario, &o, &errs));
  LONGS_EQUAL(3, errs.size());
  DOUBLES_EQUAL(12.0, o.controller.axis[index(Axis::kX)].pid.kp, 0.0);
}

TEST(Overrides, OutputFiltersAreScenarioKeysBoundedByTheirRegisters) {
  auto parsed = scenario::parse_scenario(
      "[scenario]\nname = f\nduration_s = 1\n[controller]\nx.filter1.type = notch\nx.filter1.frequency_Hz = 320Hz\n"
      "x.filter1.q = 5\nx.filter1.depth_dB = 20\nz.filter2.type = low_pass\nz.filter2.frequency_Hz = 0.6kHz\n",
      "f.scenario");
  CHECK_TRUE(parsed.ok());
  Overrides o;
  std::vector<ScenarioError> errs;
  CHECK_TRUE(apply_overrides(*parsed.scenario, &o, &errs));
  const kernel::BiquadConfig& n = o.controller.axis[index(Axis::kX)].filters[0];
  CHECK(n.type == kernel::BiquadType::kNotch);
  DOUBLES_EQUAL(320.0, n.frequency_Hz, 0.0);
  DOUBLES_EQUAL(5.0, n.q, 0.0);
  DOUBLES_EQUAL(20.0, n.depth_dB, 0.0);
  const kernel::BiquadConfig& lp = o.controller.axis[index(Axis::kZ)].filters[1];
  CHECK(lp.type == kernel::BiquadType::kLowPass);
  DOUBLES_EQUAL(600.0, lp.frequency_Hz, 0.0);
  // The kernel takes them (the loop check passes with these filters in the loop).
  kernel::Controller<float> kernel_under_test;
  CHECK(kernel_under_test.apply_config(o.controller) == kernel::ConfigError::kOk);

  // Bad ones, field by field: an unknown type, a depth beyond the register's
  // range, an unknown field, a third stage.
  auto bad = scenario::parse_scenario(
      "[scenario]\nname = g\nduration_s = 1\n[controller]\nx.filter1.type = comb\nx.filter1.depth_dB = 300\n"
      "y.filter2.width = 3\ny.filter3.q = 2\n",
      "g.scenario");
  CHECK_TRUE(bad.ok());
  Overrides o2;
  std::vector<ScenarioError> errs2;
  CHECK_FALSE(apply_overrides(*bad.scenario, &o2, &errs2));
  LONGS_EQUAL(4, errs2.size());
  CHECK(o2.controller.axis[index(Axis::kX)].filters[0].type == kernel::BiquadType::kNone);
}

TEST(Overrides, TheLdsTargetThresholdAndWindowAreLengthsBoundedByTheirRegisters) {
  Overrides o;
  std::vector<ScenarioError> errs;
  CHECK_TRUE(ApplyControllerLines("lds_target_step_min = 2.5um\nlds_target_window = 0.75mm\n", &o, &errs));
  DOUBLES_EQUAL(2.5, o.controller.measurement.lds_target_step_min_um, 1e-6);
  DOUBLES_EQUAL(750.0, o.controller.measurement.lds_target_window_um, 1e-4);
  kernel::Controller<float> kernel_under_test;
  CHECK(kernel_under_test.apply_config(o.controller) == kernel::ConfigError::kOk);
  // Outside the registers' ranges (0.1-1000 um, 1-25000 um): refused, defaults kept.
  Overrides bad;
  std::vector<ScenarioError> bad_errs;
  CHECK_FALSE(ApplyControllerLines("lds_target_step_min = 50nm\nlds_target_window = 30mm\n", &bad, &bad_errs));
  LONGS_EQUAL(2, bad_errs.size());
  STRCMP_CONTAINS("lds.target_step_min's range", bad_errs[0].message.c_str());
  STRCMP_CONTAINS("lds.target_window's range", bad_errs[1].message.c_str());
  DOUBLES_EQUAL(1.0, bad.controller.measurement.lds_target_step_min_um, 0.0);
  DOUBLES_EQUAL(1000.0, bad.controller.measurement.lds_target_window_um, 0.0);
}

// AXIS.loop picks an axis' regulator (sinusoid_imr runs paper 002's
// internal-model regulator on x); any other value is refused by name.
TEST(Overrides, AnAxisLoopIsChosenByName) {
  auto parsed = scenario::parse_scenario(
      "[scenario]\nname = l\nduration_s = 1\n[controller]\nx.loop = internal_model\ntheta_z.loop = pid2dof\n",
      "l.scenario");
  CHECK_TRUE(parsed.ok());
  Overrides o;
  std::vector<ScenarioError> errs;
  CHECK_TRUE(apply_overrides(*parsed.scenario, &o, &errs));
  for (int a = 0; a < kernel::kAxisCount; ++a) {
    CHECK(o.controller.axis[a].type ==
          (a == index(Axis::kX) ? kernel::LoopType::kInternalModel : kernel::LoopType::kPid2Dof));
  }
  static kernel::Controller<float> kernel_under_test;
  CHECK(kernel_under_test.apply_config(o.controller) == kernel::ConfigError::kOk);
  auto bad = scenario::parse_scenario("[scenario]\nname = m\nduration_s = 1\n[controller]\ny.loop = lqr\n", "m.scenario");
  CHECK_TRUE(bad.ok());
  Overrides ob;
  std::vector<ScenarioError> bad_errs;
  CHECK_FALSE(apply_overrides(*bad.scenario, &ob, &bad_errs));
  CHECK_EQUAL(1u, bad_errs.size());
  CHECK(bad_errs[0].message.find("y.loop = lqr: expected pid2dof or internal_model") != std::string::npos);
}

TEST(Overrides, ThePaperPresetIsThePublishedPidsWithoutOurShaping) {
  // Paper 000 (27), (28), (32), (33): the gains as printed, PID on the error
  // (b = c = 1), no acceleration feed-forward, no output filters; AXIS keys
  // after the preset refine it, whatever their order in the file.
  auto parsed = scenario::parse_scenario(
      "[scenario]\nname = p\nduration_s = 1\n[controller]\nx.filter1.type = notch\nx.filter1.frequency_Hz = 320Hz\n"
      "preset = paper\nz.kp = 30000\n",
      "p.scenario");
  CHECK_TRUE(parsed.ok());
  Overrides o;
  std::vector<ScenarioError> errs;
  CHECK_TRUE(apply_overrides(*parsed.scenario, &o, &errs));
  const kernel::KernelConfig d = kernel::default_kernel_config();
  for (int a = 0; a < kernel::kAxisCount; ++a) {
    const kernel::Pid2DofConfig& pid = o.controller.axis[a].pid;
    DOUBLES_EQUAL(1.0, pid.setpoint_weight_p, 0.0);
    DOUBLES_EQUAL(1.0, pid.setpoint_weight_d, 0.0);
    DOUBLES_EQUAL(d.axis[a].pid.ki, pid.ki, 0.0);
    DOUBLES_EQUAL(d.axis[a].pid.kd, pid.kd, 0.0);
  }
  DOUBLES_EQUAL(36000.0, o.controller.axis[index(Axis::kX)].pid.kp, 0.0);   // (27)
  DOUBLES_EQUAL(2400000.0, o.controller.axis[index(Axis::kY)].pid.ki, 0.0);  // (27)
  DOUBLES_EQUAL(300.0, o.controller.axis[index(Axis::kThetaZ)].pid.kp, 0.0); // (28)
  DOUBLES_EQUAL(0.09, o.controller.axis[index(Axis::kThetaX)].pid.kd, 1e-7); // (33), as a float
  DOUBLES_EQUAL(30000.0, o.controller.axis[index(Axis::kZ)].pid.kp, 0.0);    // refined after the preset
  CHECK(o.controller.axis[index(Axis::kX)].filters[0].type == kernel::BiquadType::kNotch);  // refined too
  CHECK_FALSE(o.controller.acceleration_feedforward);
  kernel::Controller<float> kernel_under_test;
  CHECK(kernel_under_test.apply_config(o.controller) == kernel::ConfigError::kOk);

  auto bad = scenario::parse_scenario("[scenario]\nname = q\nduration_s = 1\n[controller]\npreset = fast\n", "q.scenario");
  CHECK_TRUE(bad.ok());
  Overrides o2;
  std::vector<ScenarioError> errs2;
  CHECK_FALSE(apply_overrides(*bad.scenario, &o2, &errs2));
  CHECK(errs2.at(0).message.find("preset = fast: expected default or paper") != std::string::npos);
}
