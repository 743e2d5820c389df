// The raw sensor sample of a stage of paper 000 held at a pose: the
// interferometers at fixed base counts plus x, the three laser displacement
// sensors at height z, the Hall pairs at a plausible amplitude. Shared by the
// kernel's and the binding's tests (a sample the supervisor finds healthy).
#pragma once

#include <cmath>
#include <cstdint>

#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"

namespace maglev::test {

inline io::SensorSample stage_sample_at(double x_m, double z_m, const std::uint32_t (&base_counts)[3]) {
  namespace st = io::stage;
  io::SensorSample s{};
  const auto counts = static_cast<std::int32_t>(std::lround(x_m / st::kInterferometerLsb_m));
  s.interferometer_counts[0] = base_counts[0] + static_cast<std::uint32_t>(counts);
  s.interferometer_counts[1] = base_counts[1];
  s.interferometer_counts[2] = base_counts[2];
  const double volts = (z_m - st::kDisplacementZeroHeight_m) / st::kDisplacementScale_m_per_V;
  const auto code = static_cast<std::int16_t>(std::lround(volts / st::kAdcFullScale_V * 32768.0));
  for (auto& c : s.displacement_adc) c = code;
  // Hall: sin/cos pairs of a plausible amplitude.
  s.hall_adc[0] = 6000;
  s.hall_adc[1] = 6000;
  s.hall_adc[2] = 10000;
  s.hall_adc[3] = 10000;
  return s;
}

// Live sensors are never bit-for-bit still: the supervisor takes a whole
// sample that repeats for more than max_identical_samples ticks while a loop
// is closed as a frozen sensor node (FaultCode::kFrozenSample). A synthetic
// stage held at a pose adds the one-LSB Hall noise that a real one has.
inline void add_live_noise(std::uint32_t tick, io::SensorSample* s) {
  s->hall_adc[0] = static_cast<std::int16_t>(s->hall_adc[0] + static_cast<std::int16_t>(tick & 1u));
}

// Amplifiers that follow: the current monitor reads what `command` asked
// for (the supervisor's current-mismatch check compares the two).
inline void set_monitored_currents(const io::ActuatorCommand& command, io::SensorSample* s) {
  static const kernel::ForceAllocationState<float> alloc = [] {
    kernel::ForceAllocationState<float> a{};
    (void)kernel::ApplyForceAllocationConfig<float>(kernel::DefaultForceAllocationConfig(), &a);
    return a;
  }();
  for (int j = 0; j < io::kCoils; ++j) {
    const double i = command.amplifier_enable ? command.dac_code[j] / alloc.dac_codes_per_A : 0.0;
    s->coil_current_adc[j] = static_cast<std::int16_t>(std::lround(i / alloc.monitor_A_per_code));
  }
}

}  // namespace maglev::test
