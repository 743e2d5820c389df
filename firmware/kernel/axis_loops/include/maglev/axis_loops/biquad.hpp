// Optional second-order filter stages in series with an axis loop's output
// (up to kMaxBiquadStages per axis): notch, 2nd-order low-pass, lead-lag.
// Designed at apply time in double by the bilinear (Tustin) transform with
// prewarping (the notch/low-pass centre, and each lead-lag corner, land at
// exactly the requested frequency), run in Scalar as direct form I:
//   y_k = b0 x_k + b1 x_{k-1} + b2 x_{k-2} - a1 y_{k-1} - a2 y_{k-2}
// with all five products summed in the wide accumulator (Q31.32 for fixed
// point, double for float) and rounded once. Direct form I keeps the states
// equal to past inputs/outputs, so they never overflow internally.
//
// Continuous prototypes (w0 prewarped):
//   notch     (s^2 + 2 zeta_z w0 s + w0^2) / (s^2 + 2 zeta_p w0 s + w0^2),
//             zeta_p = 1/(2Q), zeta_z = zeta_p * 10^(-depth_dB/20)
//   low-pass  w0^2 / (s^2 + (w0/Q) s + w0^2)
//   lead-lag  (1 + s/wz) / (1 + s/wp)      (unity dc gain)
#pragma once

#include "maglev/io/code_placement.hpp"
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "maglev/axis_loops/design_error.hpp"
#include "maglev/numeric/scalar_traits.hpp"
#include "maglev/numeric/elementary.hpp"

