// A stage profile -> the kernel's configuration, and the boot-time check that
// the profile can run on this controller. Heap-free; host and Cortex-M7.
#pragma once

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

// The open loop of one active axis with its profile gains: the 2-DOF PID's
// feedback part (kp + ki/s + kd s/(1 + s/wf)), the half-tick delay of the
// zero-order hold (the output of tick n is applied during tick n: the
// bench's lockstep and the board's tick both work so), and the axis plant
// g / (s^2 + c s + k) with g = 2 b* / (mass or inertia). Found by a
// logarithmic scan from 0.1 Hz to the Nyquist rate (constant work).
struct LoopMargins {
  bool crossover_found = false;
  double crossover_Hz = 0.0;
  double phase_margin_deg = 0.0;
};
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

}  // namespace maglev::stage_profile
