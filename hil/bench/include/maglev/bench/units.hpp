// Quantities with units in scenario files: "10nm", "8um", "0.1urad", "6mm",
// "60mm/s", "0.6m/s^2", "2s", "250ms", "15Hz", "50mA", "539.6g". A bare number
// is SI. parse_quantity() checks the dimension, so "step x 2urad" is an error.
#pragma once

#include <optional>
#include <string>

namespace maglev::bench {

enum class Dim {
  kLength, kAngle, kVelocity, kAngularVelocity, kAcceleration, kAngularAcceleration,
  kJerk, kAngularJerk, kTime, kFrequency, kCurrent, kMass, kNumber,
};

const char* dim_name(Dim d);

struct Quantity {
  double si;
  Dim dim;          // from the unit; kNumber for a bare number
  bool has_unit;
};

std::optional<Quantity> parse_quantity_any(const std::string& token);
// Value in SI if the token is a bare number or carries a unit of dimension d.
std::optional<double> parse_quantity(const std::string& token, Dim d, std::string* error);

}  // namespace maglev::bench
