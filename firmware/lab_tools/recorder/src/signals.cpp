#include "maglev/lab_tools/signals.hpp"

#include "maglev/io/axis.hpp"

namespace maglev::lab {
namespace {

void append(char* out, std::size_t size, std::size_t& n, const char* s) {
  while (*s != '\0' && n + 1 < size) out[n++] = *s++;
  out[n] = '\0';
}

bool is_rotation_axis(std::uint8_t axis) {
  const kernel::Axis a = kernel::kAllAxes[axis];
  return a == kernel::Axis::kThetaX || a == kernel::Axis::kThetaY || a == kernel::Axis::kThetaZ;
}

}  // namespace

bool signal_name(std::uint16_t id, char* out, std::size_t size) {
  const SignalGroupDef* g = signal_group(id);
  if (g == nullptr || size == 0) return false;
  std::size_t n = 0;
  out[0] = '\0';
  const std::uint8_t index = static_cast<std::uint8_t>(id - g->first);
  if (g->count == kAxisSignals) {
    append(out, size, n, kernel::axis_name(kernel::kAllAxes[index]));
    append(out, size, n, ".");
  } else if (g->count == kCoilSignals) {
    const char digit[2] = {static_cast<char>('1' + index), '\0'};
    append(out, size, n, "coil");
    append(out, size, n, digit);
    append(out, size, n, ".");
  }
  append(out, size, n, g->name);
  return true;
}

const char* signal_unit(std::uint16_t id) {
  const SignalGroupDef* g = signal_group(id);
  if (g == nullptr) return "";
  if (g->rotational_unit && is_rotation_axis(static_cast<std::uint8_t>(id - g->first))) return "rad";
  return g->unit;
}

std::uint16_t find_signal(const char* name) {
  char buf[40];
  for (std::uint16_t id = 1; id < kSignalIdEnd; ++id) {
    if (!signal_name(id, buf, sizeof buf)) continue;
    const char* a = buf;
    const char* b = name;
    while (*a != '\0' && *a == *b) {
      ++a;
      ++b;
    }
    if (*a == *b) return id;
  }
  return 0;
}

}  // namespace maglev::lab
