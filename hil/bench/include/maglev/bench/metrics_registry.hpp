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

// Every metric of the scenario into *out (flat names, SI suffixes);
// *warnings for the ones that could not be computed.
void compute_metrics(const scenario::Scenario& sc, const MetricInputs& in, std::map<std::string, double>* out,
                     std::vector<std::string>* warnings);

}  // namespace maglev::bench
