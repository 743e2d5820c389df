// Eight linear current amplifiers (PA12A-like) driving the coils.
//
// DAC code (AD5764, 16-bit two's complement over +-10 V) -> voltage ->
// commanded current i_c = gain * V -> per-amplifier gain/offset error and
// paper 003 Table 1 current noise -> current limit -> current loop.
//
// Current loop (ours): PI compensator whose zero cancels the coil pole R/L,
// so the loop gain is K/(L s) and the closed loop is first order,
//   di/dt = (K/L) (i_target - i),   bandwidth f_i = K / (2 pi L)
// as long as the required coil voltage R i + K (i_target - i) fits inside the
// output swing (supply - dropout); beyond that the output saturates and
//   L di/dt = +-V_max - R i.
// The loop is integrated in closed form (it is far too fast for the
// mechanical RK4 step), piecewise per sub-step.
#pragma once

#include <cstdint>

#include "maglev/plant/plant_config.hpp"
#include "maglev/io/actuator_command.hpp"

namespace maglev::hil {

class Rng;

// Paper 003 Table 1: std of the measured current (A) at commanded |i| (A),
// linearly interpolated, held below the first point, extrapolated linearly
// above the last.
double Table1CurrentNoiseStd_A(double commanded_abs_A);

// Std of the force-producing current noise per servo tick (A):
// density * sqrt(bandwidth) * scale (AmplifierConfig).
double ForceNoiseStd_A(const AmplifierConfig& config);

// Std of the monitor chain's own noise at |commanded| (A): such that the
// monitored current's total std equals Table 1 (when enabled), plus
// monitor_noise_A in quadrature.
double MonitorNoiseStd_A(const AmplifierConfig& config, double commanded_abs_A);
// The same with ForceNoiseStd_A(config) given (Amplifiers::force_noise_std_A,
// computed once): the servo path's 8 monitor draws per tick.
double MonitorNoiseStd_A(const AmplifierConfig& config, double commanded_abs_A, double force_noise_std_A);

// AD5764: code -> volts (two's complement, -32768 -> -FS, 32767 -> FS*(1-2^-15)).
double DacCodeToVolts(std::int16_t code, double full_scale_V);

class Amplifiers {
 public:
  explicit Amplifiers(const AmplifierConfig& config);

  // New DAC command for the coming tick (zero-order hold). Draws the tick's
  // current-noise sample from rng when noise is enabled.
  void Apply(const io::ActuatorCommand& command, Rng* rng, bool noise_enabled);

  // Piecewise closed-form integration. BeginSubstep fixes each coil's regime
  // (linear / saturated) from its current at the sub-step start.
  // exact_quadrature: also form RkCurrent (below).
  void BeginSubstep(double h_s, bool exact_quadrature = false);
  // Current at stage 0 (t0), 1 (t0 + h/2), 2 (t0 + h) of the sub-step.
  double CurrentAt(int coil, int stage) const { return stage_current_[stage][coil]; }
  // The currents RK4 should evaluate its stages with (stage 0: k1, 1: k2 and
  // k3, 2: k4) so that, the pose held, the step's velocity and position
  // increments are the exact integrals of the closed-form current
  // (int i dt and int (h - t) i dt) instead of their Simpson samples: a
  // 5 kHz current loop settles in ~100 us, so the samples at 0, h/2, h see
  // the 400 us tick's transient as 2.1x longer than it is (docs/PERFORMANCE.md).
  // Stage 0 is the physical i(t0); stages 1, 2 are not physical samples.
  // Without exact_quadrature (or for a coil at the rail) = CurrentAt.
  double RkCurrent(int coil, int stage) const { return rk_current_[stage][coil]; }
  void EndSubstep();

  double current_A(int coil) const { return current_[coil]; }
  double commanded_A(int coil) const { return commanded_[coil]; }  // gain * V_dac
  double target_A(int coil) const { return target_[coil]; }
  bool enabled() const { return enabled_; }
  double bandwidth_Hz() const;
  double force_noise_std_A() const { return force_noise_std_A_; }
  void set_current(int coil, double current_A) { current_[coil] = current_A; }

 private:
  AmplifierConfig config_;
  double omega_;   // K / L
  // As built: per-coil loop gain K (1 + bandwidth_error[j]) (all equal to K
  // when the errors are 0; the one-exp path is then kept).
  bool bandwidth_spread_ = false;
  double omega_coil_[kCoils] = {};
  double k_coil_[kCoils] = {};
  double v_max_;   // supply - dropout
  double force_noise_std_A_;  // per tick
  double current_[kCoils] = {};
  double commanded_[kCoils] = {};
  double target_[kCoils] = {};
  double stage_current_[3][kCoils] = {};
  double rk_current_[3][kCoils] = {};
  bool enabled_ = false;
  // BeginSubstep's decay factors for the last step length (every sub-step of
  // a run has the same h): the same exp() calls, made once per h.
  double decay_h_s_ = -1.0;
  double lin_half_ = 1.0;
  double sat_half_ = 1.0;
  double coil_lin_half_[kCoils] = {};
  // Exact-quadrature weights for the last step length: stage 1 / stage 2
  // current = target + (i0 - target) * c (RkCurrent).
  double quad_mid_ = 1.0, quad_end_ = 1.0;
  double coil_quad_mid_[kCoils] = {};
  double coil_quad_end_[kCoils] = {};
};

}  // namespace maglev::hil
