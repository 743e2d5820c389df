// kernel-step-bench: N ticks of Controller::step() for float and Q7.24 on a
// fixed, synthetic input sequence (levitated-looking samples, all loops
// closed in Ready). Run under callgrind to get instructions per step():
//   valgrind --tool=callgrind --toggle-collect="*Controller*step*" (continued:)
//     build/<dir>/firmware/kernel/controller/kernel-step-bench 20000
// docs/PERFORMANCE.md records the numbers.
#include <cstdio>
#include <cstdlib>

#include "maglev/controller/controller.hpp"

namespace {

using maglev::io::SensorSample;

template <typename Scalar>
long run(long ticks) {
  static maglev::kernel::Controller<Scalar> controller;  // static, as on the target
  SensorSample s{};
  long checksum = 0;
  for (long n = 0; n < ticks; ++n) {
    // Small deterministic dither on every sensor; plausible Hall amplitudes.
    const auto d = static_cast<std::uint32_t>((n * 7919) % 13);
    s.interferometer_counts[0] = 1000u + d;
    s.interferometer_counts[1] = 2000u - d;
    s.interferometer_counts[2] = 3000u + d;
    for (int k = 0; k < 3; ++k) s.displacement_adc[k] = static_cast<std::int16_t>(-32000 + 300 + static_cast<int>(d));
    s.hall_adc[0] = 8000;
    s.hall_adc[1] = 8000;
    s.hall_adc[2] = 14000;
    s.hall_adc[3] = 14000;
    const maglev::io::ActuatorCommand c = controller.step(s, false);
    checksum += c.dac_code[0] + c.dac_code[3];
  }
  return checksum;
}

}  // namespace

int main(int argc, char** argv) {
  const long ticks = argc > 1 ? std::atol(argv[1]) : 100000;
  const long a = run<float>(ticks);
  const long b = run<maglev::numeric::Q7_24>(ticks);
  std::printf("ticks=%ld checksum_float=%ld checksum_q7_24=%ld\n", ticks, a, b);
  return 0;
}
