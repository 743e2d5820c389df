// plant-integrator-accuracy: the plant's integrators against a reference, in
// the closed loop (issue 16 item 5, docs/PERFORMANCE.md "Bench speed").
//
//   plant-integrator-accuracy SCENARIO_FILE [REF_SUBSTEPS]
//
// 1. One-tick (local) error: along the reference run, every tick is also
// stepped from the reference's own state with `classic` (2 sub-steps) and
// `fast`; the largest pose difference after one tick is the integrator's own
// error, free of the closed loop.
// 2. Closed loop: runs the scenario in process three times with the same seed (same noise
// sequence): the reference (`integrator = classic`, REF_SUBSTEPS sub-steps per
// tick, default 64), `classic` with the scenario's substeps_per_tick (2), and
// `fast`, recording the plant's TRUE pose after every tick (RunHooks), and
// prints each one's largest |pose - reference pose| per axis (pm, nrad), over
// the whole run and over the levitated part (t >= 3 s: the default
// scenario's first metric window). Speed is measured elsewhere (maglev-hil
// run prints its real-time factor; callgrind).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "maglev/bench/run_hooks.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/scenario/scenario.hpp"

namespace {

using maglev::bench::RunHooks;

using Method = maglev::hil::IntegrationConfig::Method;

void Pose(const maglev::hil::PlantState& s, double out[6]) {
  for (int a = 0; a < 3; ++a) {
    out[a] = s.position_m[a];
    out[3 + a] = s.angles_rad[a];
  }
}

// Records the true pose after every tick. With `local` set (the reference
// run), also the ONE-TICK error of each test integrator: the plant as it was
// before the tick (a copy, random generator included) is stepped through the
// same tick (sample, the same applied command, advance) with the test
// integrator and compared with the reference's state after it.
class TruthRecorder : public RunHooks {
 public:
  struct Test {
    const char* name;
    Method method;
    int substeps;
    double worst[2][6];  // [0]: whole run, [1]: t >= 3 s
  };
  std::vector<double> t_s;
  std::vector<double> pose[6];
  std::vector<Test> local;

  void attach(maglev::can::VirtualBus&) override {}
  void before_tick(std::uint64_t, double, maglev::hil::Plant& plant) override {
    if (!local.empty()) pre_.emplace(plant);
  }
  void on_sensor_sample(std::uint64_t, double, maglev::io::SensorSample*) override {}
  maglev::can::FaultAction on_frame(const maglev::can::CanFrame&, std::uint64_t) override { return {}; }
  void on_actuator(std::uint64_t, double, maglev::io::ActuatorCommand* applied) override { cmd_ = *applied; }
  void after_tick(std::uint64_t, double t, const maglev::hil::Plant& plant,
                  const maglev::kernel::ControllerStatus&) override {
    double ref[6];
    Pose(plant.truth(), ref);
    t_s.push_back(t + plant.tick_s());  // the truth after the tick
    for (int a = 0; a < 6; ++a) pose[a].push_back(ref[a]);
    for (Test& test : local) {
      maglev::hil::Plant p = *pre_;
      p.set_integrator(test.method, test.substeps);
      (void)p.sample();  // the same draws as the reference's tick
      p.apply(cmd_);
      p.advance_tick();
      double got[6];
      Pose(p.truth(), got);
      for (int a = 0; a < 6; ++a) {
        const double e = std::fabs(got[a] - ref[a]);
        test.worst[0][a] = std::max(test.worst[0][a], e);
        if (t >= 3.0) test.worst[1][a] = std::max(test.worst[1][a], e);
      }
    }
  }

 private:
  std::optional<maglev::hil::Plant> pre_;
  maglev::io::ActuatorCommand cmd_{};
};

void PrintWorst(const char* name, const double worst[6]) {
  static const char* kAxis[6] = {"x", "y", "z", "theta_x", "theta_y", "theta_z"};
  std::printf("%-22s", name);
  for (int a = 0; a < 6; ++a) {
    std::printf("  %s %10.4f %s", kAxis[a], a < 3 ? worst[a] * 1e12 : worst[a] * 1e9, a < 3 ? "pm" : "nrad");
  }
  std::printf("\n");
}

bool RunWith(maglev::scenario::Scenario sc, const std::string& integrator, int substeps, TruthRecorder* rec) {
  sc.plant["integrator"] = integrator;
  if (substeps > 0) sc.plant["substeps_per_tick"] = std::to_string(substeps);
  maglev::bench::RunOptions opt;
  opt.verbose = false;
  opt.hooks = rec;
  std::vector<maglev::bench::ScenarioError> errors;
  const auto r = maglev::bench::run(sc, opt, &errors);
  for (const auto& e : errors) std::fprintf(stderr, "%s\n", e.message.c_str());
  return r.has_value() && r->completed;
}

void Report(const char* name, const TruthRecorder& run, const TruthRecorder& ref, double t_from_s) {
  static const char* kAxis[6] = {"x", "y", "z", "theta_x", "theta_y", "theta_z"};
  std::printf("%-22s", name);
  for (int a = 0; a < 6; ++a) {
    double worst = 0.0;
    for (std::size_t i = 0; i < ref.t_s.size() && i < run.t_s.size(); ++i) {
      if (ref.t_s[i] < t_from_s) continue;
      worst = std::max(worst, std::fabs(run.pose[a][i] - ref.pose[a][i]));
    }
    // pm for positions, nrad for angles.
    std::printf("  %s %10.3f %s", kAxis[a], a < 3 ? worst * 1e12 : worst * 1e9, a < 3 ? "pm" : "nrad");
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: plant-integrator-accuracy SCENARIO_FILE [REF_SUBSTEPS]\n");
    return 2;
  }
  const int ref_substeps = argc > 2 ? std::atoi(argv[2]) : 64;
  auto parsed = maglev::scenario::load_scenario_file(argv[1]);
  if (!parsed.ok()) {
    for (const auto& e : parsed.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return 2;
  }
  const maglev::scenario::Scenario sc = *parsed.scenario;
  TruthRecorder ref, classic, fast;
  ref.local = {{"classic (2 sub-steps)", Method::kClassic, 2, {}}, {"fast", Method::kFast, 2, {}}};
  if (!RunWith(sc, "classic", ref_substeps, &ref) || !RunWith(sc, "classic", 0, &classic) ||
      !RunWith(sc, "fast", 0, &fast)) {
    std::fprintf(stderr, "plant-integrator-accuracy: a run failed\n");
    return 1;
  }
  std::printf("one tick from the reference's state, max |true pose - reference (classic, %d sub-steps)| after it\n",
              ref_substeps);
  std::printf("whole run:\n");
  for (const auto& test : ref.local) PrintWorst(("  " + std::string(test.name)).c_str(), test.worst[0]);
  std::printf("levitated, t >= 3 s:\n");
  for (const auto& test : ref.local) PrintWorst(("  " + std::string(test.name)).c_str(), test.worst[1]);
  std::printf("\nclosed loop (each integrator's own run, same seed), max |true pose - reference run's|, %zu ticks\n",
              ref.t_s.size());
  std::printf("whole run:\n");
  Report("  classic (2 sub-steps)", classic, ref, 0.0);
  Report("  fast", fast, ref, 0.0);
  std::printf("levitated, t >= 3 s:\n");
  Report("  classic (2 sub-steps)", classic, ref, 3.0);
  Report("  fast", fast, ref, 3.0);
  return 0;
}
