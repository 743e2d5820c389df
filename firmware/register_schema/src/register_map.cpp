#include "maglev/register_schema/register_map.hpp"

#include <bit>
#include <cmath>

namespace maglev::modbus {

std::uint32_t encode(RegType type, double value) {
  switch (type) {
    case RegType::kU16:
      return static_cast<std::uint16_t>(value);
    case RegType::kI32:
      return static_cast<std::uint32_t>(static_cast<std::int32_t>(value));
    case RegType::kF32:
      return std::bit_cast<std::uint32_t>(static_cast<float>(value));
    case RegType::kBlock:
      return 0;  // read-only window: no value of its own
  }
  return 0;
}

double decode(RegType type, std::uint32_t raw) {
  switch (type) {
    case RegType::kU16:
      return static_cast<double>(raw & 0xFFFFu);
    case RegType::kI32:
      return static_cast<double>(static_cast<std::int32_t>(raw));
    case RegType::kF32:
      return static_cast<double>(std::bit_cast<float>(raw));
    case RegType::kBlock:
      return 0.0;
  }
  return 0.0;
}

bool value_in_range(const RegisterDef& d, double value) {
  if (!std::isfinite(value) || d.type == RegType::kBlock) return false;
  if (d.type == RegType::kF32) {
    // Compare in float: 0.056f is above the double 0.056 and must still pass.
    const float v = static_cast<float>(value);
    return v >= static_cast<float>(d.min) && v <= static_cast<float>(d.max);
  }
  if (value != std::floor(value)) return false;
  return value >= d.min && value <= d.max;
}

double ConfigImage::get(RegId id) const {
  const int slot = persisted_slot(id);
  if (slot < 0) return 0.0;
  return decode(def(id).type, raw[static_cast<std::size_t>(slot)]);
}

void ConfigImage::set(RegId id, double value) {
  const int slot = persisted_slot(id);
  if (slot < 0) return;
  raw[static_cast<std::size_t>(slot)] = encode(def(id).type, value);
}

ConfigImage ConfigImage::defaults() {
  ConfigImage c{};
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    c.raw[s] = encode(d.type, d.default_value);
  }
  return c;
}

bool operator==(const ConfigImage& a, const ConfigImage& b) {
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    if (a.raw[s] != b.raw[s]) return false;
  }
  return true;
}

}  // namespace maglev::modbus
