// The meaning of a host command (firmware/can_link host_commands.hpp) as a
// kernel MotionCommand: ONE mapping for every path a command takes -- CAN
// host_command frames (the HIL board's Application, the bench's controller
// node) and Modbus cmd.* writes (firmware/modbus/binding) -- so an operator
// command does the same thing however it arrives. Relative moves (kMoveBy, kMoveJerkBy): target
// = present reference + distance, in double. Heap-free; host + Cortex-M7.
#pragma once

#include "maglev/can_link/host_commands.hpp"
#include "maglev/controller/controller.hpp"

namespace maglev::motion_commands {

// Reference of kernel axis a in SI (m or rad): int64 pm/prad * 1e-12
// (kernel::Axis order: x, y, theta_z, z, theta_x, theta_y; out of range -> x).
double reference_si(const kernel::Pose64& reference, int kernel_axis);

// false: the code has no kernel MotionCommand (kShutdown, bench only); *out untouched.
bool to_motion_command(const can::HostCommandFrame& h, const kernel::Pose64& reference, kernel::MotionCommand* out);

}  // namespace maglev::motion_commands
