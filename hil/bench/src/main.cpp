// maglev-hil: the HIL bench. See docs/BENCH.md.
//
//   maglev-hil list [--scenarios DIR]
//   maglev-hil run NAME|FILE --out DIR [--can virtual|IFACE] [--kernel float32|q7.24]
//                  [--mode lockstep|realtime] [--seed N] [--no-plots] [--quiet] [--can-log FILE]
//   maglev-hil suite --out DIR [same options]
//   maglev-hil check NAME|FILE...             parse + validate only
//   maglev-hil profiles                       the stage profiles (hil/profiles)
//   maglev-hil check-profile NAME|FILE        what the controller makes of a profile
//   maglev-hil controller --can IFACE [--kernel K] [--config NAME|FILE] [--out DIR] [--duration S] [--levitate]
//   maglev-hil plant NAME|FILE --can IFACE --out DIR [--controller-record FILE] [--mode lockstep|realtime]
//                  [--lockstep-timeout-ms N] [--seed N] [--no-plots] [--quiet]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "maglev/io/stage_parameters.hpp"
#include "maglev/bench/campaign.hpp"
#include "maglev/bench/metrics_registry.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/bench/pmlsm_bench.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/bench/profile_check.hpp"
#include "maglev/bench/selfstab_suite.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/bench/serve.hpp"
#include "maglev/report/report.hpp"
#include "maglev/scenario/scenario.hpp"

#ifndef MAGLEV_SCENARIO_DIR
#define MAGLEV_SCENARIO_DIR "hil/scenarios"
#endif

