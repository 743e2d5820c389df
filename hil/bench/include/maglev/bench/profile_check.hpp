// `maglev-hil profiles` and `maglev-hil check-profile`: what the controller
// and the bench make of a stage profile before anything runs.
#pragma once

#include <string>

#include "maglev/controller/controller.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

// Prints every profile in profile_dir() with its title; 0 when all parse.
int list_profiles_main();
// Prints the allocation's rank and condition on the active axes, the passive
// axes' eigenvalues, each active loop's crossover and phase margin with the
// profile's gains, and the current headroom for gravity plus the profile's
// maximum accelerations; field-by-field errors for a malformed profile.
// 0: the controller accepts the profile.
int check_profile_main(const std::string& name_or_path);
// Why the register map cannot hold a profile's kernel configuration, or ""
// when it can: "kRegisterRange's text (NAME is V, outside the register's
// range MIN..MAX)" -- the one wording of check-profile and `run --profile`.
std::string register_range_refusal(const kernel::KernelConfig& kc);
// A profile's suite: the scenarios that name it; a scenario that names no
// profile belongs to the suites of the default's family.
bool in_suite(const scenario::Scenario& sc, const std::string& profile);

}  // namespace maglev::bench
