// The outputs of one servo tick: the eight AD5764 DAC codes that set the
// linear current amplifiers, and the amplifier-enable interlock line.
#pragma once

#include <cstdint>

#include "maglev/io/sensor_sample.hpp"

namespace maglev::io {

struct ActuatorCommand {
  // AD5764 codes, 16-bit two's complement over +-10 V (BIN/2sCOMP pin low).
  // Index j is coil j+1 of paper 000 (i_1 .. i_8).
  std::int16_t dac_code[kCoils];
  bool amplifier_enable;
};

// The command every output path presets before a tick: zero current,
// amplifiers disabled. A missed tick must never leave a stale current.
inline constexpr ActuatorCommand kSafeActuatorCommand{{0, 0, 0, 0, 0, 0, 0, 0}, false};

}  // namespace maglev::io
