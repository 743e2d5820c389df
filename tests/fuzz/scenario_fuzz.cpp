// libFuzzer target: the bench's scenario file parser (hil/scenario
// parse_scenario) on arbitrary text -- scenario files come from users.
// Checked, beyond "no crash, no sanitizer report":
//   * a rejected file yields no scenario and errors whose line numbers lie
//     inside the file;
//   * an accepted scenario keeps the format's promises: a name, a finite
//     positive duration, timeline entries sorted, at times in [0, duration],
//     each with a verb; keys and values non-empty and trimmed;
//   * parse -> write -> parse gives the same scenario (the parser keeps
//     everything it accepts, and what it keeps means the same when read
//     again).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "maglev/scenario/scenario.hpp"

namespace {

using namespace maglev::scenario;

bool trimmed(const std::string& s) {
  const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
  return !s.empty() && !space(s.front()) && !space(s.back());
}

std::string number_text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);  // round-trips every double
  return buf;
}

// The text form of a parsed scenario (the inverse of parse_scenario up to
// comments, spacing and line order).
std::string write(const Scenario& sc) {
  std::string t;
  const auto section = [&](const char* name, const std::map<std::string, std::string>& m) {
    t += std::string("[") + name + "]\n";
    for (const auto& [k, v] : m) t += k + " = " + v + "\n";
  };
  section("scenario", sc.scenario);
  section("plant", sc.plant);
  section("controller", sc.controller);
  t += "[timeline]\n";
  for (const auto& e : sc.timeline) {
    t += number_text(e.t_s) + " " + e.verb;
    for (const auto& a : e.args) t += " " + a;
    t += "\n";
  }
  t += "[metrics]\n";
  for (const auto& m : sc.metrics) {
    t += m.kind;
    for (const auto& a : m.args) t += " " + a;
    t += "\n";
  }
  t += "[paper]\n";
  for (const auto& [k, v] : sc.paper) t += k + " = " + number_text(v) + "\n";
  return t;
}

bool same(const Scenario& a, const Scenario& b) {
  if (a.scenario != b.scenario || a.plant != b.plant || a.controller != b.controller || a.paper != b.paper) {
    return false;
  }
  if (a.timeline.size() != b.timeline.size() || a.metrics.size() != b.metrics.size()) return false;
  for (std::size_t i = 0; i < a.timeline.size(); ++i) {
    const auto& x = a.timeline[i];
    const auto& y = b.timeline[i];
    if (x.t_s != y.t_s || x.verb != y.verb || x.args != y.args) return false;
  }
  for (std::size_t i = 0; i < a.metrics.size(); ++i) {
    if (a.metrics[i].kind != b.metrics[i].kind || a.metrics[i].args != b.metrics[i].args) return false;
  }
  return true;
}

void check_accepted(const Scenario& sc) {
  if (sc.name().empty()) __builtin_trap();
  const double duration_s = sc.duration_s();
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) __builtin_trap();
  double previous_s = 0.0;
  for (const auto& e : sc.timeline) {
    if (!(e.t_s >= previous_s) || e.t_s > duration_s || e.verb.empty()) __builtin_trap();
    previous_s = e.t_s;
  }
  for (const auto* m : {&sc.scenario, &sc.plant, &sc.controller}) {
    for (const auto& [k, v] : *m) {
      if (!trimmed(k) || !trimmed(v)) __builtin_trap();
    }
  }
  for (const auto& [k, v] : sc.paper) {
    if (!trimmed(k) || !std::isfinite(v)) __builtin_trap();
  }
  for (const auto& m : sc.metrics) {
    if (m.kind.empty()) __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const ParseResult r = parse_scenario(text, "fuzz.scenario");
  if (!r.ok()) {
    if (r.scenario.has_value() || r.errors.empty()) __builtin_trap();
    int lines = 0;
    for (char c : text) lines += c == '\n' ? 1 : 0;
    for (const auto& e : r.errors) {
      if (e.line < 0 || e.line > lines + 1 || e.source != "fuzz.scenario") __builtin_trap();
    }
    return 0;
  }
  check_accepted(*r.scenario);
  const ParseResult again = parse_scenario(write(*r.scenario), "fuzz.scenario");
  if (!again.ok() || !same(*r.scenario, *again.scenario)) __builtin_trap();
  return 0;
}
