// Plant step cost: microseconds per servo tick (sample + apply + advance)
// with the default configuration and sub-steps, and the real-time factor.
#include <chrono>
#include <ctime>
#include <cstdio>

#include "allocation_copy.hpp"
#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace stage = maglev::io::stage;
namespace t = maglev::hil::test;

TEST_GROUP(PlantTiming){};

TEST(PlantTiming, TickCost) {
  Plant plant(PlantConfig::Default(), 5);
  t::Vector6 u = t::Vector6::Zero();
  u[3] = 1.02 * stage::kMass_kg * stage::kGravity_m_per_s2 / stage::kTwoBStarIdentified_N_per_A;
  const t::Vector8 i = t::CurrentsFromEffort(u, 0, 0);
  maglev::io::ActuatorCommand cmd{};
  for (int j = 0; j < 8; ++j) cmd.dac_code[j] = t::DacCode(i[j]);
  cmd.amplifier_enable = true;
  const int ticks = 5000;  // 2 s simulated
  std::uint32_t sink = 0;
  // Thread CPU time as well as wall time: the build machine is shared, and
  // the CPU time is what the bench's one core will spend.
  timespec c0{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < ticks; ++k) {
    const maglev::io::SensorSample s = plant.sample();
    sink += s.interferometer_counts[0];
    plant.apply(cmd);
    plant.advance_tick();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  timespec c1{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
  const double cpu = static_cast<double>(c1.tv_sec - c0.tv_sec) + 1e-9 * static_cast<double>(c1.tv_nsec - c0.tv_nsec);
  const double us_per_tick = cpu / ticks * 1e6;
  const double rt_factor = (1.0 / stage::kServoRate_Hz) / (cpu / ticks);
  std::printf("\n  plant tick cost %.2f us CPU (%.2f us wall) with %d sub-steps: real-time factor %.0fx (sink %u)\n",
              us_per_tick, wall / ticks * 1e6, plant.config().integration.substeps_per_tick, rt_factor, sink & 1u);
  CHECK(plant.truth().time_s > 1.99);
  // Generous bound (sanitizer / debug builds); the release target is <= 15 us.
  CHECK(us_per_tick < 200.0);
}
