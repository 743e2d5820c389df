// The scenario's [timeline] as typed actions. A line's verb is a host
// command's name from the one table (can_link host_commands.hpp: levitate,
// step, move, move_to, move_jerk, circle, sinusoid, ...) with that command's
// fields as arguments, in the table's order and units -- or `excite`, the
// bench's own multisine disturbance at the plant input. Nothing here lists a
// command's fields: parsing, usage text and host-command frames all come from
// the table.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "maglev/bench/axes.hpp"
#include "maglev/can_link/host_commands.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

// `excite AXIS AMPLITUDE_PER_TONE F_MIN F_MAX DURATION [TONES]`: a Schroeder
// multisine of axis effort added at the plant input (not a host command: the
// bench computes it from the controller's pose every tick).
struct BenchExcite {
  double amplitude_A = 0.0;  // per tone, axis effort
  double f_min_Hz = 0.0;
  double f_max_Hz = 0.0;
  double duration_s = 0.0;
  int tones = 24;
};

struct TimelineAction {
  enum class Kind : std::uint8_t { kHostCommand = 0, kBenchExcite = 1 };
  double t_s = 0.0;
  int line = 0;
  std::string text;  // the line as written (verb and arguments)
  Kind kind = Kind::kHostCommand;
  Axis axis = Axis::kX;  // the command's axis (x for commands without one)
  can::HostCommandFrame command{};  // kHostCommand: seq 0; the executor numbers it
  BenchExcite excite{};             // kBenchExcite
  // Set after the run (internal::mark_refused_actions): the controller
  // refused it. The step and ccq metrics then measure nothing for it: a
  // step refused as "not ready" once reported a 154 % "overshoot" of noise
  // and a verdict against the paper on a stage that never levitated.
  bool refused = false;

  bool is(can::HostCommandCode c) const { return kind == Kind::kHostCommand && command.code == c; }
  // A point-to-point motion (step, move, move_to, move_jerk, move_jerk_to):
  // what the step/ccq metrics and the rest window look for.
  bool is_point_to_point() const;
};

// One [timeline] line; false: *error says why (no "file:line:" prefix).
bool parse_action(const scenario::TimelineEntry& e, TimelineAction* out, std::string* error);
// Every line; errors come back as "file:line: why", nothing is returned then.
bool parse_timeline(const scenario::Scenario& sc, std::vector<TimelineAction>* out, std::vector<std::string>* errors);
// The usage line of a verb ("sinusoid AXIS AMPLITUDE FREQUENCY_HZ DURATION_S"), "" if unknown.
std::string usage_of(const std::string& verb);

// The bench multisine: frequencies on a 1 Hz grid (periodic in 1 s), Schroeder phases.
struct Multisine {
  bool active = false;
  Axis axis = Axis::kX;
  double t0 = 0.0, t1 = 0.0;
  std::vector<double> freqs, phases;
  double amplitude_A = 0.0;
  double value(double t) const;  // effort at time t (0 outside [t0, t1))
};
Multisine make_multisine(const TimelineAction& a);

}  // namespace maglev::bench
