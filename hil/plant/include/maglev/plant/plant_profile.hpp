// The plant of a stage profile: the one record (hil/profiles/*.profile) the
// controller's configuration also comes from. Host only.
#pragma once

#include <string>

#include "maglev/plant/plant_config.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::hil {

// The longest RK4 sub-step the bench integrates with (PlantConfigForProfile
// sets IntegrationConfig::substeps_per_tick from the servo rate).
inline constexpr double kMaxSubstep_s = 200e-6;

// The plant stepped at servo_rate_Hz: IntegrationConfig (rate, sub-steps of at
// most kMaxSubstep_s) and the current noise band (0.5 x rate).
void ApplyServoRate(double servo_rate_Hz, PlantConfig* c);

// The profile's body, forcer layout, field and coil geometry and hardware
// current limit, servo rate (integration sub-steps, current noise band) on
// top of `base` (noise, errors). false: *why
// says what the plant cannot model yet.
bool PlantConfigForProfile(const stage_profile::StageProfile& p, const PlantConfig& base, PlantConfig* out,
                           std::string* why);

}  // namespace maglev::hil
