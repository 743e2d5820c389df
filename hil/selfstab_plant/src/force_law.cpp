// Eq (4) of paper 001 and the interaction built on it (see force_law.hpp).
#include "maglev/selfstab_plant/force_law.hpp"

#include <cmath>

namespace maglev::selfstab_plant {
namespace {

constexpr double kMu0 = 4e-7 * 3.14159265358979323846;

// (4) is C [f(s + l/2) - f(s - l/2)] with
//   f(u) = u ln((R + sqrt(R^2+u^2)) / (r + sqrt(r^2+u^2))),
//   C = mu0 N / (2 l (R - r)).
// Its derivatives in closed form (S_x = sqrt(x^2 + u^2)):
//   f'(u)  = ln((R+S_R)/(r+S_r)) - R/S_R + r/S_r
//   f''(u) = u/(S_R (R+S_R)) - u/(S_r (r+S_r)) + R u/S_R^3 - r u/S_r^3
double F0(double u, double R, double r) {
  const double SR = std::sqrt(R * R + u * u);
  const double Sr = std::sqrt(r * r + u * u);
  return u * std::log((R + SR) / (r + Sr));
}
double F1(double u, double R, double r) {
  const double SR = std::sqrt(R * R + u * u);
  const double Sr = std::sqrt(r * r + u * u);
  return std::log((R + SR) / (r + Sr)) - R / SR + r / Sr;
}
double F2(double u, double R, double r) {
  const double SR = std::sqrt(R * R + u * u);
  const double Sr = std::sqrt(r * r + u * u);
  return u / (SR * (R + SR)) - u / (Sr * (r + Sr)) + R * u / (SR * SR * SR) - r * u / (Sr * Sr * Sr);
}
double Scale(const SolenoidParams& c) {
  return kMu0 * c.turns_N / (2.0 * c.length_l_m * (c.outer_radius_R_m - c.inner_radius_r_m));
}
double StretchedS(const SolenoidParams& c, double s_m) {
  return c.nominal_position_m + c.gradient_stretch_sigma * (s_m - c.nominal_position_m);
}

}  // namespace

double FieldOnAxis_T_per_A(const SolenoidParams& c, double s) {
  const double h = 0.5 * c.length_l_m;
  return Scale(c) * (F0(s + h, c.outer_radius_R_m, c.inner_radius_r_m) -
                     F0(s - h, c.outer_radius_R_m, c.inner_radius_r_m));
}
double FieldGradient_T_per_A_m(const SolenoidParams& c, double s) {
  const double h = 0.5 * c.length_l_m;
  return Scale(c) * (F1(s + h, c.outer_radius_R_m, c.inner_radius_r_m) -
                     F1(s - h, c.outer_radius_R_m, c.inner_radius_r_m));
}
double FieldCurvature_T_per_A_m2(const SolenoidParams& c, double s) {
  const double h = 0.5 * c.length_l_m;
  return Scale(c) * (F2(s + h, c.outer_radius_R_m, c.inner_radius_r_m) -
                     F2(s - h, c.outer_radius_R_m, c.inner_radius_r_m));
}
double FieldThirdDerivative_T_per_A_m3(const SolenoidParams& c, double s) {
  // Only used in the O(rho^2) term of the axial force: a central difference
  // of the closed-form b'' is ample (relative error ~1e-8 at h = 1 um).
  const double h = 1e-6;
  return (FieldCurvature_T_per_A_m2(c, s + h) - FieldCurvature_T_per_A_m2(c, s - h)) / (2.0 * h);
}

PairInteraction ComputePair(const SolenoidParams& c, double m, double kappa, double s, double rho) {
  const double sig = c.gradient_stretch_sigma;
  const double sh = StretchedS(c, s);
  const double b = FieldOnAxis_T_per_A(c, sh);
  const double b1 = FieldGradient_T_per_A_m(c, sh);
  const double b2 = FieldCurvature_T_per_A_m2(c, sh);
  const double rho2 = rho * rho;
  PairInteraction p{};
  p.flux_linkage_Wb = -m * (b / sig - 0.5 * kappa * sig * rho2 * b2);
  // d/ds: b(s_hat)/sigma -> b'; sigma b''(s_hat) -> sigma^2 b'''.
  double ds = -m * b1;
  if (rho2 > 0.0) ds += m * 0.5 * kappa * sig * sig * rho2 * FieldThirdDerivative_T_per_A_m3(c, sh);
  p.dlambda_ds_Wb_per_m = ds;
  p.dlambda_drho_over_rho_Wb_per_m2 = m * kappa * sig * b2;
  p.field_axial_T_per_A = b;
  p.field_gradient_T_per_A_m = sig * b1;
  return p;
}

double ForceConstant_N_per_A(const SolenoidParams& c, double m, double s) {
  return -m * FieldGradient_T_per_A_m(c, StretchedS(c, s));
}
double AxialStiffness_N_per_m(const SolenoidParams& c, double m, double s, double i) {
  return m * i * c.gradient_stretch_sigma * FieldCurvature_T_per_A_m2(c, StretchedS(c, s));
}
double EmfDamping_N_s_per_m(const SolenoidParams& c, double m, double s, double R) {
  const double ki = ForceConstant_N_per_A(c, m, s);
  return ki * ki / R;
}
double ForceConstantRatio(const SolenoidParams& c, double m, double offset) {
  return ForceConstant_N_per_A(c, m, c.nominal_position_m + offset) /
         ForceConstant_N_per_A(c, m, c.nominal_position_m);
}

}  // namespace maglev::selfstab_plant
