// Deterministic noise source of the plant: one 64-bit Mersenne twister,
// seeded once; every draw happens in a fixed order per tick, so a run is
// reproducible from (config, seed, command sequence).
#pragma once

#include <cstdint>
#include <random>

namespace maglev::hil {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : engine_(seed) {}
  // Standard normal sample.
  double Normal() { return normal_(engine_); }
  double Uniform() { return uniform_(engine_); }

 private:
  std::mt19937_64 engine_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace maglev::hil
