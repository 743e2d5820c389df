// The linear Halbach array's field, paper 000 eqs (1)-(3), and the Lorentz
// force on one rectangular coil side, eqs (5)-(7).
//
// The magnet matrix is modelled as two superimposed linear arrays (ours, per
// the task): an "X array" whose field varies along X and an "Y array" whose
// field varies along Y. A coil side running along Y' (the Fx coils 1,2,5,6)
// only sees the X array (the Y array's field averages out over its length p),
// and the reverse for coil sides along X' (the Fy coils 3,4,7,8).
//
// Along the varying coordinate s (X or Y), with q_n = (-1)^k c_n:
//   B_s(s, z) = sum_k q_n(z) sin(gamma_n s)        eq (1)
//   B_z(s, z) = sum_k q_n(z) cos(gamma_n s)        eq (2)
//   c_n(z)    = 2 sqrt2 mu0 M0 / (pi n) (1 - e^{-gamma_n Delta}) e^{-gamma_n z}   eq (3)
#pragma once

#include <cmath>

#include "maglev/plant/plant_config.hpp"

namespace maglev::hil {

inline constexpr int kMaxHarmonics = 4;  // n = 1, 5, 9, 13

// Field components (along the array's varying axis s, and vertical z), T.
struct FieldSZ {
  double b_s_T;
  double b_z_T;
};

// World field components of the whole magnet matrix (X array + Y array), T.
struct FieldXYZ {
  double b_x_T;
  double b_y_T;
  double b_z_T;
};

// Per-harmonic amplitudes (T, SumHarmonicsFrom order) of the field a straight
// coil side sees on average when it runs along u = (cos phi, sin phi) at any
// angle phi to X (the triangle's oblique forcers). The side's length p along
// u and its width a across it project onto X by |cos phi| p and |sin phi| a,
// onto Y by |sin phi| p and |cos phi| a; the mean of sin/cos(gamma_n s) over a
// segment whose projection onto s has length w is the value at its midpoint
// times sin(gamma_n w / 2) / (gamma_n w / 2), exactly, and the rectangle's
// mean is the product of its two segments' factors.
struct ObliqueSideAmplitudes {
  double x_array_T[kMaxHarmonics];
  double y_array_T[kMaxHarmonics];
};

// sum_h amp[h] e^{-gamma_n z} (sin, cos)(gamma_n s) from sin/cos(gamma_1 s)
// and e^{-gamma_1 z} by recurrences (n = 1, 5, 9, 13: steps of e^{j 4 theta}).
inline FieldSZ SumHarmonicsFrom(const double* amp, int harmonics, double s1, double c1, double e1) {
  double bs = amp[0] * e1 * s1;
  double bz = amp[0] * e1 * c1;
  if (harmonics > 1) {
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

class HalbachField {
 public:
  explicit HalbachField(const FieldConfig& config);

  // Point field of one linear array at coordinate s and height z above the
  // magnets' top surface (Hall sensors).
  FieldSZ PointField(double s_m, double height_m) const;
  // PointField at several s for one height: PointDecay(height) once, then
  // PointFieldAt(s, decay) equals PointField(s, height) bit for bit.
  double PointDecay(double height_m) const { return std::exp(-gamma1_ * height_m); }
  FieldSZ PointFieldAt(double s_m, double decay) const {
    const double th = gamma1_ * s_m;
    return PointFieldFrom(std::sin(th), std::cos(th), decay);
  }
  // The same from sin/cos(gamma_1 s) already known (the plant derives the
  // Hall sensors' from the previous sample's).
  FieldSZ PointFieldFrom(double sin1, double cos1, double decay) const {
    return SumHarmonicsFrom(point_amp_, harmonics_, sin1, cos1, decay);
  }

  // Field averaged over a coil side's cross-section (width a centred at s,
  // from gap g to g + d). N * I * p * (u x B_avg) is then exactly the volume
  // integral of eqs (5)-(7) for a straight side of effective length p.
  FieldSZ SideAverageField(double s_m, double gap_m) const;
  // The same from sin/cos(gamma_1 s) and exp(-gamma_1 gap) already known
  // (the plant derives them per forcer to save transcendental calls).
  FieldSZ SideAverageFieldFrom(double sin1, double cos1, double exp1) const {
    return SumHarmonicsFrom(side_amp_, harmonics_, sin1, cos1, exp1);
  }

  // Amplitudes for a side along (cos phi, sin phi), see ObliqueSideAmplitudes.
  // Along Y (cos phi = 0) the X array's equal side_amplitudes_T() up to
  // round-off; the Y array's then have the factor sin(gamma_n p/2)/(gamma_n p/2),
  // which a coil's two sides (same y, opposite currents) cancel.
  ObliqueSideAmplitudes ObliqueAmplitudes(double cos_phi, double sin_phi) const;
  // The matrix's field averaged over such a side (midpoint at world x, y; the
  // cross-section's bottom at gap above the magnets). N * I * p * (u x B_avg)
  // is then the exact integral of I dl x B over the side's volume.
  FieldXYZ ObliqueSideField(const ObliqueSideAmplitudes& amp, double x_m, double y_m, double gap_m) const;

  // b*(z) of eq (20) with n = 1 only, N/A (force amplitude of one coil).
  double BStar(double gap_m) const;
  // Amplitude of harmonic n's contribution to one coil's force, relative to
  // the fundamental, at gap z (the paper's own check below eq (9)).
  double HarmonicForceRatio(int n, double gap_m) const;
  // c_1(z) of eq (3), T.
  double C1(double gap_m) const;

  double peak_magnetization_A_per_m() const { return m0_; }
  // Side-averaged amplitude of each harmonic (T), in SumHarmonicsFrom order.
  const double* side_amplitudes_T() const { return side_amp_; }
  double gamma1_per_m() const { return gamma1_; }
  int harmonics() const { return harmonics_; }

  // M0 such that 2 b*(z0) = two_b_star, eq (20) inverted.
  static double CalibrateM0(const FieldConfig& config, double two_b_star_N_per_A);

 private:
  FieldConfig config_;
  double m0_;
  double gamma1_;
  int harmonics_;
  // Per harmonic: signed amplitude (-1)^k c_n(0) for point and side-averaged field.
  double point_amp_[kMaxHarmonics];
  double side_amp_[kMaxHarmonics];
  // Thickness factor (1 - e^{-gamma_n d}) / (gamma_n d) times point_amp_.
  double thick_amp_[kMaxHarmonics];
};

}  // namespace maglev::hil
