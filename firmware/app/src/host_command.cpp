#include "maglev/app/host_command.hpp"

#include <algorithm>
#include <cstdint>

namespace maglev::app {

double reference_si(const kernel::Pose64& r, int a) {
  const std::int64_t v[6] = {r.x_pm, r.y_pm, r.theta_z_prad, r.z_pm, r.theta_x_prad, r.theta_y_prad};
  return static_cast<double>(v[a < 0 || a > 5 ? 0 : a]) * 1e-12;
}

bool to_motion_command(const can::HostCommandFrame& h, const kernel::Pose64& reference, kernel::MotionCommand* out) {
  using C = can::HostCommandCode;
  using kernel::MotionType;
  kernel::MotionCommand c;
  c.axis = static_cast<kernel::Axis>(h.axis);
  const double* a = h.arg;
  switch (h.code) {
    case C::kHome: c.type = MotionType::kHome; break;
    case C::kLevitate: c.type = MotionType::kLevitate; break;
    case C::kLand: c.type = MotionType::kLand; break;
    case C::kStop: c.type = MotionType::kStop; break;
    case C::kClearFault: c.type = MotionType::kClearFault; break;
    case C::kHold: c.type = MotionType::kHold; break;
    case C::kStep: c.type = MotionType::kStep; c.target = a[0]; break;
    case C::kMoveTo:
    case C::kMoveBy:
    case C::kMoveJerkTo:
    case C::kMoveJerkBy: {
      const bool jerk_limited = h.code == C::kMoveJerkTo || h.code == C::kMoveJerkBy;
      const bool relative = h.code == C::kMoveBy || h.code == C::kMoveJerkBy;
      c.type = jerk_limited ? MotionType::kMoveJerkLimited : MotionType::kMoveTo;
      c.target = relative ? reference_si(reference, h.axis) + a[0] : a[0];
      c.velocity = a[1];
      c.acceleration = a[2];
      if (jerk_limited) c.jerk = a[3];
      break;
    }
    case C::kCircle: c.type = MotionType::kCircle; c.diameter_m = a[0]; c.period_s = a[1]; c.turns = a[2]; break;
    case C::kSinusoid:
      c.type = MotionType::kSinusoid; c.amplitude = a[0]; c.frequency_Hz = a[1]; c.period_s = a[2]; c.turns = a[3];
      break;
    case C::kExcite:
      c.type = MotionType::kExcite; c.amplitude = a[0]; c.frequency_Hz = a[1]; c.duration_s = a[2];
      c.harmonics = static_cast<std::uint8_t>(std::clamp(a[3], 1.0, 255.0));
      break;
    case C::kStopExcitation: c.type = MotionType::kStopExcitation; break;
    case C::kShutdown: return false;
    default: return false;  // a code this build does not know
  }
  *out = c;
  return true;
}

}  // namespace maglev::app
