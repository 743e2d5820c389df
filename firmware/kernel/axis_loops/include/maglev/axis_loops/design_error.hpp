// Error codes of the loop designers (Config -> Coefficients at apply time).
#pragma once

#include <cstdint>

namespace maglev::kernel {

enum class LoopDesignError : std::uint8_t {
  kOk = 0,
  kNonFinite,             // NaN or inf in the Config
  kNegativeGain,          // kp, ki, kd < 0
  kBadServoRate,          // servo rate <= 0
  kFilterAboveNyquist,    // a corner or centre frequency >= fs/2 (or <= 0)
  kBadSetpointWeight,     // b, c outside [0, 1]
  kBadTrackingTime,       // anti-windup Tt <= 0 or < one servo period
  kBadLimit,              // effort limit <= 0 or beyond the Scalar range
  kBadQuality,            // Q <= 0, notch depth < 0
  kCoefficientOutOfRange, // a discrete coefficient does not fit the Coeff type
  kUnstableDesign,        // pole placement failed / requested poles unstable
};

}  // namespace maglev::kernel