namespace {

namespace fs = std::filesystem;
using maglev::bench::RunOptions;

struct Args {
  std::string cmd;
  std::vector<std::string> positional;
  std::string out;
  std::string scenarios = MAGLEV_SCENARIO_DIR;
  RunOptions run;
  bool plots = true;
  bool levitate = false;
  double max_time_s = 0.0;
  std::string config;             // controller: scenario whose [controller]/kernel to apply
  std::string controller_record;  // plant: the controller's record file
  std::uint32_t lockstep_timeout_ms = 200;  // plant, lockstep: wait for actuator frame N
  int seeds = 0;                  // run --seeds N: error seeds 1..N, median and spread
  bool calibrate = false;         // run --calibrate: coupling calibration session first (issue 15)
  std::string error;
};

// An integer option's value within [lo, hi]; otherwise *error says so.
long int_option(const std::string& name, const std::string& v, long lo, long hi, std::string* error) {
  char* end = nullptr;
  const long n = std::strtol(v.c_str(), &end, 10);
  if (end == v.c_str() || *end != '\0' || n < lo || n > hi) {
    *error = name + ": an integer " + std::to_string(lo) + ".." + std::to_string(hi) + ", got '" + v + "'";
  }
  return n;
}

void usage() {
  std::fputs(
      "usage:\n"
      "  maglev-hil list [--scenarios DIR]\n"
      "  maglev-hil run NAME|FILE --out DIR [--can virtual|vcan0] [--kernel float32|q7.24]\n"
      "                 [--mode lockstep|realtime] [--seed N] [--no-plots] [--quiet] [--scenarios DIR]\n"
      "                 [--can-log FILE]   the run's CAN traffic as a candump log (simulated time)\n"
      ,
      stderr);
  std::fputs(maglev::bench::kPlantOptionsUsage, stderr);
  std::fputs(
      "                 [--seeds N]        as-built error seeds 1..N: per paper figure median, spread, ratio\n"
      "                 [--servo-rate HZ]  2500 (default), 5000, 10000 or 20000: the controller's servo rate\n"
      "                                    (re-discretized loops; the plant steps at it; in process only over\n"
      "                                    CAN above the link's budget, docs/CAN.md)\n"
      "                 [--calibrate]      first a coupling calibration session on the same plant (levitate,\n"
      "                                    level, calibrate_coupling), then the scenario with its correction\n"
      "                                    loaded as from the persisted configuration (DIR/calibration/)\n"
      "  maglev-hil suite --out DIR [run options but --can-log]\n"
      "  maglev-hil check NAME|FILE...\n"
      "  maglev-hil record-pmlsm VECTORS OUTPUTS [--profile P]   paper 002's session for the M7 replay\n"
      "  maglev-hil selfstab-schedule --profile P   paper 001's z gain schedule from the plant\n"
      "  maglev-hil profiles                  the stage profiles; run/suite take --profile NAME|FILE\n"
      "  maglev-hil error-terms               the as-built error terms (markdown, docs/PLANT.md)\n"
      "  maglev-hil floor-classes             the named floors (markdown, docs/PLANT.md section 12)\n"
      "  maglev-hil check-profile NAME|FILE   allocation, passive axes, loops, current headroom\n"
      "  maglev-hil campaign --runs N [--seed S] [--jobs J] [--out DIR] [--only I]   randomized faults, judged\n"
      "  maglev-hil controller --can IFACE [--kernel K] [--config NAME|FILE] [--out DIR] [--duration S]\n"
      "                 [--levitate]       (runs until a shutdown host command, SIGTERM/SIGINT or --duration)\n"
      "  maglev-hil plant NAME|FILE --can IFACE --out DIR [--controller-record FILE]\n"
      "                 [--mode lockstep|realtime] [--lockstep-timeout-ms N] [--seed N] [--no-plots] [--quiet]\n"
      "see docs/BENCH.md\n",
      stderr);
}

Args parse_args(int argc, char** argv) {
  Args a;
  if (argc < 2) {
    a.error = "no command";
    return a;
  }
  a.cmd = argv[1];
  for (int i = 2; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&](std::string* dst) {
      if (i + 1 >= argc) {
        a.error = s + " needs a value";
        return false;
      }
      *dst = argv[++i];
      return true;
    };
    std::string v;
    if (s == "--out") {
      value(&a.out);
    } else if (s == "--scenarios") {
      value(&a.scenarios);
    } else if (s == "--can") {
      value(&a.run.can);
    } else if (s == "--can-log") {
      value(&a.run.can_log);
    } else if (s == "--kernel") {
      if (value(&v)) {
        maglev::hil::KernelKind k{};
        if (!maglev::hil::parse_kernel_kind(v, &k)) a.error = "--kernel: expected float32 or q7.24, got '" + v + "'";
        a.run.kernel = k;
      }
    } else if (s == "--mode") {
      if (value(&v)) {
        if (v == "lockstep") a.run.mode = maglev::bench::Mode::kLockstep;
        else if (v == "realtime") a.run.mode = maglev::bench::Mode::kRealtime;
        else a.error = "--mode: expected lockstep or realtime, got '" + v + "'";
      }
    } else if (s == "--profile") {
      if (value(&v)) a.run.profile = v;
    } else if (s == "--seed") {
      if (value(&v)) {
        char* end = nullptr;
        const unsigned long long n = std::strtoull(v.c_str(), &end, 10);
        if (end == v.c_str() || *end != '\0') a.error = s + ": not an integer: '" + v + "'";
        a.run.seed = n;
      }
    } else if (s == "--plant" || s == "--error-seed" || s == "--floor" || s == "--floor-isolator-hz") {
      if (value(&v)) (void)maglev::bench::parse_plant_option(s, v, &a.run.plant_options, &a.error);
    } else if (s == "--servo-rate") {
      if (value(&v)) {
        char* end = nullptr;
        const double r = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0' || !maglev::io::stage::is_supported_servo_rate(r)) {
          a.error = "--servo-rate: " + maglev::bench::offered_servo_rates() + ", got '" + v + "'";
        }
        a.run.servo_rate_Hz = r;
      }
    } else if (s == "--seeds") {
      if (value(&v)) a.seeds = static_cast<int>(int_option(s, v, 1, 100, &a.error));
    } else if (s == "--max-time" || s == "--duration") {
      if (value(&v)) a.max_time_s = std::atof(v.c_str());
    } else if (s == "--config") {
      value(&a.config);
    } else if (s == "--controller-record") {
      value(&a.controller_record);
    } else if (s == "--lockstep-timeout-ms") {
      if (value(&v)) a.lockstep_timeout_ms = static_cast<std::uint32_t>(int_option(s, v, 1, 60000, &a.error));
    } else if (s == "--no-plots") {
      a.plots = false;
    } else if (s == "--quiet") {
      a.run.verbose = false;
    } else if (s == "--calibrate") {
      a.calibrate = true;
    } else if (s == "--levitate") {
      a.levitate = true;
    } else if (!s.empty() && s[0] == '-') {
      a.error = "unknown option " + s;
    } else {
      a.positional.push_back(s);
    }
  }
  return a;
}

