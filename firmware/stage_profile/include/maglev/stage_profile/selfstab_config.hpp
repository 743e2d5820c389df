// A solenoid_magnet stage profile (paper 001) -> the selfstab kernel's
// configuration. Heap-free; host and Cortex-M7. The paper-000 kernel's
// CheckStageProfile / MakeKernelConfig keep refusing this family: it is a
// different kernel (firmware/kernel/selfstab_stage).
#pragma once

#include "maglev/selfstab_stage/selfstab_stage.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::stage_profile {

// Profile axis index (kernel::Axis order: x, y, theta_z, z, theta_x,
// theta_y) of the paper's axis a (x, y, z, alpha, beta, gamma).
int ProfileAxisOfSelfstabAxis(int selfstab_axis);

// The loop gain of a selfstab axis: axis acceleration (m/s^2, rad/s^2) per
// A of effort through T, from the profile's force constants, mass and
// inertias ((11): x 6 k_ip / m, y 2 sqrt3 k_ip / m, z 3 k_op / m, alpha
// 1.5 r1 k_op / I_xx, beta sqrt3 r1 k_op / I_yy, gamma 6 r2 k_ip / I_zz; the
// signs of (13) are in T, so every gain here is positive).
double SelfstabAxisGain(const StageProfile& p, int selfstab_axis);

// Refuses (nothing written) a profile of another family (kUnsupportedFamily),
// without three PSDs (kUnsupportedSensors), with an active axis that is not a
// PID (kUnsupportedController) or a filter other than butterworth2 /
// low_pass, without force constants or nominal currents
// (kBadActuatorParameters), a start-up other than 'lift_off_from_dock ready'
// (kBadStartup), nominal currents plus efforts above the peak current or the
// peak above the hardware (kLimitsOutsideHardware), and the other basic
// checks (name, servo rate, body, at least one active axis).
ProfileError MakeSelfstabKernelConfig(const StageProfile& p, selfstab::SelfstabKernelConfig* out);

}  // namespace maglev::stage_profile
