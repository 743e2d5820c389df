// Scenario files: the human-readable description of one bench experiment.
//
// Format (documented field by field in hil/scenarios/README.md):
//
//   # comment
//   [scenario]            key = value   (name, title, duration_s, kernel, seed, paper ...)
//   [plant]               key = value   (plant model overrides, SI units)
//   [controller]          key = value   (kernel config overrides, SI units)
//   [timeline]            <t_s> <verb> <args...>     one command per line
//   [metrics]             <kind> <args...>           one metric request per line
//   [paper]               <metric_name> = <value>    the paper's figure for a metric
//
// Parsing never throws: errors come back with the file name and line number,
// so a user's typo is reported precisely and nothing half-parsed runs.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace maglev::scenario {

struct TimelineEntry {
  double t_s;
  std::string verb;               // levitate, land, step, move, circle, ...
  std::vector<std::string> args;  // raw tokens; the runner interprets them
  int line;
};

struct MetricRequest {
  std::string kind;               // noise, step, ccq, tracking, currents, frequency_response
  std::vector<std::string> args;
  int line;
};

struct Scenario {
  std::string source;  // file path or "<builtin:name>"
  std::map<std::string, std::string> scenario;
  std::map<std::string, std::string> plant;
  std::map<std::string, int> plant_line;  // [plant] key -> its line (errors say file:line: key: reason)
  std::map<std::string, std::string> controller;
  std::vector<TimelineEntry> timeline;  // sorted by t_s (stable)
  std::vector<MetricRequest> metrics;
  std::map<std::string, double> paper;  // metric name -> paper's value

  [[nodiscard]] std::string name() const;
  [[nodiscard]] double duration_s() const;
};

struct ParseError {
  std::string source;
  int line;  // 0 = whole file
  std::string message;
  [[nodiscard]] std::string to_string() const;
};

struct ParseResult {
  std::optional<Scenario> scenario;
  std::vector<ParseError> errors;
  [[nodiscard]] bool ok() const { return scenario.has_value() && errors.empty(); }
};

ParseResult parse_scenario(const std::string& text, const std::string& source);
ParseResult load_scenario_file(const std::string& path);

// Strict number parsing: the whole token must be a finite number.
std::optional<double> parse_number(const std::string& token);

}  // namespace maglev::scenario