namespace maglev::kernel {

inline constexpr int kMaxBiquadStages = 2;

enum class BiquadType : std::uint8_t { kNone = 0, kNotch, kLowPass, kLeadLag };

struct BiquadConfig {
  BiquadType type = BiquadType::kNone;
  // Explicit, always zero: as padding these three bytes held stack garbage
  // from brace-initialized temporaries, and configurations compare byte by
  // byte (the kernel's "locked while levitated" check; GCC 12's
  // __builtin_clear_padding left them in a sanitizer build).
  std::uint8_t reserved[3] = {};
  float frequency_Hz = 0.0f;   // notch / low-pass: f0. lead-lag: zero frequency
  float q = 0.7071f;           // notch / low-pass quality factor
  float depth_dB = 0.0f;       // notch depth at f0 (>= 0); 0 dB = no notch
  float pole_Hz = 0.0f;        // lead-lag: pole frequency
};

template <typename Scalar>
struct BiquadCoefficients {
  // Taps that only enter the accumulator's MACs: the float kernel holds the
  // float taps' values as double (ScalarTraits<float>::AccCoeff, exact), one
  // conversion fewer per MAC; Q7.24 its Q3.28.
  using AccCoeff = typename numeric::ScalarTraits<Scalar>::AccCoeff;
  bool enabled = false;  // false: pass-through
  AccCoeff b0{}, b1{}, b2{}, a1{}, a2{};
};

template <typename Scalar>
struct BiquadState {
  Scalar x1{}, x2{}, y1{}, y2{};
};

// Double-precision design result (also used by tests for the exact response).
struct BiquadDesign {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0, a1 = 0.0, a2 = 0.0;
  bool enabled = false;
};

MAGLEV_CONFIG_CODE inline LoopDesignError design_biquad_double(const BiquadConfig& config, double servo_rate_Hz, BiquadDesign* out) {
  constexpr double kPi = 3.14159265358979323846;
  const double f0 = static_cast<double>(config.frequency_Hz);
  const double q = static_cast<double>(config.q);
  const double depth = static_cast<double>(config.depth_dB);
  const double fp = static_cast<double>(config.pole_Hz);
  if (!std::isfinite(f0) || !std::isfinite(q) || !std::isfinite(depth) || !std::isfinite(fp) ||
      !std::isfinite(servo_rate_Hz)) {
    return LoopDesignError::kNonFinite;
  }
  if (servo_rate_Hz <= 0.0) return LoopDesignError::kBadServoRate;
  BiquadDesign d;
  if (config.type == BiquadType::kNone) {
    *out = d;
    return LoopDesignError::kOk;
  }
  const double T = 1.0 / servo_rate_Hz;
  const double nyq = 0.5 * servo_rate_Hz;
  if (f0 <= 0.0 || f0 >= nyq) return LoopDesignError::kFilterAboveNyquist;
  const double K = 2.0 / T;  // s = K (z-1)/(z+1)
  auto warp = [&](double f) { return K * numeric::dtan(kPi * f * T); };
  // Bilinear of (n2 s^2 + n1 s + n0)/(d2 s^2 + d1 s + d0).
  auto bilinear = [&](double n2, double n1, double n0, double d2, double d1, double d0) {
    const double A0 = d2 * K * K + d1 * K + d0;
    d.b0 = (n2 * K * K + n1 * K + n0) / A0;
    d.b1 = (2.0 * n0 - 2.0 * n2 * K * K) / A0;
    d.b2 = (n2 * K * K - n1 * K + n0) / A0;
    d.a1 = (2.0 * d0 - 2.0 * d2 * K * K) / A0;
    d.a2 = (d2 * K * K - d1 * K + d0) / A0;
  };
  switch (config.type) {
    case BiquadType::kNotch: {
      if (q <= 0.0 || depth < 0.0) return LoopDesignError::kBadQuality;
      const double w0 = warp(f0);
      const double zp = 1.0 / (2.0 * q);
      const double zz = zp * numeric::dpow(10.0, -depth / 20.0);
      bilinear(1.0, 2.0 * zz * w0, w0 * w0, 1.0, 2.0 * zp * w0, w0 * w0);
      break;
    }
    case BiquadType::kLowPass: {
      if (q <= 0.0) return LoopDesignError::kBadQuality;
      const double w0 = warp(f0);
      bilinear(0.0, 0.0, w0 * w0, 1.0, w0 / q, w0 * w0);
      break;
    }
    case BiquadType::kLeadLag: {
      if (fp <= 0.0 || fp >= nyq) return LoopDesignError::kFilterAboveNyquist;
      const double wz = warp(f0);
      const double wp = warp(fp);
      bilinear(0.0, 1.0 / wz, 1.0, 0.0, 1.0 / wp, 1.0);
      break;
    }
    case BiquadType::kNone:
      break;
  }
  d.enabled = true;
  *out = d;
  return LoopDesignError::kOk;
}

template <typename Scalar>
MAGLEV_CONFIG_CODE LoopDesignError design_biquad(const BiquadConfig& config, double servo_rate_Hz, BiquadCoefficients<Scalar>* out) {
  using Traits = numeric::ScalarTraits<Scalar>;
  BiquadDesign d;
  const LoopDesignError err = design_biquad_double(config, servo_rate_Hz, &d);
  if (err != LoopDesignError::kOk) return err;
  const double all[] = {d.b0, d.b1, d.b2, d.a1, d.a2};
  for (double v : all) {
    if (!Traits::coeff_fits(v)) return LoopDesignError::kCoefficientOutOfRange;
  }
  BiquadCoefficients<Scalar> c;
  c.enabled = d.enabled;
  c.b0 = Traits::acc_coeff_from_double(d.b0);
  c.b1 = Traits::acc_coeff_from_double(d.b1);
  c.b2 = Traits::acc_coeff_from_double(d.b2);
  c.a1 = Traits::acc_coeff_from_double(d.a1);
  c.a2 = Traits::acc_coeff_from_double(d.a2);
  *out = c;
  return LoopDesignError::kOk;
}

// One tick of one stage. Disabled stages pass x through (and track it, so
// enabling a stage later starts from the current signal, not from zero).
template <typename Scalar>
Scalar biquad_update(const BiquadCoefficients<Scalar>& c, BiquadState<Scalar>& s, Scalar x) {
  using Traits = numeric::ScalarTraits<Scalar>;
  Scalar y = x;
  if (c.enabled) {
    auto acc = Traits::acc_zero();
    Traits::mac(acc, c.b0, x);
    Traits::mac(acc, c.b1, s.x1);
    Traits::mac(acc, c.b2, s.x2);
    Traits::mac(acc, c.a1, -s.y1);
    Traits::mac(acc, c.a2, -s.y2);
    y = Traits::acc_to_scalar(acc);
  }
  s.x2 = s.x1;
  s.x1 = x;
  s.y2 = s.y1;
  s.y1 = y;
  return y;
}

// Sets a stage's state to its steady state for a constant input x (dc gain g).
template <typename Scalar>
void biquad_reset(BiquadState<Scalar>& s, Scalar x, Scalar y) {
  s.x1 = s.x2 = x;
  s.y1 = s.y2 = y;
}

template <typename Scalar>
bool biquad_chain_enabled(const BiquadCoefficients<Scalar> (&c)[kMaxBiquadStages]) {
  bool any = false;
  for (const BiquadCoefficients<Scalar>& k : c) any = any || k.enabled;
  return any;
}

// The filter chains of kChains axes: each kMaxBiquadStages stages in series
// on its axis' loop output.
//
// A disabled stage passes its input through, and biquad_update() keeps its
// state anyway (x1 = y1 = its last input, x2 = y2 = the one before), so that
// a stage enabled later starts from the signal. With no stage of a chain
// enabled -- the default -- that is two stages' state updates per axis and
// tick for nothing read. Such a chain leaves its stages as they were and
// keeps only its input's last two values (`history`); reconfigure(), when one
// of its stages is enabled again, gives the stages the state running them
// would have left. That depends on the ticks since the last stage was
// disabled: none, the state as it was; one, x1 = y1 = that tick's input and
// x2 / y2 the old x1 / y1; two or more, the pass-through state of the last
// two inputs. The output is bit for bit that of running biquad_update() on
// every stage on every tick, for any sequence of configurations, several
// between one tick and the next included (test
// Biquad.BankSkippingPassThroughStagesEqualsTrackingEveryStage).
template <typename Scalar, std::size_t kChains>
class BiquadBank {
 public:
  // One tick of chain k: its coefficients c, `enabled` = biquad_chain_enabled(c).
  Scalar update(int k, const BiquadCoefficients<Scalar> (&c)[kMaxBiquadStages], bool enabled, Scalar x) {
    if (enabled) {
      for (int f = 0; f < kMaxBiquadStages; ++f) x = biquad_update(c[f], stage_[k][f], x);
      return x;
    }
    history_[k][1] = history_[k][0];
    history_[k][0] = x;
    return x;
  }

