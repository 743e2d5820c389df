#include "maglev/scenario/scenario.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace maglev::scenario {
namespace {

// Every character tokens() splits on (std::isspace in the "C" locale): a
// line that trims to something non-empty always has a first token. Trimming
// fewer (it once left '\v' and '\f') let a line of only those reach
// tok[0] on an empty token list.
constexpr const char* kSpace = " \t\r\n\v\f";

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(kSpace);
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(kSpace);
  return s.substr(b, e - b + 1);
}

std::vector<std::string> tokens(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

const std::set<std::string> kSections{"scenario", "plant", "controller", "timeline", "metrics", "paper"};

}  // namespace

std::optional<double> parse_number(const std::string& token) {
  if (token.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (errno != 0 || end != token.c_str() + token.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string ParseError::to_string() const {
  return line > 0 ? source + ":" + std::to_string(line) + ": " + message : source + ": " + message;
}

std::string Scenario::name() const {
  const auto it = scenario.find("name");
  return it == scenario.end() ? std::string{} : it->second;
}

double Scenario::duration_s() const {
  const auto it = scenario.find("duration_s");
  if (it == scenario.end()) return 0.0;
  return parse_number(it->second).value_or(0.0);
}

ParseResult parse_scenario(const std::string& text, const std::string& source) {
  ParseResult result;
  Scenario sc;
  sc.source = source;
  std::string section;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  auto fail = [&](int line, std::string msg) { result.errors.push_back({source, line, std::move(msg)}); };

  while (std::getline(in, raw)) {
    ++line_no;
    const auto hash = raw.find('#');
    const std::string line = trim(hash == std::string::npos ? raw : raw.substr(0, hash));
    if (line.empty()) continue;
    if (line.front() == '[') {
      if (line.back() != ']') { fail(line_no, "section header must end with ']'"); continue; }
      section = trim(line.substr(1, line.size() - 2));
      if (!kSections.count(section)) fail(line_no, "unknown section [" + section + "] (expected scenario, plant, controller, timeline, metrics or paper)");
      continue;
    }
    if (section.empty()) { fail(line_no, "content before the first [section]"); continue; }

    if (section == "timeline") {
      auto tok = tokens(line);
      const auto t = parse_number(tok[0]);
      if (!t || *t < 0) { fail(line_no, "timeline entry must start with a time in seconds >= 0, got '" + tok[0] + "'"); continue; }
      if (tok.size() < 2) { fail(line_no, "timeline entry at " + tok[0] + " s has no command"); continue; }
      sc.timeline.push_back({*t, tok[1], std::vector<std::string>(tok.begin() + 2, tok.end()), line_no});
    } else if (section == "metrics") {
      auto tok = tokens(line);
      sc.metrics.push_back({tok[0], std::vector<std::string>(tok.begin() + 1, tok.end()), line_no});
    } else {
      const auto eq = line.find('=');
      if (eq == std::string::npos) { fail(line_no, "expected 'key = value' in [" + section + "]"); continue; }
      const std::string key = trim(line.substr(0, eq));
      const std::string value = trim(line.substr(eq + 1));
      if (key.empty() || value.empty()) { fail(line_no, "empty key or value in [" + section + "]"); continue; }
      if (section == "paper") {
        const auto v = parse_number(value);
        if (!v) { fail(line_no, "paper value for '" + key + "' is not a number: '" + value + "'"); continue; }
        sc.paper[key] = *v;
        continue;
      }
      auto& map = section == "scenario" ? sc.scenario : section == "plant" ? sc.plant : sc.controller;
      if (map.count(key)) { fail(line_no, "duplicate key '" + key + "' in [" + section + "]"); continue; }
      map[key] = value;
      if (section == "plant") sc.plant_line[key] = line_no;
    }
  }
  if (sc.name().empty()) fail(0, "[scenario] needs 'name = ...'");
  const auto dur = sc.scenario.find("duration_s");
  if (dur == sc.scenario.end()) {
    fail(0, "[scenario] needs 'duration_s = ...'");
  } else if (const auto d = parse_number(dur->second); !d || *d <= 0) {
    fail(0, "duration_s must be a positive number, got '" + dur->second + "'");
  }
  for (const auto& e : sc.timeline) {
    if (sc.duration_s() > 0 && e.t_s > sc.duration_s()) {
      fail(e.line, "timeline entry at " + std::to_string(e.t_s) + " s is after duration_s");
    }
  }
  std::stable_sort(sc.timeline.begin(), sc.timeline.end(),
                   [](const TimelineEntry& a, const TimelineEntry& b) { return a.t_s < b.t_s; });
  if (result.errors.empty()) result.scenario = std::move(sc);
  return result;
}

ParseResult load_scenario_file(const std::string& path) {
  std::ifstream f(path);
  if (!f) {
    ParseResult r;
    r.errors.push_back({path, 0, "cannot open scenario file"});
    return r;
  }
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_scenario(ss.str(), path);
}

}  // namespace maglev::scenario
