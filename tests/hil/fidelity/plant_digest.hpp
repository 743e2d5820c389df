// A digest of a plant's whole behaviour under a fixed command sequence: every
// sensor sample's bytes and the rigid-body state's bits, tick by tick
// (FNV-1a, 64 bit). Equal digests = bit-identical plants. Header-only so the
// same code can be compiled against an older plant (the recording in
// test_plant_unchanged.cpp was made with the plant of commit 4e8aecc).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "maglev/plant/plant.hpp"

namespace maglev::hil::testing {

inline void Fnv(std::uint64_t* h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    *h ^= p[i];
    *h *= 0x100000001b3ull;
  }
}

// ticks servo ticks of a lift-and-wobble DAC pattern (enable on from tick 10).
inline std::uint64_t PlantDigest(const PlantConfig& config, std::uint64_t seed, int ticks) {
  Plant plant(config, seed);
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (int n = 0; n < ticks; ++n) {
    const io::SensorSample s = plant.sample();
    Fnv(&h, s.interferometer_counts, sizeof(s.interferometer_counts));
    Fnv(&h, s.displacement_adc, sizeof(s.displacement_adc));
    Fnv(&h, s.hall_adc, sizeof(s.hall_adc));
    Fnv(&h, s.coil_current_adc, sizeof(s.coil_current_adc));
    Fnv(&h, &s.status_flags, sizeof(s.status_flags));
    io::ActuatorCommand c{};
    c.amplifier_enable = n >= 10;
    for (int j = 0; j < 8; ++j) {
      c.dac_code[j] = static_cast<std::int16_t>(std::lround(9000.0 * std::sin(0.004 * n + 0.7 * j)));
    }
    plant.apply(c);
    plant.advance_tick();
    const BodyState& b = plant.body_state();
    const double v[13] = {b.position_m.x(), b.position_m.y(), b.position_m.z(), b.velocity_m_per_s.x(),
                          b.velocity_m_per_s.y(), b.velocity_m_per_s.z(), b.attitude.w(), b.attitude.x(),
                          b.attitude.y(), b.attitude.z(), b.omega_body_rad_per_s.x(), b.omega_body_rad_per_s.y(),
                          b.omega_body_rad_per_s.z()};
    Fnv(&h, v, sizeof(v));
  }
  return h;
}

}  // namespace maglev::hil::testing
