#include "maglev/motion_commands/to_motion_command.hpp"

#include <cmath>
#include <cstdint>

namespace maglev::motion_commands {

double reference_si(const kernel::Pose64& r, int a) {
  return static_cast<double>(r.pico[a < 0 || a >= kernel::kAxisCount ? 0 : a]) * 1e-12;
}

bool to_motion_command(const can::HostCommandFrame& h, const kernel::Pose64& reference, kernel::MotionCommand* out) {
  using C = can::HostCommandCode;
  using kernel::MotionType;
  kernel::MotionCommand c;
  c.axis = static_cast<kernel::Axis>(h.axis);
  const can::HostCommandArgs& a = h.args;
  // Relative moves: target = present reference + distance, in double.
  const double here = reference_si(reference, h.axis);
  switch (h.code) {
    case C::kHome: c.type = MotionType::kHome; break;
    case C::kLevitate: c.type = MotionType::kLevitate; break;
    case C::kLand: c.type = MotionType::kLand; break;
    case C::kStop: c.type = MotionType::kStop; break;
    case C::kClearFault: c.type = MotionType::kClearFault; break;
    case C::kHold: c.type = MotionType::kHold; break;
    case C::kStep: c.type = MotionType::kStep; c.target = a.step.delta; break;
    case C::kMoveTo:
      c.type = MotionType::kMoveTo;
      c.target = a.move_to.target; c.velocity = a.move_to.velocity; c.acceleration = a.move_to.acceleration;
      break;
    case C::kMoveBy:
      c.type = MotionType::kMoveTo;
      c.target = here + a.move_by.distance; c.velocity = a.move_by.velocity; c.acceleration = a.move_by.acceleration;
      break;
    case C::kMoveJerkTo:
      c.type = MotionType::kMoveJerkLimited;
      c.target = a.move_jerk_to.target; c.velocity = a.move_jerk_to.velocity;
      c.acceleration = a.move_jerk_to.acceleration; c.jerk = a.move_jerk_to.jerk;
      break;
    case C::kMoveJerkBy:
      c.type = MotionType::kMoveJerkLimited;
      c.target = here + a.move_jerk_by.distance; c.velocity = a.move_jerk_by.velocity;
      c.acceleration = a.move_jerk_by.acceleration; c.jerk = a.move_jerk_by.jerk;
      break;
    case C::kCircle:
      c.type = MotionType::kCircle;
      c.diameter_m = a.circle.diameter_m; c.period_s = a.circle.period_s; c.turns = a.circle.turns;
      break;
    case C::kSinusoid:
      // The kernel counts cycles (0 = until hold) and ends only at rest, on
      // a whole half cycle; the command says how long: at least that long,
      // to the next half cycle (1 s at 1.2 Hz: 1.5 cycles, 1.25 s).
      c.type = MotionType::kSinusoid;
      c.amplitude = a.sinusoid.amplitude; c.frequency_Hz = a.sinusoid.frequency_Hz;
      // A positive duration is at least half a cycle; 0 stays "until hold";
      // a negative or non-finite one stays what it is, for the kernel to refuse.
      {
        const double d = a.sinusoid.duration_s, f = a.sinusoid.frequency_Hz;
        c.turns = d > 0.0 ? 0.5 * std::fmax(1.0, std::ceil(2.0 * d * f - 1e-9)) : d * f;
      }
      break;
    case C::kExcite:
      c.type = MotionType::kExcite;
      c.amplitude = a.excite.amplitude; c.frequency_Hz = a.excite.frequency_Hz; c.duration_s = a.excite.duration_s;
      // A whole number of lines, 1..255; anything else (0, -7, 300, 2.5,
      // NaN) becomes 0, which the kernel refuses -- never silently another
      // excitation than the one asked for.
      {
        const double lines = a.excite.harmonics;
        c.harmonics = lines >= 1.0 && lines <= 255.0 && lines == std::floor(lines) ? static_cast<std::uint8_t>(lines) : 0u;
      }
      break;
    case C::kStopExcitation: c.type = MotionType::kStopExcitation; break;
    case C::kCalibrateCoupling: c.type = MotionType::kCalibrateCoupling; break;
    case C::kShutdown: return false;
    default: return false;  // a code this build does not know
  }
  *out = c;
  return true;
}

}  // namespace maglev::motion_commands
