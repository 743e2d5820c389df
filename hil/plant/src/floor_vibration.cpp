#include "maglev/plant/floor_vibration.hpp"

#include <cmath>
#include <random>
#include <string>

namespace maglev::hil {

namespace {
constexpr double kTwoPi = 6.283185307179586476925286766559;
// Re-derive the phasors from their phases this often, so that the rotation's
// rounding never accumulates (a 1e-16 drift per tick would be 1e-12 after
// 10^4 ticks; this keeps it at 1e-13).
constexpr std::uint64_t kResyncTicks = 1024;
}  // namespace

int find_floor_class(std::string_view name) {
  for (int i = 0; i < kFloorClassCount; ++i) {
    if (name == kFloorClasses[i].name) return i;
  }
  return -1;
}

const char* floor_class_names() {
  static const std::string names = [] {
    std::string s;
    for (int i = 0; i < kFloorClassCount; ++i) {
      if (i != 0) s += i + 1 == kFloorClassCount ? " or " : ", ";
      s += kFloorClasses[i].name;
    }
    return s;
  }();
  return names.c_str();
}

double FloorVibration::BandCentre_Hz(int band) { return std::pow(10.0, band / 10.0); }

double FloorVibration::Transmissibility(double f_Hz, double f0_Hz, double zeta) {
  if (!(f0_Hz > 0.0)) return 1.0;
  const double r = f_Hz / f0_Hz;
  const double c = 2.0 * zeta * r;
  const double k = 1.0 - r * r;
  return std::sqrt((1.0 + c * c) / (k * k + c * c));
}

FloorVibration::FloorVibration(const FloorVibrationConfig& config, double tick_s, std::uint64_t seed)
    : active_(config.active()), tick_s_(tick_s) {
  if (!active_) return;
  // Its own stream: turning the floor on leaves the sensor and current noise
  // of the same seed as they were.
  std::mt19937_64 engine(seed ^ 0xf100f100d00dfeedull);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double per_line = std::sqrt(2.0 / kLinesPerBand);
  for (int a = 0; a < kAxes; ++a) {
    for (int b = 0; b < kBands; ++b) {
      const double fc = BandCentre_Hz(b);
      const double lo = fc * std::pow(10.0, -0.05), hi = fc * std::pow(10.0, 0.05);
      for (int k = 0; k < kLinesPerBand; ++k) {
        const int i = b * kLinesPerBand + k;
        const double f = lo * std::pow(hi / lo, unit(engine));
        const double phase = kTwoPi * unit(engine);
        omega_[a][i] = kTwoPi * f;
        amplitude_[a][i] = config.band_velocity_m_per_s * per_line *
                           Transmissibility(f, config.isolator_hz, config.isolator_damping);
        // The first tick's midpoint.
        phase0_[a][i] = phase + omega_[a][i] * 0.5 * tick_s;
        cos_[a][i] = std::cos(phase0_[a][i]);
        sin_[a][i] = std::sin(phase0_[a][i]);
        step_cos_[a][i] = std::cos(omega_[a][i] * tick_s);
        step_sin_[a][i] = std::sin(omega_[a][i] * tick_s);
      }
    }
  }
}

// v = sum V cos(theta), u = sum V / omega sin(theta), a = -sum V omega sin(theta).
double FloorVibration::velocity_m_per_s(int axis) const {
  double s = 0.0;
  for (int i = 0; i < kLines; ++i) s += amplitude_[axis][i] * cos_[axis][i];
  return s;
}

double FloorVibration::displacement_m(int axis) const {
  double s = 0.0;
  for (int i = 0; i < kLines; ++i) {
    if (omega_[axis][i] > 0.0) s += amplitude_[axis][i] / omega_[axis][i] * sin_[axis][i];
  }
  return s;
}

double FloorVibration::acceleration_m_per_s2(int axis) const {
  double s = 0.0;
  for (int i = 0; i < kLines; ++i) s -= amplitude_[axis][i] * omega_[axis][i] * sin_[axis][i];
  return s;
}

double FloorVibration::band_rms_velocity_m_per_s(int axis, int band) const {
  double s = 0.0;
  for (int k = 0; k < kLinesPerBand; ++k) {
    const double v = amplitude_[axis][band * kLinesPerBand + k];
    s += 0.5 * v * v;
  }
  return std::sqrt(s);
}

void FloorVibration::Rotate(double dt_s) {
  elapsed_s_ += dt_s;
  ++ticks_;
  const bool exact = dt_s != tick_s_ || ticks_ % kResyncTicks == 0;
  for (int a = 0; a < kAxes; ++a) {
    for (int i = 0; i < kLines; ++i) {
      if (exact) {
        const double theta = phase0_[a][i] + omega_[a][i] * elapsed_s_;
        cos_[a][i] = std::cos(theta);
        sin_[a][i] = std::sin(theta);
      } else {
        const double c = cos_[a][i], s = sin_[a][i];
        cos_[a][i] = c * step_cos_[a][i] - s * step_sin_[a][i];
        sin_[a][i] = s * step_cos_[a][i] + c * step_sin_[a][i];
      }
    }
  }
}

void FloorVibration::Next(double dt_s, double acc_m_per_s2[kAxes]) {
  for (int a = 0; a < kAxes; ++a) acc_m_per_s2[a] = active_ ? acceleration_m_per_s2(a) : 0.0;
  if (active_) Rotate(dt_s);
}

}  // namespace maglev::hil