std::vector<fs::path> scenario_files(const std::string& dir) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".scenario") out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// NAME (a file in the scenario dir) or a path to a file.
std::string resolve(const std::string& name_or_file, const std::string& dir) {
  if (fs::exists(name_or_file) && fs::is_regular_file(name_or_file)) return name_or_file;
  const fs::path p = fs::path(dir) / (name_or_file + ".scenario");
  return p.string();
}

bool load(const std::string& name_or_file, const std::string& dir, maglev::scenario::Scenario* out) {
  const std::string path = resolve(name_or_file, dir);
  if (!fs::exists(path)) {
    std::fprintf(stderr, "maglev-hil: no scenario '%s' (not a file, and no %s); try 'maglev-hil list'\n",
                 name_or_file.c_str(), path.c_str());
    return false;
  }
  auto r = maglev::scenario::load_scenario_file(path);
  if (!r.ok()) {
    for (const auto& e : r.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
    return false;
  }
  const auto errs = maglev::bench::validate(*r.scenario);
  for (const auto& e : errs) std::fprintf(stderr, "%s\n", e.message.c_str());
  if (!errs.empty()) return false;
  *out = *r.scenario;
  return true;
}

std::string primary_of(const maglev::scenario::Scenario& sc) {
  const auto it = sc.scenario.find("primary");
  return it == sc.scenario.end() ? "x" : it->second == "thx" ? "theta_x" : it->second == "thy" ? "theta_y"
       : it->second == "thz" ? "theta_z" : it->second;
}

// Writes a run's results into dir and prints its summary; 0 when it completed.
int report_run(const maglev::scenario::Scenario& sc, const maglev::bench::RunResult& r, const Args& a,
               const std::string& dir) {
  std::string err;
  const bool wrote = maglev::report::write_run(r, dir, primary_of(sc), a.plots, &err);
  if (!wrote) std::fprintf(stderr, "maglev-hil: %s\n", err.c_str());
  std::fputs(maglev::report::format_table(r).c_str(), stdout);
  for (const auto& w : r.warnings) std::printf("  warning: %s\n", w.c_str());
  std::printf("  final state %s, fault %s; %llu ticks in %.2f s wall: real-time factor %.1f", r.final_state.c_str(),
              r.fault.c_str(), static_cast<unsigned long long>(r.ticks), r.wall_s, r.real_time_factor);
  if (r.cpu_s > 0) {
    // simulated s = factor x wall s
    std::printf(" (%.1f on the loop's CPU time, %.2f s)", r.real_time_factor * r.wall_s / r.cpu_s, r.cpu_s);
  }
  std::printf(", bus load %.1f %%\n", r.bus_load_percent);
  std::printf("  results in %s: metrics.json, trace.csv, commands.txt", dir.c_str());
  if (a.plots && wrote) std::printf(", plots pose.png and currents.png");
  std::printf("\n");
  return r.completed && wrote ? 0 : 1;
}

// run --calibrate: the calibration session on the scenario's plant and
// controller (same error set and noise seed): levitate, level the platen
// (as the ccq scenarios do), calibrate_coupling, hold. Its correction, if
// the kernel kept one, is what the scenario run then boots with.
constexpr double kCalibrateAt_s = 4.5;
constexpr double kCalibrationSession_s = 36.0;
maglev::scenario::Scenario calibration_session(const maglev::scenario::Scenario& sc) {
  maglev::scenario::Scenario c = sc;
  c.scenario["name"] = sc.name() + "_calibration";
  c.scenario["title"] = "coupling calibration session (--calibrate)";
  c.scenario["duration_s"] = std::to_string(kCalibrationSession_s);
  c.timeline.clear();
  c.metrics.clear();
  c.paper.clear();
  auto at = [&](double t, const std::string& verb, std::vector<std::string> args) {
    maglev::scenario::TimelineEntry e;
    e.t_s = t;
    e.verb = verb;
    e.args = std::move(args);
    e.line = 0;
    c.timeline.push_back(e);
  };
  at(0.0, "levitate", {});
  at(2.5, "move_to", {"theta_x", "0urad", "1mrad/s", "10mrad/s^2"});
  at(2.5, "move_to", {"theta_y", "0urad", "1mrad/s", "10mrad/s^2"});
  at(kCalibrateAt_s, "calibrate_coupling", {});
  return c;
}

int run_one_plain(const maglev::scenario::Scenario& sc, const Args& a, const std::string& dir,
                  maglev::bench::RunResult* keep);

// Runs one scenario into dir; returns 0 when it completed.
int run_one(const maglev::scenario::Scenario& sc, const Args& a, const std::string& dir,
            maglev::bench::RunResult* keep) {
  if (!a.calibrate) return run_one_plain(sc, a, dir, keep);
  maglev::bench::RunResult cal;
  const int rc = run_one_plain(calibration_session(sc), a, (fs::path(dir) / "calibration").string(), &cal);
  const auto it = cal.metrics.find("calibration_result");
  const int result = it == cal.metrics.end() ? 0 : static_cast<int>(it->second);
  std::printf("  calibration: %s (coupling %.4g -> %.4g, line spread %.3g)\n",
              maglev::kernel::to_string(static_cast<maglev::kernel::CouplingCalibrationResult>(result)),
              cal.metrics.count("calibration_coupling_before") ? cal.metrics.at("calibration_coupling_before") : 0.0,
              cal.metrics.count("calibration_coupling_after") ? cal.metrics.at("calibration_coupling_after") : 0.0,
              cal.metrics.count("calibration_inconsistency") ? cal.metrics.at("calibration_inconsistency") : 0.0);
  Args ak = a;
  ak.run.coupling = cal.coupling;  // what the kernel stored (unchanged = off when it failed)
  maglev::bench::RunResult r;
  const int rr = run_one_plain(sc, ak, dir, &r);
  r.metrics["calibration_result"] = result;
  for (const char* k : {"calibration_coupling_before", "calibration_coupling_after", "calibration_inconsistency"}) {
    if (cal.metrics.count(k)) r.metrics[k] = cal.metrics.at(k);
  }
  if (keep != nullptr) *keep = std::move(r);
  return rc | rr;
}

int run_one_plain(const maglev::scenario::Scenario& sc, const Args& a, const std::string& dir,
                  maglev::bench::RunResult* keep) {
  std::printf("== %s: %s (kernel %s, CAN %s, %s)\n", sc.name().c_str(),
              sc.scenario.count("title") ? sc.scenario.at("title").c_str() : "",
              a.run.kernel ? maglev::hil::to_string(*a.run.kernel)
                           : (sc.scenario.count("kernel") ? sc.scenario.at("kernel").c_str() : "float32"),
              a.run.can.c_str(), a.run.mode == maglev::bench::Mode::kLockstep ? "lockstep" : "realtime");
  std::vector<maglev::bench::ScenarioError> errs;
  auto r = maglev::bench::run(sc, a.run, &errs);
  if (!r) {
    for (const auto& e : errs) std::fprintf(stderr, "%s\n", e.message.c_str());
    return 2;
  }
  const int rc = report_run(sc, *r, a, dir);
  if (!a.run.can_log.empty()) std::printf("  CAN log (candump format, simulated time): %s\n", a.run.can_log.c_str());
  if (keep != nullptr) *keep = std::move(*r);
  return rc;
}

// run --seeds N: the scenario once per as-built error seed 1..N (noise seed
// unchanged), each into DIR/error_seed_K; then, per paper figure, the median
// and spread of the bench's values and the ratio median / paper against the
// 0.5-2x band (docs/PERFORMANCE.md). Also into DIR/seeds_summary.json.
int run_seeds(const maglev::scenario::Scenario& sc, const Args& a) {
  std::map<std::string, std::vector<double>> values;
  int rc = 0;
  for (int k = 1; k <= a.seeds; ++k) {
    Args ak = a;
    ak.run.plant_options.error_seed = static_cast<std::uint64_t>(k);
    maglev::bench::RunResult r;
    rc |= run_one(sc, ak, (fs::path(a.out) / ("error_seed_" + std::to_string(k))).string(), &r);
    if (r.metrics.count("plant_model") == 0 ||
        r.metrics.at("plant_model") != static_cast<double>(static_cast<int>(maglev::hil::PlantModel::kAsBuilt))) {
      std::fprintf(stderr, "maglev-hil run --seeds: the plant is not as-built (say --plant as-built or model = as-built)\n");
      return 2;
    }
    for (const auto& [key, v] : r.metrics) values[key].push_back(v);
  }
  auto stats = [](std::vector<double> v, double* med, double* lo, double* hi) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    *med = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    *lo = v.front();
    *hi = v.back();
  };
  std::ofstream js((fs::path(a.out) / "seeds_summary.json").string());
  js << "{\n  \"error_seeds\": " << a.seeds;
  std::printf("\n== %s, as-built, error seeds 1..%d: paper figures (median [min, max] over the seeds)\n",
              sc.name().c_str(), a.seeds);
  std::printf("  %-44s %12s %24s %10s %8s  %s\n", "metric", "paper", "bench median [min, max]", "", "ratio", "band 0.5-2x");
  const auto within = [](double ratio) {
    return ratio >= maglev::report::kPaperBandLow && ratio <= maglev::report::kPaperBandHigh;
  };
  int in_band = 0, total = 0;
  std::map<std::string, bool> key_in_band;  // the paper's keys, for the z read as the sensors' mean
  for (const auto& [key, paper] : sc.paper) {
    const auto it = values.find(key);
    if (it == values.end()) continue;
    double med = 0, lo = 0, hi = 0;
    stats(it->second, &med, &lo, &hi);
    const double ratio = paper != 0.0 ? med / paper : 0.0;
    const bool ok = within(ratio);
    key_in_band[key] = ok;
    in_band += ok;
    ++total;
    std::printf("  %-44s %12.4g %10.4g [%.3g, %.3g] %8.3g  %s\n", key.c_str(), paper, med, lo, hi, ratio,
                ok ? "within" : "OUTSIDE");
    js << ",\n  \"" << key << "_paper\": " << paper << ",\n  \"" << key << "_median\": " << med << ",\n  \"" << key
       << "_min\": " << lo << ",\n  \"" << key << "_max\": " << hi << ",\n  \"" << key << "_ratio\": " << ratio;
  }
  // The paper's z entries once more with its z read as the mean of the three
  // height sensors (a hypothesis about the paper's measurement,
  // docs/PERFORMANCE.md "Tables 4-8"). The count above stays the kernel's z;
  // this one swaps in the mean.
  int in_band_mean = in_band, z_entries = 0;
  for (const auto& [key, paper] : sc.paper) {
    const std::string mean_key = maglev::bench::ZSensorMeanKey(key);
    const auto it = values.find(mean_key);
    if (mean_key.empty() || key_in_band.count(key) == 0 || it == values.end()) continue;
    double med = 0, lo = 0, hi = 0;
    stats(it->second, &med, &lo, &hi);
    const double ratio = paper != 0.0 ? med / paper : 0.0;
    in_band_mean += static_cast<int>(within(ratio)) - static_cast<int>(key_in_band.at(key));
    ++z_entries;
    std::printf("  %-44s %12.4g %10.4g [%.3g, %.3g] %8.3g  %s  (z as the height sensors' mean)\n", key.c_str(), paper,
                med, lo, hi, ratio, within(ratio) ? "within" : "OUTSIDE");
    js << ",\n  \"" << mean_key << "_median\": " << med << ",\n  \"" << mean_key << "_ratio\": " << ratio;
  }
  // Peak times and p-p perturbations, reported separately (paper 003 Sec. 3.3).
  for (const auto& [key, v] : values) {
    if (key.find("_peak_time_s") == std::string::npos && key.find("_pp_") == std::string::npos) continue;
    if (key.find("rest_pp") != std::string::npos) continue;
    double med = 0, lo = 0, hi = 0;
    stats(v, &med, &lo, &hi);
    std::printf("  %-44s %12s %10.4g [%.3g, %.3g]\n", key.c_str(), "", med, lo, hi);
    js << ",\n  \"" << key << "_median\": " << med << ",\n  \"" << key << "_min\": " << lo << ",\n  \"" << key
       << "_max\": " << hi;
  }
  js << "\n}\n";
  std::printf("  %d of %d paper figures within 0.5-2x (median of %d error seeds)\n", in_band, total, a.seeds);
  if (z_entries != 0) {
    std::printf("  %d of %d with the paper's z read as the mean of its three height sensors (a hypothesis: "
                "docs/PERFORMANCE.md)\n", in_band_mean, total);
  }
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "serve") return maglev::bench::serve_main(argc - 1, argv + 1);
  if (argc >= 2 && std::string(argv[1]) == "campaign") return maglev::bench::campaign_main(argc - 1, argv + 1);
  const Args a = parse_args(argc, argv);
  if (!a.error.empty()) {
    std::fprintf(stderr, "maglev-hil: %s\n", a.error.c_str());
    usage();
    return 2;
  }
  // One log is one run's bus: `suite` would overwrite it per scenario, and the
  // two-process bench runs on a real interface that `candump -l` records.
  if (!a.run.can_log.empty() && a.cmd != "run") {
    std::fprintf(stderr, "maglev-hil %s: --can-log is an option of 'run' only%s\n", a.cmd.c_str(),
                 a.cmd == "plant" || a.cmd == "controller" ? " (record the interface with 'candump -l IFACE')" : "");
    return 2;
  }
  // Stages of another actuator family than the default's run on their own
  // kernel and plant in process (paper 002: docs/PAPER-002.md); their suite
  // is a list of experiments, not scenario files.
  if (a.run.profile && (a.cmd == "run" || a.cmd == "suite" || a.cmd == "list")) {
    const maglev::profile::ProfileParse pp = maglev::profile::find_profile(*a.run.profile, maglev::bench::profile_dir());
    if (!pp.ok()) {
      for (const auto& e : pp.errors) std::fprintf(stderr, "%s\n", e.c_str());
      return 2;
    }
    if (pp.profile.family == maglev::stage_profile::ActuatorFamily::kIronCorePmlsm) {
      namespace pm = maglev::bench::pmlsm;
      if (a.cmd == "list") {
        pm::list_experiments();
        return 0;
      }
      if (a.out.empty() || (a.cmd == "run" && a.positional.size() != 1)) {
        std::fprintf(stderr, "maglev-hil %s --profile %s: needs %s--out DIR\n", a.cmd.c_str(), pp.profile.name,
                     a.cmd == "run" ? "one experiment NAME and " : "");
        return 2;
      }
      return pm::suite_main(pp.profile, a.out, a.cmd == "run" ? a.positional[0] : std::string());
    }
  }
  int selfstab_rc = 0;  // a solenoid_magnet stage (paper 001): its own bench, selfstab_suite.hpp
  if (a.run.profile && maglev::bench::selfstab_dispatch(a.cmd, a.positional, *a.run.profile, a.out, &selfstab_rc)) {
    return selfstab_rc;
  }
  if (a.cmd == "record-pmlsm") {
    if (a.positional.size() != 2) {
      std::fprintf(stderr, "maglev-hil record-pmlsm: needs VECTORS OUTPUTS\n");
      return 2;
    }
    const maglev::profile::ProfileParse pp =
        maglev::profile::find_profile(a.run.profile ? *a.run.profile : "fmp2009-pmlsm", maglev::bench::profile_dir());
    if (!pp.ok()) {
      for (const auto& e : pp.errors) std::fprintf(stderr, "%s\n", e.c_str());
      return 2;
    }
    return maglev::bench::pmlsm::record_main(pp.profile, a.positional[0], a.positional[1]);
  }
  if (a.cmd == "list") {
    const auto files = scenario_files(a.scenarios);
    if (files.empty()) {
      std::fprintf(stderr, "maglev-hil: no .scenario files in %s\n", a.scenarios.c_str());
      return 1;
    }
    for (const auto& f : files) {
      auto r = maglev::scenario::load_scenario_file(f.string());
      if (!r.ok()) {
        std::printf("  %-28s (parse error: %s)\n", f.stem().c_str(), r.errors.front().to_string().c_str());
        continue;
      }
      const auto& sc = *r.scenario;
      std::printf("  %-28s %6.1f s  %s\n", sc.name().c_str(), sc.duration_s(),
                  sc.scenario.count("title") ? sc.scenario.at("title").c_str() : "");
    }
    return 0;
  }
  if (a.cmd == "profiles") return maglev::bench::list_profiles_main();
  if (a.cmd == "error-terms") {
    // The as-built error terms as a markdown table (docs/PLANT.md is made
    // from this output: kErrorTerms is the one source).
    static const char* kDraw[] = {"uniform +-M", "normal, sigma M", "+-[lo M, M]", "[lo M, M]"};
    std::printf("| [plant] key | draw | M (as-built default) | lo | refused above | source |\n|---|---|---|---|---|---|\n");
    for (const auto& t : maglev::hil::kErrorTerms) {
      std::printf("| `%s` | %s | %g | %s | %g | %s |\n", t.key, kDraw[static_cast<int>(t.draw)], t.magnitude,
                  t.lo_fraction > 0 ? std::to_string(t.lo_fraction).substr(0, 5).c_str() : "-", t.max, t.source);
    }
    return 0;
  }
  if (a.cmd == "floor-classes") {
    // The named floors as a markdown table (docs/PLANT.md section 12 is this
    // output: kFloorClasses is the one source; hil_fidelity_floor checks it).
    std::printf("| `floor =` | rms velocity per one-third-octave band, 1-80 Hz | source |\n|---|---|---|\n");
    for (const auto& c : maglev::hil::kFloorClasses) {
      std::printf("| `%s` | %g um/s | %s |\n", c.name, c.band_velocity_m_per_s * 1e6, c.source);
    }
    return 0;
  }
  if (a.cmd == "check-profile") {
    if (a.positional.size() != 1) {
      std::fprintf(stderr, "maglev-hil check-profile: needs one profile NAME|FILE\n");
      return 2;
    }
    const maglev::profile::ProfileParse pp = maglev::profile::find_profile(a.positional[0], maglev::bench::profile_dir());
    if (pp.ok() && pp.profile.family == maglev::stage_profile::ActuatorFamily::kIronCorePmlsm) {
      return maglev::bench::pmlsm::check_profile_main(pp.profile);
    }
    return maglev::bench::check_profile_main(a.positional[0]);
  }
  if (a.cmd == "check") {
    int bad = 0;
    for (const auto& p : a.positional) {
      maglev::scenario::Scenario sc;
      if (!load(p, a.scenarios, &sc)) ++bad;
      else std::printf("%s: ok\n", p.c_str());
    }
    return bad == 0 && !a.positional.empty() ? 0 : 2;
  }
  if (a.cmd == "run") {
    if (a.positional.size() != 1 || a.out.empty()) {
      std::fprintf(stderr, "maglev-hil run: needs one scenario NAME|FILE and --out DIR\n");
      return 2;
    }
    maglev::scenario::Scenario sc;
    if (!load(a.positional[0], a.scenarios, &sc)) return 2;
    if (a.seeds > 0) return run_seeds(sc, a);
    return run_one(sc, a, a.out, nullptr);
  }
  if (a.cmd == "suite") {
    if (a.out.empty()) {
      std::fprintf(stderr, "maglev-hil suite: needs --out DIR\n");
      return 2;
    }
    struct Row {
      std::string name, state;
      int rc;
      double rtf, load, sim_s, wall_s;
    };
    std::vector<Row> rows;
    double sim_total = 0, wall_total = 0, cpu_total = 0;
    const std::string suite_profile = a.run.profile ? *a.run.profile : maglev::bench::kDefaultProfile;
    for (const auto& f : scenario_files(a.scenarios)) {
      maglev::scenario::Scenario sc;
      if (!load(f.string(), a.scenarios, &sc)) {
        rows.push_back({f.stem().string(), "scenario error", 2, 0, 0, 0, 0});
        continue;
      }
      // A profile's suite: the scenarios that name it, and -- for a stage of
      // the default's family -- the ones that name none.
      if (!maglev::bench::in_suite(sc, suite_profile)) continue;
      maglev::bench::RunResult r;
      const int rc = run_one(sc, a, (fs::path(a.out) / sc.name()).string(), &r);
      const auto sim_it = r.metrics.find("simulated_time_s");  // ticks at the run's servo rate
      const double sim = sim_it != r.metrics.end() ? sim_it->second : 0.0;
      rows.push_back({sc.name(), r.final_state, rc, r.real_time_factor, r.bus_load_percent, sim, r.wall_s});
      sim_total += sim;
      wall_total += r.wall_s;
      cpu_total += r.cpu_s;
    }
    std::printf("\n%-28s %-12s %8s %8s %10s %8s\n", "scenario", "final state", "sim s", "wall s", "RT factor",
                "bus %");
    int failed = 0;
    for (const auto& r : rows) {
      std::printf("%-28s %-12s %8.1f %8.2f %10.1f %8.1f%s\n", r.name.c_str(), r.state.c_str(), r.sim_s, r.wall_s,
                  r.rtf, r.load, r.rc == 0 ? "" : "  FAILED");
      failed += r.rc != 0;
    }
    std::printf("%-28s %-12s %8.1f %8.2f %10.1f\n", "TOTAL", "", sim_total, wall_total,
                wall_total > 0 ? sim_total / wall_total : 0.0);
    if (cpu_total > 0) {
      // On a shared machine: the factor on the run loops' own CPU time.
      std::printf("%-28s %-12s %8.1f %8.2f %10.1f\n", "TOTAL (loop CPU time)", "", sim_total, cpu_total,
                  sim_total / cpu_total);
    }
    return failed == 0 ? 0 : 1;
  }
  if (a.cmd == "controller") {
    maglev::bench::ControllerProcessOptions o;
    o.can = a.run.can;
    o.duration_s = a.max_time_s;
    o.out_dir = a.out;
    o.levitate = a.levitate;
    if (!a.config.empty()) {
      maglev::scenario::Scenario sc;
      if (!load(a.config, a.scenarios, &sc)) return 2;
      std::vector<maglev::bench::ScenarioError> errs;
      if (!maglev::bench::controller_config_of(sc, &o.config, &o.kernel, &errs)) {
        for (const auto& e : errs) std::fprintf(stderr, "%s\n", e.message.c_str());
        return 2;
      }
    }
    if (a.run.kernel) o.kernel = *a.run.kernel;
    return maglev::bench::run_controller_process(o);
  }
  if (a.cmd == "plant") {
    if (a.positional.size() != 1 || a.out.empty()) {
      std::fprintf(stderr, "maglev-hil plant: needs one scenario NAME|FILE and --out DIR\n");
      return 2;
    }
    maglev::scenario::Scenario sc;
    if (!load(a.positional[0], a.scenarios, &sc)) return 2;
    maglev::bench::PlantProcessOptions po;
    po.controller_record = a.controller_record.empty() ? a.out + "/controller_record.bin" : a.controller_record;
    po.lockstep_timeout_us = a.lockstep_timeout_ms * 1000u;
    std::printf("== %s: plant process over CAN %s (%s)\n", sc.name().c_str(), a.run.can.c_str(),
                a.run.mode == maglev::bench::Mode::kLockstep ? "lockstep" : "realtime");
    std::vector<maglev::bench::ScenarioError> errs;
    auto r = maglev::bench::run_plant_process(sc, a.run, po, &errs);
    if (!r) {
      for (const auto& e : errs) std::fprintf(stderr, "%s\n", e.message.c_str());
      return 2;
    }
    return report_run(sc, *r, a, a.out);
  }
  std::fprintf(stderr, "maglev-hil: unknown command '%s'\n", a.cmd.c_str());
  usage();
  return 2;
}
