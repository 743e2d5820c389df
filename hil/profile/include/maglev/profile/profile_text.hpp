// The stage profile's text form (hil/profiles/*.profile, docs/STAGES.md) ->
// stage_profile::StageProfile, with an error per bad field:
// "file:line: field: what is wrong". Nothing runs on a profile with errors.
// Host only.
#pragma once

#include <string>
#include <vector>

#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::profile {

struct ProfileParse {
  stage_profile::StageProfile profile{};
  std::vector<std::string> errors;  // "file:line: field: reason"
  bool ok() const { return errors.empty(); }
};

// source: the name used in messages (the file's path).
ProfileParse parse_profile(const std::string& text, const std::string& source);
ProfileParse load_profile_file(const std::string& path);

// The shipped profiles: every *.profile in dir, by name (sorted).
std::vector<std::string> list_profiles(const std::string& dir);
// NAME (looked up in dir) or a path to a .profile file.
ProfileParse find_profile(const std::string& name_or_path, const std::string& dir);

}  // namespace maglev::profile
