#include "maglev/bench/units.hpp"

#include <cctype>
#include <utility>

#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {
namespace {
struct UnitDef {
  const char* name;
  double factor;
  Dim dim;
};
constexpr UnitDef kUnits[] = {
    {"m", 1.0, Dim::kLength}, {"mm", 1e-3, Dim::kLength}, {"um", 1e-6, Dim::kLength},
    {"nm", 1e-9, Dim::kLength}, {"pm", 1e-12, Dim::kLength},
    {"rad", 1.0, Dim::kAngle}, {"mrad", 1e-3, Dim::kAngle}, {"urad", 1e-6, Dim::kAngle},
    {"nrad", 1e-9, Dim::kAngle}, {"deg", 3.14159265358979323846 / 180.0, Dim::kAngle},
    {"m/s", 1.0, Dim::kVelocity}, {"mm/s", 1e-3, Dim::kVelocity}, {"um/s", 1e-6, Dim::kVelocity},
    {"rad/s", 1.0, Dim::kAngularVelocity}, {"mrad/s", 1e-3, Dim::kAngularVelocity},
    {"urad/s", 1e-6, Dim::kAngularVelocity},
    {"m/s^2", 1.0, Dim::kAcceleration}, {"mm/s^2", 1e-3, Dim::kAcceleration},
    {"um/s^2", 1e-6, Dim::kAcceleration},
    {"rad/s^2", 1.0, Dim::kAngularAcceleration}, {"mrad/s^2", 1e-3, Dim::kAngularAcceleration},
    {"urad/s^2", 1e-6, Dim::kAngularAcceleration},
    {"m/s^3", 1.0, Dim::kJerk}, {"mm/s^3", 1e-3, Dim::kJerk},
    {"rad/s^3", 1.0, Dim::kAngularJerk}, {"urad/s^3", 1e-6, Dim::kAngularJerk},
    {"s", 1.0, Dim::kTime}, {"ms", 1e-3, Dim::kTime},
    {"Hz", 1.0, Dim::kFrequency}, {"kHz", 1e3, Dim::kFrequency},
    {"A", 1.0, Dim::kCurrent}, {"mA", 1e-3, Dim::kCurrent},
    {"kg", 1.0, Dim::kMass}, {"g", 1e-3, Dim::kMass},
};
}  // namespace

const char* dim_name(Dim d) {
  switch (d) {
    case Dim::kLength: return "length (m, mm, um, nm)";
    case Dim::kAngle: return "angle (rad, mrad, urad, nrad)";
    case Dim::kVelocity: return "velocity (m/s, mm/s, um/s)";
    case Dim::kAngularVelocity: return "angular velocity (rad/s, mrad/s, urad/s)";
    case Dim::kAcceleration: return "acceleration (m/s^2, mm/s^2)";
    case Dim::kAngularAcceleration: return "angular acceleration (rad/s^2, mrad/s^2, urad/s^2)";
    case Dim::kJerk: return "jerk (m/s^3, mm/s^3)";
    case Dim::kAngularJerk: return "angular jerk (rad/s^3, urad/s^3)";
    case Dim::kTime: return "time (s, ms)";
    case Dim::kFrequency: return "frequency (Hz)";
    case Dim::kCurrent: return "current (A, mA)";
    case Dim::kMass: return "mass (kg, g)";
    case Dim::kNumber: return "number";
  }
  return "?";
}

std::optional<Quantity> parse_quantity_any(const std::string& token) {
  if (const auto v = scenario::parse_number(token)) return Quantity{*v, Dim::kNumber, false};
  // Longest numeric prefix that parses, the rest is the unit.
  std::size_t split = token.size();
  while (split > 0 && (std::isalpha(static_cast<unsigned char>(token[split - 1])) != 0 ||
                       token[split - 1] == '/' || token[split - 1] == '^' ||
                       (std::isdigit(static_cast<unsigned char>(token[split - 1])) != 0 && split >= 2 &&
                        token[split - 2] == '^'))) {
    --split;
  }
  if (split == 0 || split == token.size()) return std::nullopt;
  const auto v = scenario::parse_number(token.substr(0, split));
  if (!v) return std::nullopt;
  const std::string unit = token.substr(split);
  for (const UnitDef& u : kUnits) {
    if (unit == u.name) return Quantity{*v * u.factor, u.dim, true};
  }
  return std::nullopt;
}

std::optional<double> parse_quantity(const std::string& token, Dim d, std::string* error) {
  const auto q = parse_quantity_any(token);
  if (!q) {
    if (error != nullptr) *error = "'" + token + "' is not a number with a known unit (expected " + dim_name(d) + ")";
    return std::nullopt;
  }
  if (q->has_unit && q->dim != d) {
    if (error != nullptr) *error = "'" + token + "' has the wrong unit: expected " + std::string(dim_name(d));
    return std::nullopt;
  }
  return q->si;
}

}  // namespace maglev::bench
