// SplitMix64 (Vigna): the numeric tests' pseudo-random arguments, fixed seed,
// so the host and the M7 build check the same values (the M7 a prefix).
#pragma once

#include <cstdint>

namespace maglev::numeric::test {

inline std::uint64_t NextRandom(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace maglev::numeric::test
