// The tests' OWN copy of paper 000's nominal force allocation, eqs (18),
// (21), (23), (24): i = 2 S_xy B U. Deliberately independent of the kernel's
// force_allocation module, so the plant is checked against the paper itself.
#pragma once

#include <Eigen/Dense>
#include <cmath>

#include "maglev/io/stage_parameters.hpp"

namespace maglev::hil::test {

using Matrix68 = Eigen::Matrix<double, 6, 8>;
using Matrix86 = Eigen::Matrix<double, 8, 6>;
using Matrix8 = Eigen::Matrix<double, 8, 8>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using Vector8 = Eigen::Matrix<double, 8, 1>;

// Eq (18): [Fx Fy Tz Fz Tx Ty] = A [F12x F12z F34y F34z F56x F56z F78y F78z].
inline Matrix68 AllocationA() {
  const double l = io::stage::kLeverArm_m;
  Matrix68 a;
  a << 1, 0, 0, 0, 1, 0, 0, 0,  //
      0, 0, 1, 0, 0, 0, 1, 0,   //
      l, 0, l, 0, -l, 0, -l, 0,  //
      0, 1, 0, 1, 0, 1, 0, 1,   //
      0, -l, 0, 0, 0, l, 0, 0,  //
      0, 0, 0, -l, 0, 0, 0, l;
  return a;
}

// Eq (21): B = pinv(A) (A has full row rank).
inline Matrix86 AllocationB() {
  const Matrix68 a = AllocationA();
  return a.transpose() * (a * a.transpose()).inverse();
}

// Eq (19) matrix (forces per unit b*): F = b* S19 i.
inline Matrix8 S19(double x2, double y8) {
  const double g = io::stage::kGamma1_per_m;
  const double sx = std::sin(g * x2), cx = std::cos(g * x2);
  const double sy = std::sin(g * y8), cy = std::cos(g * y8);
  Matrix8 s = Matrix8::Zero();
  s(0, 0) = sx;  s(0, 1) = -cx;
  s(1, 0) = cx;  s(1, 1) = sx;
  s(2, 2) = cy;  s(2, 3) = sy;
  s(3, 2) = -sy; s(3, 3) = cy;
  s(4, 4) = cx;  s(4, 5) = -sx;
  s(5, 4) = -sx; s(5, 5) = -cx;
  s(6, 6) = -sy; s(6, 7) = -cy;
  s(7, 6) = -cy; s(7, 7) = sy;
  return s;
}

// Eq (23) matrix S_xy (without the 1/b* factor): i = S23 F / b*.
inline Matrix8 S23(double x2, double y8) {
  const double g = io::stage::kGamma1_per_m;
  const double sx = std::sin(g * x2), cx = std::cos(g * x2);
  const double sy = std::sin(g * y8), cy = std::cos(g * y8);
  Matrix8 s = Matrix8::Zero();
  s(0, 0) = sx;  s(0, 1) = cx;
  s(1, 0) = -cx; s(1, 1) = sx;
  s(2, 2) = cy;  s(2, 3) = -sy;
  s(3, 2) = sy;  s(3, 3) = cy;
  s(4, 4) = cx;  s(4, 5) = -sx;
  s(5, 4) = -sx; s(5, 5) = -cx;
  s(6, 6) = -sy; s(6, 7) = -cy;
  s(7, 6) = -cy; s(7, 7) = sy;
  return s;
}

// Eq (24): i = 2 S_xy B U, commutated at the platen's base points.
inline Vector8 CurrentsFromEffort(const Vector6& u, double x, double y) {
  return 2.0 * S23(x + io::stage::kBasePointX2_m, y + io::stage::kBasePointY8_m) * AllocationB() * u;
}

// Currents -> DAC codes (0.5 A/V, +-10 V, 16 bit), rounding to nearest.
inline short DacCode(double current_A) {
  const double code = std::nearbyint(current_A / io::stage::kAmplifierGain_A_per_V / io::stage::kDacFullScale_V * 32768.0);
  return static_cast<short>(code > 32767.0 ? 32767.0 : (code < -32768.0 ? -32768.0 : code));
}

}  // namespace maglev::hil::test
