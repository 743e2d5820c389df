// The suite of paper 002 on the bench: every experiment runs, Table III's
// specifications hold, the tracking errors, the loop's poles and the
// anti-windup's effect, each as measured by `maglev-hil suite --profile
// fmp2009-pmlsm` (docs/PAPER-002.md).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "maglev/bench/pmlsm_bench.hpp"
#include "maglev/profile/profile_text.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

namespace {
std::string Slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
double Metric(const std::string& json, const std::string& key) {
  const auto k = json.find("\"" + key + "\": ");
  if (k == std::string::npos) return NAN;
  return std::strtod(json.c_str() + k + key.size() + 4, nullptr);
}
}  // namespace

TEST_GROUP(PmlsmSuite) {};

TEST(PmlsmSuite, TheSuiteRunsEveryExperimentWithTheExpectedVerdicts) {
  const auto parsed = maglev::profile::find_profile("fmp2009-pmlsm", MAGLEV_PROFILE_DIR);
  CHECK_TRUE(parsed.ok());
  const std::string out = (std::filesystem::temp_directory_path() / "pmlsm-suite-test").string();
  std::filesystem::remove_all(out);
  // Returns 1: three verdicts are outside their band, measured and explained
  // in docs/PAPER-002.md (3-DOF gap tracking 2.9x, 10 mrad overshoot 0.21x).
  maglev::bench::pmlsm::suite_main(parsed.profile, out, "");
  const std::string v = Slurp(out + "/verdicts.json");
  CHECK_TRUE(v.size() > 1000);
  // Every Table III specification holds.
  std::size_t pos = 0;
  int table3 = 0;
  while ((pos = v.find("(Table III", pos)) != std::string::npos) {
    const auto end = v.find('}', pos);
    CHECK_TRUE(v.substr(pos, end - pos).find("\"pass\": true") != std::string::npos);
    ++table3;
    pos = end;
  }
  LONGS_EQUAL(3 * 9, table3);  // 9 steps x (overshoot, t_s, t_enc)
  const std::string step = Slurp(out + "/gap_step_7mm/metrics.json");
  const double os = Metric(step, "overshoot_percent");
  CHECK_TRUE(os > 0.5 * 14.3 && os < 2.0 * 14.3);  // Fig. 4, 0.5-2x band
  const std::string t4 = Slurp(out + "/tracking_4dof/metrics.json");
  CHECK_TRUE(Metric(t4, "mean_abs_error_gap_measured") < 1.5 * 47.03e-6);
  CHECK_TRUE(Metric(t4, "mean_abs_error_x_measured") < 1.5 * 77.98e-6);
  CHECK_TRUE(Metric(t4, "mean_abs_error_z_measured") < 1.5 * 76.85e-6);
  CHECK_TRUE(Metric(t4, "mean_abs_error_theta_measured") < 1.5 * 123.9e-6);
  const std::string aw = Slurp(out + "/antiwindup_x_30mm/metrics.json");
  CHECK_TRUE(Metric(aw, "with_antiwindup_settling_time_s") < Metric(aw, "without_antiwindup_settling_time_s"));
  const std::string poles = Slurp(out + "/poles/metrics.json");
  for (const char* a : {"gap", "x", "z", "phi", "theta"}) {
    CHECK_TRUE(Metric(poles, std::string(a) + "_design_pole_error") < 1e-6);
    CHECK_TRUE(Metric(poles, std::string(a) + "_slow_pole_error") < 0.15);
  }
  const std::string bad = Slurp(out + "/bad_input/metrics.json");
  CHECK_TRUE(v.find("\"bad set-points refused with their result code (count)\", \"kind\": \"spec\", \"bench\": 8,") !=
             std::string::npos);
  const std::string land = Slurp(out + "/lift_off_and_land/metrics.json");
  CHECK_TRUE(Metric(land, "touchdown_speed_m_per_s") < 2e-3);
  const std::string ours = Slurp(out + "/ours_tracking_4dof/metrics.json");
  CHECK_TRUE(Metric(ours, "mean_abs_error_gap_true") < 1e-6);
}
