#pragma once
// Numerical linearization of the nonlinear plant at the Table 2 nominal
// point (central differences), in the form of eq (13):
//   q'' + c q' + k q = b (currents)   per axis.
// Coils voltage-driven with L -> 0 (tau = L/R ~ 0.1 ms, far above the
// 2..5 Hz modes): a velocity changes the currents by -e/R, which is the
// damping of (9). Input gains are d(q'')/d(i) at fixed pose.
#include <array>

#include "maglev/selfstab_plant/params.hpp"
#include "maglev/selfstab_plant/plant.hpp"

namespace maglev::selfstab_plant {

struct Linearization {
  // -d(q_dd)/d(q) and -d(q_dd)/d(q_dot), full 6x6 (row: acceleration).
  std::array<std::array<double, 6>, 6> stiffness{};
  std::array<std::array<double, 6>, 6> damping{};
  // d(q_dd)/d(i_j), 6x9.
  std::array<std::array<double, kCoils>, 6> input{};
  // Per axis in the form of (13): diagonal c, k and the gain on the first
  // current of the bracket of (13).
  Eq13 axes{};
};
Linearization Linearize(const StageParams& p);

// Per-axis mode of q'' + c q' + k q = 0: natural frequency and damping ratio.
struct Mode {
  double frequency_Hz;
  double damping_ratio;
  double real_part_per_s;  // of the eigenvalue pair; < 0 is stable
};
Mode AxisMode(const AxisCoefficients& a);

// z force constant of the whole stage, dF_z/d(I_A + I_B + I_C)/3 per coil,
// at rotor height z (pose otherwise nominal) [N/A]: what a gain schedule
// over the z operating range needs.
double ZForceConstant_N_per_A(const StageParams& p, double z_m);

}  // namespace maglev::selfstab_plant
