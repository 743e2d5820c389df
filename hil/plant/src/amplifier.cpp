#include "maglev/plant/amplifier.hpp"

#include <algorithm>
#include <cmath>

#include "maglev/plant/rng.hpp"

namespace maglev::hil {
namespace {

// Paper 003 Table 1 (8 coils, PA12A): average desired current vs std of the
// measured current, both mA.
constexpr int kTablePoints = 5;
constexpr double kTableDesired_mA[kTablePoints] = {4.29, 12.62, 107.74, 213.40, 424.80};
constexpr double kTableStd_mA[kTablePoints] = {4.79, 4.82, 5.60, 7.09, 10.93};

// RkCurrent's weights for a first-order transient i = it + d exp(-w t) over
// one step h, x = w h: with A = (1 - e^-x) / x (the mean of exp(-w t)) and
// B = (x - 1 + e^-x) / x^2 (its (h - t)-weighted mean, / h^2), RK4's
// increments with the pose held are dv ~ (i0 + 4 i_mid + i_end) / 6 and
// dx - h v0 ~ h^2 (i0 + 2 i_mid) / 6; equal to the integrals when
// i_mid = it + d (3 B - 1/2) and i_end = it + d (6 A + 1 - 12 B).
// Small x: the series (the direct form cancels); both -> 1 as x -> 0.
void QuadratureWeights(double x, double* mid, double* end) {
  double a, b;
  if (x < 1e-3) {
    a = 1.0 - x / 2.0 + x * x / 6.0;
    b = 0.5 - x / 6.0 + x * x / 24.0;
  } else {
    const double one_minus_e = -std::expm1(-x);
    a = one_minus_e / x;
    b = (x - one_minus_e) / (x * x);
  }
  *mid = 3.0 * b - 0.5;
  *end = 6.0 * a + 1.0 - 12.0 * b;
}

}  // namespace

double Table1CurrentNoiseStd_A(double commanded_abs_A) {
  const double i_mA = std::fabs(commanded_abs_A) * 1e3;
  if (i_mA <= kTableDesired_mA[0]) {
    return kTableStd_mA[0] * 1e-3;
  }
  int k = 0;
  while (k < kTablePoints - 2 && i_mA > kTableDesired_mA[k + 1]) {
    ++k;
  }
  const double t = (i_mA - kTableDesired_mA[k]) / (kTableDesired_mA[k + 1] - kTableDesired_mA[k]);
  return (kTableStd_mA[k] + t * (kTableStd_mA[k + 1] - kTableStd_mA[k])) * 1e-3;
}

double ForceNoiseStd_A(const AmplifierConfig& config) {
  return config.current_noise_density_A_per_rtHz * std::sqrt(config.current_noise_bandwidth_Hz) *
         config.current_noise_scale;
}

double MonitorNoiseStd_A(const AmplifierConfig& config, double commanded_abs_A) {
  return MonitorNoiseStd_A(config, commanded_abs_A, ForceNoiseStd_A(config));
}

double MonitorNoiseStd_A(const AmplifierConfig& config, double commanded_abs_A, double force_noise_std_A) {
  double var = config.monitor_noise_A * config.monitor_noise_A;
  if (config.monitor_reproduces_table1) {
    const double total = Table1CurrentNoiseStd_A(commanded_abs_A);
    const double force = force_noise_std_A;
    var += std::max(0.0, total * total - force * force);
  }
  return std::sqrt(var);
}

double DacCodeToVolts(std::int16_t code, double full_scale_V) {
  return static_cast<double>(code) * (full_scale_V / 32768.0);
}

Amplifiers::Amplifiers(const AmplifierConfig& config)
    : config_(config),
      omega_(config.loop_transresistance_V_per_A / config.coil_inductance_H),
      v_max_(config.supply_voltage_V - config.output_dropout_V),
      force_noise_std_A_(ForceNoiseStd_A(config)) {
  for (int j = 0; j < kCoils; ++j) {
    bandwidth_spread_ = bandwidth_spread_ || config.bandwidth_error[j] != 0.0;
    omega_coil_[j] = omega_ * (1.0 + config.bandwidth_error[j]);
    k_coil_[j] = config.loop_transresistance_V_per_A * (1.0 + config.bandwidth_error[j]);
  }
}

double Amplifiers::bandwidth_Hz() const { return omega_ / (2.0 * io::stage::kPi); }

void Amplifiers::Apply(const io::ActuatorCommand& command, Rng* rng, bool noise_enabled) {
  enabled_ = command.amplifier_enable;
  for (int j = 0; j < kCoils; ++j) {
    const double v = DacCodeToVolts(command.dac_code[j], config_.dac_full_scale_V);
    commanded_[j] = config_.gain_A_per_V * v;
    // Draw the noise sample even when disabled: the random sequence then
    // does not depend on the enable line.
    const double n = (rng != nullptr && noise_enabled) ? rng->Normal() : 0.0;
    if (!enabled_) {
      target_[j] = 0.0;  // disabled output: the loop drives the coil to zero
      continue;
    }
    double t = commanded_[j] * (1.0 + config_.gain_error[j]) + config_.offset_A[j];
    t += n * force_noise_std_A_;
    target_[j] = std::clamp(t, -config_.current_limit_A, config_.current_limit_A);
  }
}

void Amplifiers::BeginSubstep(double h_s, bool exact_quadrature) {
  const double r = config_.coil_resistance_Ohm;
  const double l = config_.coil_inductance_H;
  const double k = config_.loop_transresistance_V_per_A;
  if (h_s != decay_h_s_) {
    decay_h_s_ = h_s;
    lin_half_ = std::exp(-omega_ * h_s / 2.0);
    sat_half_ = std::exp(-r / l * h_s / 2.0);
    for (int j = 0; j < kCoils; ++j) coil_lin_half_[j] = std::exp(-omega_coil_[j] * h_s / 2.0);
    QuadratureWeights(omega_ * h_s, &quad_mid_, &quad_end_);
    for (int j = 0; j < kCoils; ++j) QuadratureWeights(omega_coil_[j] * h_s, &coil_quad_mid_[j], &coil_quad_end_[j]);
  }
  const double lin_half = lin_half_;
  const double lin_full = lin_half * lin_half;
  const double sat_half = sat_half_;
  const double sat_full = sat_half * sat_half;
  for (int j = 0; j < kCoils; ++j) {
    const double i0 = current_[j];
    const double it = target_[j];
    double lh = lin_half, lf = lin_full, kj = k;
    if (bandwidth_spread_) {
      lh = coil_lin_half_[j];
      lf = lh * lh;
      kj = k_coil_[j];
    }
    const double v_demand = r * i0 + kj * (it - i0);
    stage_current_[0][j] = i0;
    rk_current_[0][j] = i0;
    if (std::fabs(v_demand) <= v_max_) {
      stage_current_[1][j] = it + (i0 - it) * lh;
      stage_current_[2][j] = it + (i0 - it) * lf;
      if (exact_quadrature) {
        const double qm = bandwidth_spread_ ? coil_quad_mid_[j] : quad_mid_;
        const double qe = bandwidth_spread_ ? coil_quad_end_[j] : quad_end_;
        rk_current_[1][j] = it + (i0 - it) * qm;
        rk_current_[2][j] = it + (i0 - it) * qe;
      } else {
        rk_current_[1][j] = stage_current_[1][j];
        rk_current_[2][j] = stage_current_[2][j];
      }
    } else {
      // Output at the rail: L di/dt = +-V_max - R i, never past the target.
      const double i_inf = std::copysign(v_max_, v_demand) / r;
      double i1 = i_inf + (i0 - i_inf) * sat_half;
      double i2 = i_inf + (i0 - i_inf) * sat_full;
      if (v_demand > 0.0) {
        i1 = std::min(i1, it);
        i2 = std::min(i2, it);
      } else {
        i1 = std::max(i1, it);
        i2 = std::max(i2, it);
      }
      stage_current_[1][j] = i1;
      stage_current_[2][j] = i2;
      // At the rail (clipped at the target): the samples (not reached by
      // the stage's +-5 A commands, docs/PLANT.md).
      rk_current_[1][j] = i1;
      rk_current_[2][j] = i2;
    }
  }
}

void Amplifiers::EndSubstep() {
  for (int j = 0; j < kCoils; ++j) {
    current_[j] = stage_current_[2][j];
  }
}

}  // namespace maglev::hil
