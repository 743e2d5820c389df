// The plant of a stage profile: the one record (hil/profiles/*.profile) the
// controller's configuration also comes from. Host only.
#pragma once

#include <string>

#include "maglev/plant/plant_config.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::hil {

// The profile's body, forcer layout, field and coil geometry and hardware
// current limit on top of `base` (noise, errors, integration). false: *why
// says what the plant cannot model yet.
bool PlantConfigForProfile(const stage_profile::StageProfile& p, const PlantConfig& base, PlantConfig* out,
                           std::string* why);

}  // namespace maglev::hil
