// Issue 15: `ideal` (and `default`) stay what they were. The digests below
// were recorded with the plant of commit 4e8aecc (before issue 15): every
// sensor sample and the body state of 3000 ticks under a fixed DAC pattern,
// bit for bit (plant_digest.hpp).
#include <cstdio>

#include "plant_digest.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::PlantConfig;
using maglev::hil::testing::PlantDigest;

TEST_GROUP(PlantUnchanged){};

TEST(PlantUnchanged, IdealAndDefaultAreBitIdenticalToThePreIssue15Plant) {
  const unsigned long long ideal = PlantDigest(PlantConfig::Ideal(), 1, 3000);
  const unsigned long long def = PlantDigest(PlantConfig::Default(), 1, 3000);
  std::printf("\n  digests: ideal %016llx, default %016llx\n", ideal, def);
  CHECK_EQUAL(0xecfab0bfc9147bafull, ideal);
  CHECK_EQUAL(0xe0fd8bb0e0174d7eull, def);
}
