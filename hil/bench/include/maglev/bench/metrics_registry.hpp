// The scenario's [metrics] lines as typed specs, and the registry that turns
// each kind (noise, step, ccq, tracking, currents, loop, levitation) into its
// flat, SI-named results. One function per kind; adding a kind is one entry.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "maglev/bench/axes.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

struct Trace;

struct MetricSpec {
  std::string kind;
  Axis axis = Axis::kX;
  double t0 = 0, t1 = 0;
  std::string name;
  int line = 0;
};

// One [metrics] line; false: *error says why.
bool parse_metric(const scenario::MetricRequest& m, MetricSpec* out, std::string* error);
// "noise, step, ccq, tracking, currents, loop, levitation".
std::string metric_kinds();

// What the metric functions read.
struct MetricInputs {
  const std::vector<TimelineAction>& actions;
  const Trace& trace;
  const std::vector<Multisine>& excitations;
  double levitate_t = -1.0;  // when levitate was commanded (-1: never)
  double ready_t = -1.0;     // first tick in Ready (-1: never)
  double duration_s = 0.0;
  double servo_rate_Hz = 0.0;
  // The laser displacement sensors' centroid in the platen frame (m): the
  // ccq metrics also report z as the mean of the three heights, z + y_c
  // theta_x - x_c theta_y of the measured plane (paper 003 Tables 4-6; the
  // kernel's z is the plane's at the platen centre). NaN: not reported.
  double height_sensor_centroid_m[2] = {std::numeric_limits<double>::quiet_NaN(),
                                        std::numeric_limits<double>::quiet_NaN()};
};

// The label of z read as the height sensors' mean in the ccq metric names
// (NAME_ccq_z_sensor_mean_*, NAME_pp_z_sensor_mean_m, ...).
inline constexpr const char* kZSensorMeanLabel = "z_sensor_mean";
// NAME_ccq_z_UNIT -> NAME_ccq_z_sensor_mean_UNIT; "" for a key that is not a z CCQ.
inline std::string ZSensorMeanKey(const std::string& ccq_key) {
  const std::size_t at = ccq_key.find("_ccq_z_");
  if (at == std::string::npos) return {};
  return ccq_key.substr(0, at) + "_ccq_" + kZSensorMeanLabel + ccq_key.substr(at + 6);
}

// Every metric of the scenario into *out (flat names, SI suffixes);
// *warnings for the ones that could not be computed.
void compute_metrics(const scenario::Scenario& sc, const MetricInputs& in, std::map<std::string, double>* out,
                     std::vector<std::string>* warnings);

}  // namespace maglev::bench
