#include "maglev/pmlsm_plant/force_law.hpp"

#include <cmath>
#include <numbers>

namespace maglev::pmlsm_plant {
namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kMu0 = 4e-7 * std::numbers::pi;  // [H/m]
double Coth(double x) { return 1.0 / std::tanh(x); }
double Arg(const MotorParams& m, double gap_m) {
  return kPi / m.pole_pitch_tau_m * (m.pm_height_hm_m + gap_m);
}
}  // namespace

ForceConstants ComputeForceConstants(const MotorParams& m) {
  const double p2 = m.pole_pairs_p * m.pole_pairs_p;
  const double W = m.turns_per_phase_W;
  ForceConstants k{};
  k.Kv1 = m.pm_length_LA_m * m.pm_count_pm * m.pole_pitch_tau_m / (4.0 * kMu0);
  k.Kv2 = 3.0 * std::sqrt(2.0) * m.pm_length_LA_m * m.pm_count_pm * W * m.winding_factor_kw1 / p2;
  k.Kv3 = m.kv3_scale * 18.0 * m.pm_length_LA_m * m.pm_count_pm * W * W * m.winding_factor_kw1 *
          m.winding_factor_kw1 * kMu0 / (m.pole_pitch_tau_m * p2);
  k.Kh = 12.0 * std::sqrt(2.0) * W * m.winding_factor_kw1 * m.pm_count_pm * m.pm_length_LA_m *
         m.pm_coercivity_Hc_A_per_m * kMu0 * std::sinh(kPi / m.pole_pitch_tau_m * m.pm_height_hm_m) *
         std::sin(kPi * m.pm_width_taup_m / (2.0 * m.pole_pitch_tau_m)) / (kPi * m.pole_pairs_p);
  return k;
}

double Gamma1(const MotorParams& m, double gap_m) {
  const double a = m.slot_width_b0_m / (2.0 * gap_m);
  return 4.0 / kPi * (a * std::atan(a) - std::log(std::sqrt(1.0 + a * a)));
}

double CarterFactor_Kc(const MotorParams& m, double gap_m) {
  return m.slot_pitch_t1_m / (m.slot_pitch_t1_m - gap_m * Gamma1(m, gap_m));
}

double Lambda(const MotorParams& m, double gap_m) {
  const double b0 = m.slot_width_b0_m;
  return 1.0 - b0 * b0 /
                   (4.0 * m.slot_pitch_t1_m *
                    (gap_m + b0 / 2.0 + m.pm_height_hm_m / m.pm_recoil_permeability_mu_rec));
}

double PmField_B_T(const MotorParams& m, double gap_m) {
  const double tau = m.pole_pitch_tau_m;
  return 4.0 / kPi * kMu0 * m.pm_coercivity_Hc_A_per_m * std::sin(kPi * m.pm_width_taup_m / (2.0 * tau)) *
         std::sinh(kPi * m.pm_height_hm_m / tau) / std::sinh(Arg(m, gap_m));
}

double Lv1(const MotorParams& m, double gap_m) {
  const double b = PmField_B_T(m, gap_m);
  return Lambda(m, gap_m) * b * b;
}

double Lv2(const MotorParams& m, double gap_m) {
  return Lambda(m, gap_m) * PmField_B_T(m, gap_m) * Coth(Arg(m, gap_m)) / CarterFactor_Kc(m, gap_m);
}

double Lv3(const MotorParams& m, double gap_m) {
  const double c = Coth(Arg(m, gap_m));
  const double kc = CarterFactor_Kc(m, gap_m);
  return Lambda(m, gap_m) * c * c / (kc * kc);
}

double Lh(const MotorParams& m, double gap_m) {
  return Lambda(m, gap_m) / (CarterFactor_Kc(m, gap_m) * std::sinh(Arg(m, gap_m)));
}

MotorForce ComputeMotorForce(const MotorParams& m, const ForceConstants& k, double gap_m,
                             double i_d_A, double i_q_A) {
  MotorForce f{};
  f.horizontal_N = -k.Kh * Lh(m, gap_m) * i_q_A;
  f.vertical_N = -k.Kv1 * Lv1(m, gap_m) + k.Kv2 * Lv2(m, gap_m) * i_d_A -
                 k.Kv3 * Lv3(m, gap_m) * (i_d_A * i_d_A + i_q_A * i_q_A);
  return f;
}

bool HoverDirectCurrent_A(const MotorParams& m, const ForceConstants& k, double gap_m,
                          double weight_N, double* i_d_A) {
  // F_V(i_d) = -weight  <=>  -c3 i_d^2 + c2 i_d + (weight - c1) = 0.
  const double c1 = k.Kv1 * Lv1(m, gap_m);
  const double c2 = k.Kv2 * Lv2(m, gap_m);
  const double c3 = k.Kv3 * Lv3(m, gap_m);
  const double c0 = weight_N - c1;
  if (c3 == 0.0) {
    *i_d_A = -c0 / c2;
    return true;
  }
  const double disc = c2 * c2 + 4.0 * c3 * c0;
  if (disc < 0.0) return false;
  // Root continuous with the linear solution as c3 -> 0.
  *i_d_A = (c2 - std::sqrt(disc)) / (2.0 * c3);
  return true;
}

}  // namespace maglev::pmlsm_plant
