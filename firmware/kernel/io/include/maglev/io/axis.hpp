// The six control axes, in the order of paper 000's effort vector
// U = [u_x u_y u_thz u_z u_thx u_thy] (eqs (18), (21)): index = static_cast
// of the enum, so arrays indexed by Axis line up with A, B and S_xy.
#pragma once

#include <cstdint>

namespace maglev::kernel {

enum class Axis : std::uint8_t { kX = 0, kY = 1, kThetaZ = 2, kZ = 3, kThetaX = 4, kThetaY = 5 };

inline constexpr int kAxisCount = 6;

constexpr int axis_index(Axis a) { return static_cast<int>(a); }

// Rotational axes carry angles (rad, kernel unit urad, 64-bit prad);
// the others carry lengths (m, um, pm).
constexpr bool is_rotation(Axis a) { return a == Axis::kThetaZ || a == Axis::kThetaX || a == Axis::kThetaY; }

inline constexpr Axis kAllAxes[kAxisCount] = {Axis::kX, Axis::kY, Axis::kThetaZ, Axis::kZ, Axis::kThetaX, Axis::kThetaY};

// The axes' names, indexed by Axis: THE axis vocabulary of registers, CAN,
// scenarios, traces and tools.
inline constexpr const char* kAxisNames[kAxisCount] = {"x", "y", "theta_z", "z", "theta_x", "theta_y"};
constexpr const char* axis_name(Axis a) { return kAxisNames[axis_index(a)]; }

}  // namespace maglev::kernel
