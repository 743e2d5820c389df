// A stage profile -> the kernel's configuration, and the boot-time check that
// the profile can run on this controller. Heap-free; host and Cortex-M7.
#pragma once

#include "maglev/axis_loops/loop_check.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::stage_profile {

struct ProfileCheck {
  ProfileError error = ProfileError::kOk;
  std::int8_t axis = -1;  // the axis concerned (kernel::Axis index), -1 none
  // Allocation on the active axes (singular values of A restricted to them).
  int allocation_rank = 0;
  double allocation_condition = 0.0;
};

// The loop check (kernel axis_loops/loop_check.hpp) of one active axis with
// the profile's gains and the axis plant g / (s^2 + c s + k), g = 2 b* /
// (mass or inertia).
using kernel::LoopMargins;
LoopMargins AxisLoopMargins(const StageProfile& p, int axis);
// y'' + c y' + k y: plant gain per A of effort (m/s^2 or rad/s^2 per A).
double AxisPlantGain(const StageProfile& p, int axis);

// Validates the profile against this firmware (family, controllers, sensors
// per active axis, allocation rank and condition, limits inside the
// hardware, start-up sequence). Nothing is applied.
ProfileCheck CheckStageProfile(const StageProfile& p);

// The kernel configuration for the profile: the family's baseline
// (default_kernel_config()) with every field the profile describes set from
// it. For the default profile (nk2017-cross) the result equals
// default_kernel_config() field for field. Runs CheckStageProfile first; on
// an error *out is untouched.
ProfileCheck MakeKernelConfig(const StageProfile& p, kernel::KernelConfig* out);

// The sensor geometry of the profile into a pose solver configuration (the
// part of MakeKernelConfig that places the sensors, unchecked): its sensors
// in order of kind -- interferometers -> the three beams (axis, perpendicular
// offset, counting sign), laser displacement sensors -> the three heights,
// the first Hall sensor -> Hall A -- and the pitch. The bench's plant places
// its sensors from the same call, so the two cannot disagree.
void SetSensorGeometry(const StageProfile& p, kernel::SensorsToPoseConfig* m);

}  // namespace maglev::stage_profile
