#pragma once
// Paper 002's stage from its profile: the bench plant's parameters and the
// firmware kernel's configuration (maglev::pmlsm_stage::PmlsmKernelConfig).
// The kernel receives computed data: the LQR gains (Riccati solved here with
// Eigen from the profile's weights), the internal model's ZOH matrices and
// the force-law tables. Host only.
#include <array>
#include <complex>
#include <string>
#include <vector>

#include "maglev/pmlsm_plant/params.hpp"
#include "maglev/pmlsm_stage/pmlsm_stage.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::control_design {

// The profile axis (kernel::Axis index: x, y, theta_z, z, theta_x, theta_y)
// of each pmlsm_stage axis (gap, X, Z, phi, theta): docs/STAGES.md.
inline constexpr std::array<int, pmlsm_stage::kAxes> kProfileAxisOf{3, 0, 1, 4, 5};

struct PmlsmStage {
  pmlsm_plant::StageParams stage;
  pmlsm_plant::AmplifierParams amplifier;
  pmlsm_plant::EncoderParams encoder;
};
// The bench plant's parameters from the profile ([pmlsm], [body], sensors, limits).
bool PmlsmStageFromProfile(const stage_profile::StageProfile& p, PmlsmStage* out, std::string* why);

struct PmlsmDesign {
  pmlsm_stage::PmlsmKernelConfig config{};
  // Per pmlsm_stage axis: the continuous closed-loop poles of the design
  // plant (13)+(14)-(16) with the gains the kernel receives.
  std::array<std::vector<std::complex<double>>, pmlsm_stage::kAxes> poles;
};
// The kernel configuration; false with `why` when the profile cannot give one.
bool BuildPmlsmKernelConfig(const stage_profile::StageProfile& p, PmlsmDesign* out, std::string* why);

}  // namespace maglev::control_design
