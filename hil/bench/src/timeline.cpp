#include "maglev/bench/timeline.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "maglev/bench/units.hpp"

namespace maglev::bench {

namespace {

constexpr double kPi = 3.14159265358979323846;

// The unit rule of a command field on a given axis.
Dim dim_of(can::ArgQuantity q, Axis a) {
  const bool rot = is_rotation(a);
  switch (q) {
    case can::ArgQuantity::kAxisPosition: return rot ? Dim::kAngle : Dim::kLength;
    case can::ArgQuantity::kAxisVelocity: return rot ? Dim::kAngularVelocity : Dim::kVelocity;
    case can::ArgQuantity::kAxisAcceleration: return rot ? Dim::kAngularAcceleration : Dim::kAcceleration;
    case can::ArgQuantity::kAxisJerk: return rot ? Dim::kAngularJerk : Dim::kJerk;
    case can::ArgQuantity::kLength: return Dim::kLength;
    case can::ArgQuantity::kTime: return Dim::kTime;
    case can::ArgQuantity::kFrequency: return Dim::kFrequency;
    case can::ArgQuantity::kCount: return Dim::kNumber;
    case can::ArgQuantity::kAxisEffort: return Dim::kCurrent;
  }
  return Dim::kNumber;
}

std::string upper(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Scenario verbs: every host command but the bench's own shutdown.
const can::HostCommandSpec* find_verb(const std::string& v) {
  for (const auto& s : can::kHostCommandSpecs) {
    if (s.code != can::HostCommandCode::kShutdown && v == s.name) return &s;
  }
  return nullptr;
}

std::string verb_list() {
  std::string l;
  for (const auto& s : can::kHostCommandSpecs) {
    if (s.code == can::HostCommandCode::kShutdown) continue;
    l += std::string(l.empty() ? "" : ", ") + s.name;
  }
  return l + ", excite";
}

constexpr const char* kExciteUsage = "excite AXIS AMPLITUDE_PER_TONE F_MIN F_MAX DURATION [TONES]";

bool parse_excite(const scenario::TimelineEntry& e, TimelineAction* a, std::string* err) {
  const auto& args = e.args;
  if (!(args.size() == 5 || args.size() == 6)) {
    *err = "'excite' takes 5 or 6 arguments: " + std::string(kExciteUsage);
    return false;
  }
  if (!parse_axis(args[0], &a->axis)) {
    *err = "unknown axis '" + args[0] + "' (" + axis_name_list() + ")";
    return false;
  }
  BenchExcite& x = a->excite;
  const Dim dims[4] = {Dim::kCurrent, Dim::kFrequency, Dim::kFrequency, Dim::kTime};
  double* dst[4] = {&x.amplitude_A, &x.f_min_Hz, &x.f_max_Hz, &x.duration_s};
  for (int i = 0; i < 4; ++i) {
    const auto r = parse_quantity(args[static_cast<std::size_t>(i) + 1], dims[i], err);
    if (!r) return false;
    *dst[i] = *r;
  }
  double tones = 24;
  if (args.size() == 6) {
    const auto r = parse_quantity(args[5], Dim::kNumber, err);
    if (!r) return false;
    tones = *r;
  }
  x.tones = static_cast<int>(tones);
  if (!(x.f_min_Hz >= 1.0 && x.f_max_Hz > x.f_min_Hz && x.f_max_Hz <= 1000.0 && x.duration_s >= 2.0 &&
        x.tones >= 1 && x.tones <= 200 && tones == std::floor(tones))) {
    *err = "excite: need 1 Hz <= F_MIN < F_MAX <= 1000 Hz, DURATION >= 2 s, 1..200 tones";
    return false;
  }
  a->kind = TimelineAction::Kind::kBenchExcite;
  return true;
}

}  // namespace

bool TimelineAction::is_point_to_point() const {
  using C = can::HostCommandCode;
  return is(C::kStep) || is(C::kMoveTo) || is(C::kMoveBy) || is(C::kMoveJerkTo) || is(C::kMoveJerkBy);
}

std::string usage_of(const std::string& verb) {
  if (verb == "excite") return kExciteUsage;
  const can::HostCommandSpec* s = find_verb(verb);
  if (s == nullptr) return "";
  std::string u = s->name;
  if (s->takes_axis) u += " AXIS";
  for (int i = 0; i < s->field_count; ++i) u += " " + upper(s->fields[static_cast<std::size_t>(i)].name);
  return u;
}

bool parse_action(const scenario::TimelineEntry& e, TimelineAction* out, std::string* err) {
  TimelineAction a;
  a.t_s = e.t_s;
  a.line = e.line;
  a.text = e.verb;
  for (const auto& s : e.args) a.text += " " + s;
  if (e.verb == "excite") {
    if (!parse_excite(e, &a, err)) return false;
    *out = a;
    return true;
  }
  const can::HostCommandSpec* spec = find_verb(e.verb);
  if (spec == nullptr) {
    *err = "unknown command '" + e.verb + "' (" + verb_list() + ")";
    return false;
  }
  const std::size_t want = (spec->takes_axis ? 1u : 0u) + spec->field_count;
  // An axis-free command without fields may still name no axis at all.
  if (e.args.size() != want) {
    *err = "'" + e.verb + "' takes " + std::to_string(want) + " argument(s): " + usage_of(e.verb);
    return false;
  }
  std::size_t next = 0;
  if (spec->takes_axis) {
    if (!parse_axis(e.args[0], &a.axis)) {
      *err = "unknown axis '" + e.args[0] + "' (" + axis_name_list() + ")";
      return false;
    }
    next = 1;
  }
  double values[can::kHostCommandMaxFields] = {};
  for (std::size_t i = 0; i < spec->field_count; ++i) {
    const can::ArgFieldInfo& f = spec->fields[i];
    const auto r = parse_quantity(e.args[next + i], dim_of(f.quantity, a.axis), err);
    if (!r) return false;
    const bool ok = f.range == can::ArgRange::kAny || (f.range == can::ArgRange::kPositive && *r > 0.0) ||
                    (f.range == can::ArgRange::kNonNegative && *r >= 0.0);
    if (!ok) {
      *err = std::string(spec->name) + ": " + f.name + " must be " +
             (f.range == can::ArgRange::kPositive ? "> 0" : ">= 0");
      return false;
    }
    values[i] = *r;
  }
  a.kind = TimelineAction::Kind::kHostCommand;
  a.command = can::make_host_command(spec->code, 0, static_cast<std::uint8_t>(index(a.axis)));
  can::with_args(spec->code, a.command.args, [&](auto& args) {
    using A = std::remove_reference_t<decltype(args)>;
    for (std::size_t i = 0; i < A::kFields.size(); ++i) args.*A::kFields[i].member = values[i];
  });
  *out = a;
  return true;
}

bool parse_timeline(const scenario::Scenario& sc, std::vector<TimelineAction>* out, std::vector<std::string>* errors) {
  std::vector<TimelineAction> actions;
  const std::size_t before = errors->size();
  for (const auto& e : sc.timeline) {
    TimelineAction a;
    std::string err;
    if (parse_action(e, &a, &err)) actions.push_back(a);
    else errors->push_back(sc.source + ":" + std::to_string(e.line) + ": " + err);
  }
  if (errors->size() != before) return false;
  *out = std::move(actions);
  return true;
}

Multisine make_multisine(const TimelineAction& a) {
  Multisine x;
  const BenchExcite& e = a.excite;
  x.active = true;
  x.axis = a.axis;
  x.t0 = a.t_s;
  x.t1 = a.t_s + e.duration_s;
  x.amplitude_A = e.amplitude_A;
  for (int k = 0; k < e.tones; ++k) {
    const double f = e.tones == 1 ? e.f_min_Hz
                                  : e.f_min_Hz * std::pow(e.f_max_Hz / e.f_min_Hz, static_cast<double>(k) / (e.tones - 1));
    const double fr = std::round(f);
    if (x.freqs.empty() || fr > x.freqs.back()) x.freqs.push_back(fr);
  }
  const double n = static_cast<double>(x.freqs.size());
  for (std::size_t k = 0; k < x.freqs.size(); ++k) {
    const double kk = static_cast<double>(k + 1);
    x.phases.push_back(-kPi * kk * (kk - 1.0) / n);  // Schroeder: low crest factor
  }
  return x;
}

double Multisine::value(double t) const {
  if (!active || t < t0 || t >= t1) return 0.0;
  double d = 0.0;
  for (std::size_t k = 0; k < freqs.size(); ++k) d += std::sin(2.0 * kPi * freqs[k] * (t - t0) + phases[k]);
  return amplitude_A * d;
}

}  // namespace maglev::bench
