#include "maglev/pmlsm_plant/plant.hpp"

#include <algorithm>
#include <cmath>

namespace maglev::pmlsm_plant {

std::array<double, kMotors> AirGaps_m(const StageParams& p, const State& x) {
  const double r = p.radius_to_movers_r_m;
  return {x[0] - r * std::sin(x[6]), x[0] + r * std::sin(x[8]), x[0] + r * std::sin(x[6]),
          x[0] - r * std::sin(x[8])};
}

State Derivative(const StageParams& p, const ForceConstants& k, const State& x, const MotorCurrents& i) {
  const auto g = AirGaps_m(p, x);
  std::array<MotorForce, kMotors> f{};
  for (std::size_t m = 0; m < kMotors; ++m) f[m] = ComputeMotorForce(p.motor, k, g[m], i[m].d_A, i[m].q_A);
  const double c = p.guide_damping_per_s;
  State dx{};
  dx[0] = x[1];
  dx[1] = p.gravity_G_m_per_s2 + (f[0].vertical_N + f[1].vertical_N + f[2].vertical_N + f[3].vertical_N) / p.mass_y_kg -
          c * x[1];
  dx[2] = x[3];
  dx[3] = (f[1].horizontal_N + f[3].horizontal_N) / p.mass_x_kg - c * x[3];
  dx[4] = x[5];
  dx[5] = (f[0].horizontal_N + f[2].horizontal_N) / p.mass_z_kg - c * x[5];
  const double r = p.radius_to_movers_r_m;
  dx[6] = x[7];
  dx[7] = r * (f[2].vertical_N - f[0].vertical_N) / p.inertia_x_kg_m2 - p.guide_torsion_phi_per_s2 * x[6] - c * x[7];
  dx[8] = x[9];
  dx[9] = r * (f[1].vertical_N - f[3].vertical_N) / p.inertia_z_kg_m2 - p.guide_torsion_theta_per_s2 * x[8] -
          c * x[9];
  return dx;
}

Measurement MeasureEncoders(const EncoderParams& e, const State& x) {
  auto q = [](double v, double res) { return std::round(v / res) * res; };
  Measurement m;
  m.y = {q(x[0], e.translation_resolution_m), q(x[2], e.translation_resolution_m),
         q(x[4], e.translation_resolution_m), q(x[6], e.rotation_resolution_rad),
         q(x[8], e.rotation_resolution_rad)};
  return m;
}

Plant::Plant(const StageParams& p, const AmplifierParams& a, const EncoderParams& e)
    : p_(p), a_(a), e_(e), k_(ComputeForceConstants(p.motor)) {}

MotorCurrents Plant::Step(const MotorCurrents& command, double dt_s) {
  // Motors 2, 4 travel with X (x3); motors 1, 3 with Z (x5).
  const double th_x = ElectricalAngle_rad(p_.motor, x_[2]);
  const double th_z = ElectricalAngle_rad(p_.motor, x_[4]);
  MotorCurrents delivered{};
  saturated_ = false;
  for (std::size_t m = 0; m < kMotors; ++m) {
    const AmplifierOutput o = DriveMotor(a_, command[m], (m % 2 == 1) ? th_x : th_z);
    delivered[m] = o.delivered;
    saturated_ = saturated_ || o.saturated;
  }
  return Advance(delivered, dt_s);
}

MotorCurrents Plant::StepPhases(const std::array<PhaseCurrents, kMotors>& command, double dt_s) {
  const double th_x = ElectricalAngle_rad(p_.motor, x_[2]);
  const double th_z = ElectricalAngle_rad(p_.motor, x_[4]);
  MotorCurrents delivered{};
  saturated_ = false;
  for (std::size_t m = 0; m < kMotors; ++m) {
    PhaseCurrents ph = command[m];
    double peak = 0.0;
    for (double i : ph.abc_A) peak = std::max(peak, std::abs(i));
    if (peak > a_.phase_peak_A) {
      for (double& i : ph.abc_A) i *= a_.phase_peak_A / peak;
      saturated_ = true;
    }
    delivered[m] = ParkClarke(ph, (m % 2 == 1) ? th_x : th_z);
  }
  return Advance(delivered, dt_s);
}

std::array<std::int32_t, 5> Plant::EncoderCounts() const {
  auto q = [](double v, double res) { return static_cast<std::int32_t>(std::lround(v / res)); };
  return {q(x_[0], e_.translation_resolution_m), q(x_[2], e_.translation_resolution_m),
          q(x_[4], e_.translation_resolution_m), q(x_[6], e_.rotation_resolution_rad),
          q(x_[8], e_.rotation_resolution_rad)};
}

MotorCurrents Plant::Advance(const MotorCurrents& delivered, double dt_s) {
  auto add = [](const State& a, const State& b, double s) {
    State r{};
    for (std::size_t j = 0; j < r.size(); ++j) r[j] = a[j] + s * b[j];
    return r;
  };
  const State k1 = Derivative(p_, k_, x_, delivered);
  const State k2 = Derivative(p_, k_, add(x_, k1, dt_s / 2), delivered);
  const State k3 = Derivative(p_, k_, add(x_, k2, dt_s / 2), delivered);
  const State k4 = Derivative(p_, k_, add(x_, k3, dt_s), delivered);
  for (std::size_t j = 0; j < x_.size(); ++j) x_[j] += dt_s / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
  // Mechanical stops of the guides: inelastic.
  auto stop = [this](std::size_t pos, double lo, double hi) {
    if (x_[pos] < lo || x_[pos] > hi) {
      x_[pos] = std::clamp(x_[pos], lo, hi);
      x_[pos + 1] = 0.0;
    }
  };
  stop(0, p_.gap_min_m, p_.gap_max_m);
  stop(2, -p_.horizontal_range_m, p_.horizontal_range_m);
  stop(4, -p_.horizontal_range_m, p_.horizontal_range_m);
  return delivered;
}

}  // namespace maglev::pmlsm_plant
