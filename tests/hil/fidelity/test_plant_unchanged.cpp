// Issue 15: `ideal` (and `default`) stay what they were. The digests below
// were recorded with the plant of commit 4e8aecc (before issue 15): every
// sensor sample and the body state of 3000 ticks under a fixed DAC pattern,
// bit for bit (plant_digest.hpp). Issue 16 made `integrator = fast` the
// default (docs/PERFORMANCE.md "Integrator `fast`"): the model is the same,
// and with `classic` (the integrator these digests were recorded with) the
// plant stays bit for bit what it was.
#include <cstdio>

#include "plant_digest.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::PlantConfig;
using maglev::hil::testing::PlantDigest;

TEST_GROUP(PlantUnchanged){};

TEST(PlantUnchanged, IdealAndDefaultAreBitIdenticalToThePreIssue15Plant) {
  PlantConfig ideal_config = PlantConfig::Ideal();
  PlantConfig default_config = PlantConfig::Default();
  ideal_config.integration.method = maglev::hil::IntegrationConfig::Method::kClassic;
  default_config.integration.method = maglev::hil::IntegrationConfig::Method::kClassic;
  const unsigned long long ideal = PlantDigest(ideal_config, 1, 3000);
  const unsigned long long def = PlantDigest(default_config, 1, 3000);
  std::printf("\n  digests: ideal %016llx, default %016llx\n", ideal, def);
  CHECK_EQUAL(0xecfab0bfc9147bafull, ideal);
  CHECK_EQUAL(0xe0fd8bb0e0174d7eull, def);
}
