// The bench's axis vocabulary: the kernel's one Axis order (x, y, theta_z, z,
// theta_x, theta_y: paper 000's effort vector) indexes every per-axis array
// of the bench (trace, metrics, commands). The only other order is the
// presentation order of trace.csv and the plots, kDisplayOrder (x, y, z,
// theta_x, theta_y, theta_z, as in the papers' figures), named once here.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "maglev/io/axis.hpp"
#include "maglev/controller/controller.hpp"

namespace maglev::bench {

using kernel::Axis;
inline constexpr int kAxes = kernel::kAxisCount;

inline constexpr std::array<Axis, kAxes> kDisplayOrder{Axis::kX,      Axis::kY,      Axis::kZ,
                                                       Axis::kThetaX, Axis::kThetaY, Axis::kThetaZ};

constexpr int index(Axis a) { return kernel::axis_index(a); }
using kernel::is_rotation;

// "x", "y", "theta_z", "z", "theta_x", "theta_y": the kernel's one table.
using kernel::axis_name;
// "m" or "rad".
inline const char* si_unit(Axis a) { return is_rotation(a) ? "rad" : "m"; }
// Accepts the names above and the short forms thx/tx, thy/ty, thz/tz.
bool parse_axis(const std::string& s, Axis* out);
// "x, y, z, theta_x, theta_y, theta_z" (display order), for messages.
std::string axis_name_list();
// A pose/reference component in SI (m or rad) from the kernel's pm/prad.
double pose_si(const kernel::Pose64& p, Axis a);

}  // namespace maglev::bench
