// The raw inputs of one servo tick, exactly as the amplifier board's drivers
// (or the HIL plant, over CAN) deliver them. No unit conversion happens here:
// the kernel's sensors_to_pose stage owns every scale and offset, so the
// board, the bench and the tests feed the kernel the very same bits.
#pragma once

#include <cstdint>

namespace maglev::io {

inline constexpr int kInterferometerAxes = 3;   // x, y1, y2 (default layout)
inline constexpr int kDisplacementSensors = 3;  // laser displacement sensors (heights)
inline constexpr int kHallChannels = 4;         // 2 two-axis Hall sensors: A.Bx, A.By, B.Bx, B.By
inline constexpr int kCoils = 8;

// status_flags bits. A set bit means "this input is NOT trustworthy".
enum SensorStatusBit : std::uint16_t {
  kBeamLoss0 = 1u << 0,  // interferometer axis 0 signal loss
  kBeamLoss1 = 1u << 1,
  kBeamLoss2 = 1u << 2,
  kDisplacementOutOfRange0 = 1u << 3,  // laser displacement sensor reports no target
  kDisplacementOutOfRange1 = 1u << 4,
  kDisplacementOutOfRange2 = 1u << 5,
  kAdcFault = 1u << 6,      // AD7606 BUSY timeout / conversion error
  kStaleFrame = 1u << 7,    // transport: this sample repeats the previous one
};

struct SensorSample {
  // Wrapping 32-bit hardware up/down counters (quadrature edges or
  // interferometer-electronics counts). The kernel extends them to 64 bit.
  std::uint32_t interferometer_counts[kInterferometerAxes];
  // AD7606 codes, 16-bit two's complement over the +-10 V range.
  std::int16_t displacement_adc[kDisplacementSensors];
  std::int16_t hall_adc[kHallChannels];
  std::int16_t coil_current_adc[kCoils];  // amplifier current monitors
  std::uint16_t status_flags;             // SensorStatusBit
};

}  // namespace maglev::io
