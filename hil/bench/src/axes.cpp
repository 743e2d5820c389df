#include "maglev/bench/axes.hpp"

namespace maglev::bench {

namespace {
using kernel::kAxisNames;
// Short forms accepted in scenario files, indexed by the kernel's Axis order.
constexpr const char* kShort[kAxes][2] = {{"x", "x"}, {"y", "y"}, {"thz", "tz"}, {"z", "z"}, {"thx", "tx"}, {"thy", "ty"}};
}  // namespace

bool parse_axis(const std::string& s, Axis* out) {
  for (Axis a : kernel::kAllAxes) {
    if (s == kAxisNames[index(a)] || s == kShort[index(a)][0] || s == kShort[index(a)][1]) {
      *out = a;
      return true;
    }
  }
  return false;
}

std::string axis_name_list() {
  std::string l;
  for (Axis a : kDisplayOrder) l += std::string(l.empty() ? "" : ", ") + axis_name(a);
  return l;
}

double pose_si(const kernel::Pose64& p, Axis a) { return static_cast<double>(p[a]) * 1e-12; }

}  // namespace maglev::bench
