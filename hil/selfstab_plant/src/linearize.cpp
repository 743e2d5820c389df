// Central-difference linearization of the nonlinear plant (linearize.hpp).
#include "maglev/selfstab_plant/linearize.hpp"

#include <cmath>
#include <cstddef>

namespace maglev::selfstab_plant {

using std::size_t;

Linearization Linearize(const StageParams& p) {
  Linearization L;
  const Pose pose0{};
  const std::array<double, 6> zero{};
  const CoilVector i0 = NominalCurrents(p);
  const CoilVector u0 = NominalVoltages(p);
  // Steps: 1 um / 1 urad. The force law is smooth on the mm scale, so the
  // truncation error is ~(1e-6 / 1e-2)^2 and round-off ~1e-16 / 1e-6.
  const double h = 1e-6;
  for (size_t k = 0; k < 6; ++k) {
    Pose a = pose0, b = pose0;
    a[k] += h;
    b[k] -= h;
    const auto fa = Accelerations(p, a, zero, i0);
    const auto fb = Accelerations(p, b, zero, i0);
    for (size_t r = 0; r < 6; ++r) L.stiffness[r][k] = -(fa[r] - fb[r]) / (2 * h);
  }
  for (size_t k = 0; k < 6; ++k) {
    std::array<double, 6> va{}, vb{};
    va[k] = h;
    vb[k] = -h;
    // Voltage-driven coils, L -> 0: the velocity changes the currents by -e/R.
    const auto fa = Accelerations(p, pose0, va, QuasiStaticCurrents(p, pose0, va, u0));
    const auto fb = Accelerations(p, pose0, vb, QuasiStaticCurrents(p, pose0, vb, u0));
    for (size_t r = 0; r < 6; ++r) L.damping[r][k] = -(fa[r] - fb[r]) / (2 * h);
  }
  const double hi = 1e-4;  // A; the force is linear in the current
  for (size_t j = 0; j < kCoils; ++j) {
    CoilVector a = i0, b = i0;
    a[j] += hi;
    b[j] -= hi;
    const auto fa = Accelerations(p, pose0, zero, a);
    const auto fb = Accelerations(p, pose0, zero, b);
    for (size_t r = 0; r < 6; ++r) L.input[r][j] = (fa[r] - fb[r]) / (2 * hi);
  }
  // The first current of each bracket of (13).
  const size_t first[6] = {kDm, kDm, kA, kA, kB, kDm};
  for (size_t r = 0; r < 6; ++r) {
    L.axes[r].damping_per_s = L.damping[r][r];
    L.axes[r].stiffness_per_s2 = L.stiffness[r][r];
    L.axes[r].gain = L.input[r][first[r]];
  }
  return L;
}

Mode AxisMode(const AxisCoefficients& a) {
  const double wn = std::sqrt(a.stiffness_per_s2);
  Mode m{};
  m.frequency_Hz = wn / (2.0 * 3.14159265358979323846);
  m.damping_ratio = a.damping_per_s / (2.0 * wn);
  m.real_part_per_s = -0.5 * a.damping_per_s;
  return m;
}

double ZForceConstant_N_per_A(const StageParams& p, double z_m) {
  Pose pose{};
  pose[2] = z_m;
  const std::array<double, 6> zero{};
  CoilVector a{}, b{};
  const double hi = 1e-3;
  a[kA] = a[kB] = a[kC] = hi;
  const double fa = Accelerations(p, pose, zero, a)[2];
  const double fb = Accelerations(p, pose, zero, b)[2];
  return (fa - fb) * p.mass_kg / (3.0 * hi);
}

}  // namespace maglev::selfstab_plant
