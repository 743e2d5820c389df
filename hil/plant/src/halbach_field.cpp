#include "maglev/hil/halbach_field.hpp"

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
              : CalibrateM0(config, io::stage::kTwoBStarIdentified_N_per_A)),
      gamma1_(2.0 * kPi / config.pitch_m),
      harmonics_(config.harmonics < 1 ? 1 : (config.harmonics > kMaxHarmonics ? kMaxHarmonics : config.harmonics)) {
  for (int h = 0; h < kMaxHarmonics; ++h) {
    const int n = kHarmonicN[h];
    const double sign = (h % 2 == 0) ? 1.0 : -1.0;  // (-1)^k, n = 4k + 1
    point_amp_[h] = sign * m0_ * CnPerM0(n, config_);
    side_amp_[h] = point_amp_[h] * SideFactor(n, config_);
  }
}

namespace {

// sum_h amp[h] e^{-gamma_n z} (sin, cos)(gamma_n s) by recurrences: one
// sincos and one exp per call, whatever the number of harmonics.
inline FieldSZ SumHarmonicsFrom(const double* amp, int harmonics, double s1, double c1, double e1) {
  double bs = amp[0] * e1 * s1;
  double bz = amp[0] * e1 * c1;
  if (harmonics > 1) {
    // e^{j4 th}, e^{-4 gamma1 z}
    const double s2 = 2.0 * s1 * c1;
    const double c2 = c1 * c1 - s1 * s1;
    const double s4 = 2.0 * s2 * c2;
    const double c4 = c2 * c2 - s2 * s2;
    const double e2 = e1 * e1;
    const double e4 = e2 * e2;
    double sn = s1;
    double cn = c1;
    double en = e1;
    for (int h = 1; h < harmonics; ++h) {
      const double sn_next = sn * c4 + cn * s4;
      const double cn_next = cn * c4 - sn * s4;
      sn = sn_next;
      cn = cn_next;
      en *= e4;
      bs += amp[h] * en * sn;
      bz += amp[h] * en * cn;
    }
  }
  return {bs, bz};
}

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

FieldSZ HalbachField::SideAverageFieldFrom(double sin1, double cos1, double exp1) const {
  return SumHarmonicsFrom(side_amp_, harmonics_, sin1, cos1, exp1);
}

double HalbachField::BStar(double gap_m) const { return m0_ * BStarPerM0(1, gap_m, config_); }

double HalbachField::HarmonicForceRatio(int n, double gap_m) const {
  return std::fabs(BStarPerM0(n, gap_m, config_) / BStarPerM0(1, gap_m, config_));
}

double HalbachField::C1(double gap_m) const {
  return m0_ * CnPerM0(1, config_) * std::exp(-gamma1_ * gap_m);
}

}  // namespace maglev::hil
