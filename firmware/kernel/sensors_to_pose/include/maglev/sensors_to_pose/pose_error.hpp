// Pose errors (reference - measurement) as Scalar in kernel units (um, urad),
// saturating at the Scalar range (+-128 um / urad for float and Q7.24 alike).
#pragma once

#include <cstdint>

#include "maglev/numeric/saturation.hpp"
#include "maglev/sensors_to_pose/sensors_to_pose.hpp"

namespace maglev::kernel {

// Saturating int64 difference (a - b): a corrupt pose can never wrap.
constexpr std::int64_t SaturatingDiff(std::int64_t a, std::int64_t b) {
  std::int64_t r = 0;
  if (__builtin_sub_overflow(a, b, &r)) return a < 0 ? INT64_MIN + 1 : INT64_MAX;
  return r;
}

// out[i] in maglev::kernel::Axis order: x, y, theta_z, z, theta_x, theta_y.
template <typename Scalar>
constexpr void PoseErrors(const Pose64& reference, const Pose64& measured, Scalar out[6]) {
  out[0] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kX], measured[Axis::kX]));
  out[1] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kY], measured[Axis::kY]));
  out[2] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kThetaZ], measured[Axis::kThetaZ]));
  out[3] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kZ], measured[Axis::kZ]));
  out[4] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kThetaX], measured[Axis::kThetaX]));
  out[5] = numeric::pico_to_micro<Scalar>(SaturatingDiff(reference[Axis::kThetaY], measured[Axis::kThetaY]));
}

}  // namespace maglev::kernel