  // Once per tick, after the chains' update().
  void end_tick() { ++ticks_; }

  // Between ticks, when coefficients change: was[k] / now[k] are
  // biquad_chain_enabled() of chain k's old and new coefficients.
  void reconfigure(const bool (&was)[kChains], const bool (&now)[kChains]) {
    for (std::size_t k = 0; k < kChains; ++k) {
      if (was[k] && !now[k]) {
        disabled_at_[k] = ticks_;
      } else if (!was[k] && now[k]) {
        const std::uint64_t since = ticks_ - disabled_at_[k];
        const Scalar h0 = history_[k][0], h1 = history_[k][1];
        for (BiquadState<Scalar>& st : stage_[k]) {
          if (since == 1) {
            st = BiquadState<Scalar>{h0, st.x1, h0, st.y1};
          } else if (since >= 2) {
            st = BiquadState<Scalar>{h0, h1, h0, h1};
          }
        }
      }
    }
  }

 private:
  BiquadState<Scalar> stage_[kChains][kMaxBiquadStages]{};
  Scalar history_[kChains][2]{};
  std::uint64_t disabled_at_[kChains]{};  // ticks_ when the chain's last stage was disabled
  std::uint64_t ticks_ = 0;               // end_tick() calls (no wrap in 2^64 ticks)
};

}  // namespace maglev::kernel
