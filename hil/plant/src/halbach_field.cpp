#include "maglev/plant/halbach_field.hpp"

#include <cmath>

namespace maglev::hil {
namespace {

constexpr double kPi = io::stage::kPi;
constexpr int kHarmonicN[kMaxHarmonics] = {1, 5, 9, 13};

// c_n(0) / M0 of eq (3).
double CnPerM0(int n, const FieldConfig& c) {
  const double gn = 2.0 * kPi * n / c.pitch_m;
  return 2.0 * std::sqrt(2.0) * io::stage::kMu0 / (kPi * n) * (1.0 - std::exp(-gn * c.magnet_thickness_m));
}

// Cross-section averaging factors of one coil side for harmonic n:
// width a: sin(gamma_n a/2) / (gamma_n a/2); thickness d: (1 - e^{-gamma_n d}) / (gamma_n d).
double SideFactor(int n, const FieldConfig& c) {
  const double gn = 2.0 * kPi * n / c.pitch_m;
  const double ha = gn * c.coil_side_width_m / 2.0;
  const double gd = gn * c.coil_thickness_m;
  return (std::sin(ha) / ha) * ((1.0 - std::exp(-gd)) / gd);
}

// b*(z) / M0 for harmonic n: one coil = 2 sides, each N I p B_avg.
double BStarPerM0(int n, double gap_m, const FieldConfig& c) {
  const double gn = 2.0 * kPi * n / c.pitch_m;
  return 2.0 * c.coil_turns * c.coil_effective_length_m * CnPerM0(n, c) * std::exp(-gn * gap_m) *
         SideFactor(n, c);
}

}  // namespace

double HalbachField::CalibrateM0(const FieldConfig& config, double two_b_star_N_per_A) {
  return two_b_star_N_per_A / (2.0 * BStarPerM0(1, config.rest_gap_m, config));
}

HalbachField::HalbachField(const FieldConfig& config)
    : config_(config),
      m0_(config.peak_magnetization_A_per_m > 0.0
              ? config.peak_magnetization_A_per_m
              : CalibrateM0(config, config.two_b_star_N_per_A)),
      gamma1_(2.0 * kPi / config.pitch_m),
      harmonics_(config.harmonics < 1 ? 1 : (config.harmonics > kMaxHarmonics ? kMaxHarmonics : config.harmonics)) {
  for (int h = 0; h < kMaxHarmonics; ++h) {
    const int n = kHarmonicN[h];
    const double sign = (h % 2 == 0) ? 1.0 : -1.0;  // (-1)^k, n = 4k + 1
    point_amp_[h] = sign * m0_ * CnPerM0(n, config_);
    side_amp_[h] = point_amp_[h] * SideFactor(n, config_);
    const double gd = 2.0 * kPi * n / config_.pitch_m * config_.coil_thickness_m;
    thick_amp_[h] = point_amp_[h] * ((1.0 - std::exp(-gd)) / gd);
  }
}

namespace {

// sin(x) / x, 1 at 0.
double Sinc(double x) { return std::fabs(x) < 1e-12 ? 1.0 : std::sin(x) / x; }

}  // namespace

ObliqueSideAmplitudes HalbachField::ObliqueAmplitudes(double cos_phi, double sin_phi) const {
  ObliqueSideAmplitudes out{};
  const double p = config_.coil_effective_length_m;
  const double a = config_.coil_side_width_m;
  for (int h = 0; h < kMaxHarmonics; ++h) {
    const double gn = 2.0 * kPi * kHarmonicN[h] / config_.pitch_m;
    // X array: length projects by |cos phi|, width by |sin phi|; Y the reverse.
    out.x_array_T[h] = thick_amp_[h] * Sinc(gn * p * std::fabs(cos_phi) / 2.0) * Sinc(gn * a * std::fabs(sin_phi) / 2.0);
    out.y_array_T[h] = thick_amp_[h] * Sinc(gn * p * std::fabs(sin_phi) / 2.0) * Sinc(gn * a * std::fabs(cos_phi) / 2.0);
  }
  return out;
}

FieldXYZ HalbachField::ObliqueSideField(const ObliqueSideAmplitudes& amp, double x_m, double y_m,
                                        double gap_m) const {
  const double e1 = std::exp(-gamma1_ * gap_m);
  const FieldSZ bx = SumHarmonicsFrom(amp.x_array_T, harmonics_, std::sin(gamma1_ * x_m), std::cos(gamma1_ * x_m), e1);
  const FieldSZ by = SumHarmonicsFrom(amp.y_array_T, harmonics_, std::sin(gamma1_ * y_m), std::cos(gamma1_ * y_m), e1);
  return {bx.b_s_T, by.b_s_T, bx.b_z_T + by.b_z_T};
}

namespace {

inline FieldSZ SumHarmonics(const double* amp, int harmonics, double gamma1, double s, double z) {
  const double th = gamma1 * s;
  return SumHarmonicsFrom(amp, harmonics, std::sin(th), std::cos(th), std::exp(-gamma1 * z));
}

}  // namespace

FieldSZ HalbachField::PointField(double s_m, double height_m) const {
  return SumHarmonics(point_amp_, harmonics_, gamma1_, s_m, height_m);
}

FieldSZ HalbachField::SideAverageField(double s_m, double gap_m) const {
  return SumHarmonics(side_amp_, harmonics_, gamma1_, s_m, gap_m);
}

double HalbachField::BStar(double gap_m) const { return m0_ * BStarPerM0(1, gap_m, config_); }

double HalbachField::HarmonicForceRatio(int n, double gap_m) const {
  return std::fabs(BStarPerM0(n, gap_m, config_) / BStarPerM0(1, gap_m, config_));
}

double HalbachField::C1(double gap_m) const {
  return m0_ * CnPerM0(1, config_) * std::exp(-gamma1_ * gap_m);
}

}  // namespace maglev::hil
