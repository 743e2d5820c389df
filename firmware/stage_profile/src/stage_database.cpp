#include "maglev/stage_profile/stage_database.hpp"

#include <cstring>

#include "maglev/persistence/config_store.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

namespace maglev::stage_profile {

#include "stage_database_data.inc"

ProfileError LoadStageProfile(std::size_t index, StageProfile* out) {
  if (index >= kStageDatabaseCount) return ProfileError::kUnknownProfile;
  return LoadStageRecord(kStageDatabase[index], out);
}

ProfileError LoadStageRecord(const StageRecord& r, StageProfile* out) {
  if (r.bytes == nullptr) return ProfileError::kUnknownProfile;
  if (persistence::crc32(r.bytes, sizeof(StageProfile)) != r.crc32) return ProfileError::kChecksum;
  // Static scratch: a StageProfile is ~2 kB, too large for a small stack.
  static StageProfile candidate;
  std::memcpy(static_cast<void*>(&candidate), r.bytes, sizeof candidate);
  const ProfileCheck c = CheckStageProfile(candidate);
  if (c.error != ProfileError::kOk) return c.error;
  *out = candidate;
  return ProfileError::kOk;
}

int FindStageProfile(const char* name) {
  for (std::size_t i = 0; i < kStageDatabaseCount; ++i) {
    if (std::strcmp(kStageDatabase[i].name, name) == 0) return static_cast<int>(i);
  }
  return -1;
}

}  // namespace maglev::stage_profile
