// The loop check: crossover and phase margin of one axis' PID loop on its
// plant, so the kernel can refuse gains that would not hold the stage (a
// z.kp of 1e7 once saturated the coils while the status said Ready).
//
// L(jw) = (kp + ki/(jw) + kd jw / (1 + jw/wf)) e^{-jw T/2} g / (k - w^2 + j c w):
// the PID's feedback part, the half-tick hold (the output of tick n is
// applied during tick n) and the axis plant y'' + c y' + k y = g u. A
// logarithmic scan from 0.1 Hz to the Nyquist rate (constant work, double,
// heap-free); the last downward crossing of |L| = 1 is the crossover.
// The axis' output filters (biquad stages: notch, low-pass, lead-lag) are in
// the loop, so their discrete response H(e^{jwT}) multiplies L: a low-pass
// set too low is refused like a gain that is too high.
#pragma once

#include "maglev/axis_loops/biquad.hpp"
#include "maglev/axis_loops/pid2dof.hpp"

namespace maglev::kernel {

struct LoopMargins {
  bool crossover_found = false;
  double crossover_Hz = 0.0;
  double phase_margin_deg = 0.0;
  // The extra loop delay that would use up the phase margin at the
  // crossover, in servo ticks: PM / (360 deg * crossover / servo rate).
  double delay_margin_ticks = 0.0;
};

struct LoopPlant {
  double gain;             // m/s^2 (rad/s^2) per A of effort
  double damping_per_s;    // c
  double stiffness_per_s2; // k
};

// `filters`: the axis' biquad stages in series (kNone stages are skipped),
// nullptr for none. A stage that cannot be designed gives no crossover.
LoopMargins Pid2DofLoopMargins(const Pid2DofConfig& pid, const LoopPlant& plant, double servo_rate_Hz,
                               const BiquadConfig* filters = nullptr, int filter_count = 0);

// A loop the kernel accepts: it crosses over below the Nyquist rate with a
// phase margin of at least kMinPhaseMargin_deg, and that margin is worth at
// least kMinDelayMargin_ticks of extra delay.
//
// Why a delay margin: the model holds the half-tick hold only, and the real
// loop has more lag (the computation tick, the amplifiers' current loop, a
// CAN frame that arrives a tick late). Phase margin alone let theta_x gains
// x20 through (52 deg, but at 285 Hz: 1.27 ticks of delay margin); on the
// bench they held until one actuator frame came a tick late (a CAN reorder),
// then oscillated and landed at 1.7-3.4 mm/s (campaign seed 1, run 3013).
// Measured on that run with theta_x kp and kd scaled by k: x10 (3.16 ticks)
// rides through the late frames; x12 (2.54 ticks) oscillates into a
// following error; x15 (1.91 ticks) touches down at 1.3 mm/s. Every default
// loop has at least 3.99 ticks (x, y, theta_z), docs/RELIABILITY.md.
inline constexpr double kMinPhaseMargin_deg = 10.0;
inline constexpr double kMinDelayMargin_ticks = 3.0;
inline bool LoopIsAcceptable(const LoopMargins& m) {
  return m.crossover_found && m.phase_margin_deg >= kMinPhaseMargin_deg &&
         m.delay_margin_ticks >= kMinDelayMargin_ticks;
}

}  // namespace maglev::kernel
