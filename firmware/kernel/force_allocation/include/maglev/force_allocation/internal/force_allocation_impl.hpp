// Template bodies of force_allocation.hpp (included at its end).
#pragma once

#include "maglev/io/code_placement.hpp"
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "maglev/numeric/dac_code.hpp"
#include "maglev/numeric/fixed.hpp"
#include "maglev/numeric/int64_double.hpp"
#include "maglev/numeric/saturation.hpp"
#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

namespace detail_fa {
ForceAllocationError FillCommon(const ForceAllocationConfig& c, const ForceAllocationTablesDouble& t,
                                CommutationTables* ct);

template <typename Scalar>
constexpr Scalar AbsScalar(Scalar v) {
  if constexpr (!numeric::ScalarTraits<Scalar>::kIsFixed) {
    // VABS, one instruction on the M7 (the compare-and-negate is four); its
    // one use, MaxScalar(m, |h|), gives the same for every h, NaN included.
    return __builtin_fabsf(v);
  } else {
    return v < numeric::ScalarTraits<Scalar>::zero() ? -v : v;
  }
}
template <typename Scalar>
constexpr Scalar MaxScalar(Scalar a, Scalar b) {
  if constexpr (!numeric::ScalarTraits<Scalar>::kIsFixed) {
    // VMAXNM, one instruction on the M7 (the compare and select are three).
    // The same value as a < b ? b : a wherever it is used: a is never NaN
    // (a running maximum from +0, or the positive peak), a NaN b gives a
    // either way, and the two differ only in which of two equal values they
    // return (+0 and -0 cannot meet: b is an |h| or the positive peak).
    return __builtin_fmaxf(a, b);
  } else {
    return a < b ? b : a;
  }
}
// Fixed::dot3 for the allocation's sums of B x signal products. When every
// |B| is below 32 (ForceAllocationState::b_below_32) each product is below
// 2^60 (a g x one() term below 2^55), so the exact sum cannot overflow and
// dot3's saturating add is skipped: the same value.
template <typename Scalar>
Scalar Dot3(bool b_below_32, Scalar a0, Scalar b0, Scalar a1, Scalar b1, Scalar a2, Scalar b2) {
  if (b_below_32) {
    return Scalar::template round_product_sum<Scalar::kFracBits>(
        numeric::detail::product_sum2(a0.raw(), b0.raw(), a1.raw(), b1.raw()) + std::int64_t{a2.raw()} * b2.raw());
  }
  return Scalar::dot3(a0, b0, a1, b1, a2, b2);
}

}  // namespace detail_fa

template <typename Scalar>
MAGLEV_CONFIG_CODE ForceAllocationError ApplyForceAllocationConfig(const ForceAllocationConfig& config,
                                                ForceAllocationState<Scalar>* state) {
  using Traits = numeric::ScalarTraits<Scalar>;
  ForceAllocationState<Scalar> s{};
  ForceAllocationError e = ComputeForceAllocationTables(config, &s.tables);
  if (e != ForceAllocationError::kOk) return e;
  e = detail_fa::FillCommon(config, s.tables, &s.commutation);
  if (e != ForceAllocationError::kOk) return e;
  // Every Scalar constant must be representable (Q7.24: |v| < 128) and not
  // lose more than 1e-4 of itself to quantisation when non-zero.
  const auto fits = [](double v) { return v < Traits::kMaxMagnitude && v > -Traits::kMaxMagnitude; };
  s.b_below_32 = true;
  for (int r = 0; r < kForcerForces; ++r)
    for (int c = 0; c < kEfforts; ++c) {
      const double v = s.tables.b[r][c];
      if (!fits(v)) return ForceAllocationError::kScalarRange;
      s.b[r][c] = Traits::from_double(v);
      s.b_below_32 = s.b_below_32 && v < 32.0 && v > -32.0;
    }
  s.coil_centres_active = false;
  using C = typename ForceAllocationState<Scalar>::CorrectionScalar;
  for (int j = 0; j < io::kCoils; ++j) {
    const double dx = config.coil_centre_offset_m[j][0], dy = config.coil_centre_offset_m[j][1];
    s.coil_torque_arm[0][j] = static_cast<C>(dy);   // tau_x = +dy F_z
    s.coil_torque_arm[1][j] = static_cast<C>(-dx);  // tau_y = -dx F_z
    s.coil_centres_active = s.coil_centres_active || dx != 0.0 || dy != 0.0;
  }
  for (int row = 0; row < 2; ++row) {
    for (int k = 0; k < kForcers; ++k) {
      s.arm_active[row][k] = s.coil_torque_arm[row][2 * k] != C(0) || s.coil_torque_arm[row][2 * k + 1] != C(0);
    }
  }
  // B's theta_x / theta_y columns as the correction reads them: the Scalar
  // value itself for float, the exact table for Q7.24.
  for (int r = 0; r < kForcerForces; ++r) {
    for (int col = 0; col < 2; ++col) {
      if constexpr (Traits::kIsFixed) {
        s.b_tilt_columns[col][r] = s.tables.b[r][4 + col];
      } else {
        s.b_tilt_columns[col][r] = s.b[r][4 + col];
      }
    }
  }
  s.two_b_star_N_per_A = s.tables.two_b_star_N_per_A;
  const double gravity_A = (config.mass_kg + config.payload_kg) * config.gravity_m_per_s2 / s.two_b_star_N_per_A;
  if (!fits(config.peak_current_A) || !fits(gravity_A) || !fits(1.0 / s.two_b_star_N_per_A)) {
    return ForceAllocationError::kScalarRange;
  }
  s.peak_current_A = Traits::from_double(config.peak_current_A);
  s.half_peak_current_A = Traits::from_double(config.peak_current_A / 2.0);
  s.gravity_effort_A = Traits::from_double(gravity_A);
  s.inv_two_b_star_A_per_N = Traits::from_double(1.0 / s.two_b_star_N_per_A);
  s.dac_codes_per_A = 32768.0 / (config.amplifier_gain_A_per_V * config.dac_full_scale_V);
  s.monitor_A_per_code = config.adc_full_scale_V / 32768.0 / config.current_monitor_gain_V_per_A;
  if constexpr (Traits::kIsFixed) {
    // codes = raw * 2^-F * codes_per_A  ->  (raw * q32) >> 32, q32 < 2^31 for any sane gain.
    const double q32 = s.dac_codes_per_A * numeric::detail::pow2(32 - Scalar::kFracBits);
    const double q16 = s.monitor_A_per_code * numeric::detail::pow2(Scalar::kFracBits + 16);
    if (!(q32 < 2147483647.0) || !(q16 < 2147483647.0)) return ForceAllocationError::kScalarRange;
    s.dac_q32_per_raw = static_cast<std::int64_t>(q32 + 0.5);
    s.monitor_raw_per_code_q16 = static_cast<std::int64_t>(q16 + 0.5);
  }
  s.configured = true;
  *state = s;
  return ForceAllocationError::kOk;
}

// Inline, and inlined into the tick (AllocateCurrents): out of line, the
// phases went through memory and the call saved and restored registers
// (~15 M7 instructions a tick).
[[gnu::always_inline]] inline void ForcerPhases(std::int64_t x_pm, std::int64_t y_pm, const CommutationTables& t,
                                                std::uint32_t first_coil_phase_turn[kForcers]) {
  // Turns of each coordinate, NOT reduced: for a direction cosine h that is
  // not an integer, h * (x mod L) != h * x mod L.
  const double tx = numeric::Int64ToDouble(x_pm + t.base_x_pm) * t.inv_pitch_pm;
  const double ty = numeric::Int64ToDouble(y_pm + t.base_y_pm) * t.inv_pitch_pm;
#pragma GCC unroll 4
  for (int k = 0; k < kForcers; ++k) {
    // A forcer with an earlier one's thrust direction has that one's turns,
    // bit for bit, and a coil offset whole quarter turns from its
    // (CommutationTables::same_as): its phase is that one's plus those
    // quarter turns, exactly what the lines below would give (one add
    // instead of ~12 M7 instructions; two of the cross layout's four forcers).
    const int j = t.same_as[k];
    if (j >= 0) {
      first_coil_phase_turn[k] = first_coil_phase_turn[j] + (std::uint32_t{t.quarter_turns[k]} << 30);
      continue;
    }
    const double turns = t.h_dir[k][0] * tx + t.h_dir[k][1] * ty;
    // Exact: turns and floor(turns) share turns' binade or the result is
    // below one ulp of it, so the difference is representable; < 1, so the
    // scaled fraction is < 2^32 and its conversion truncates (= floor).
    const double frac = turns - std::floor(turns);
    const auto psi = static_cast<std::uint32_t>(frac * 4294967296.0);
    first_coil_phase_turn[k] = psi + t.coil_offset_turn[2 * k];
  }
}

template <typename Scalar>
void AllocateCurrents(const Scalar effort_A[kEfforts], std::int64_t x_pm, std::int64_t y_pm,
                      const ForceAllocationState<Scalar>& state, AllocationOutput<Scalar>* out) {
  using Traits = numeric::ScalarTraits<Scalar>;
  // G = B U  (eq (21) without its 2 b*: G is the forcer force in units of 2 b*).
  // B is block-structured (kHorizontalEfforts): a forcer's F_h row reads
  // efforts 0-2 only, its F_z row efforts 3-5 only; the other entries are
  // exactly zero (checked at configuration). Summed from +0, a +-0 product
  // never changes a sum (x + -0 = x, +0 + -0 = +0), so the three terms give
  // the bits of the six: 24 multiply-adds instead of 48.
  // Fixed point sums the three exact products and rounds once
  // (Fixed::dot3); float keeps its product-by-product sum.
  Scalar g[kForcerForces];
#pragma GCC unroll 8
  for (int r = 0; r < kForcerForces; ++r) {
    const int first = (r & 1) == 0 ? 0 : kHorizontalEfforts;
    if constexpr (Traits::kIsFixed) {
      g[r] = detail_fa::Dot3(state.b_below_32, state.b[r][first], effort_A[first], state.b[r][first + 1],
                             effort_A[first + 1], state.b[r][first + 2], effort_A[first + 2]);
    } else {
      Scalar acc = Traits::zero();
#pragma GCC unroll 3
      for (int c = first; c < first + kHorizontalEfforts; ++c) acc += state.b[r][c] * effort_A[c];
      g[r] = acc;
    }
  }
  // i = 2 S_xy G, eq (24). Row j of S_xy (eq 23) is (sin psi_j, cos psi_j) on
  // its forcer's (F_h, F_z): the transpose of column j of eq (19). One table
  // lookup per forcer: its second coil is a quarter turn off the first
  // (CommutationTables::second_coil_leads), sin(p +- 1/4) = +-cos p,
  // cos(p +- 1/4) = -+sin p, exactly the values the table gives there.
  std::uint32_t phase[kForcers] = {};  // every one written below (GCC cannot see it through same_as)
  ForcerPhases(x_pm, y_pm, state.commutation, phase);
  // Per coil (sin psi_j, cos psi_j): one table lookup per forcer.
  // A forcer with the phase of an earlier one plus whole quarter turns
  // (CommutationTables::same_as) takes its table values rotated, exactly.
  // Fixed point keeps the table's Q30 values (sin_q30, cos_q30) and rounds
  // each coil's current once from them (below); float converts them.
  Scalar sin_psi[io::kCoils], cos_psi[io::kCoils];
  std::int32_t sin_q30[io::kCoils], cos_q30[io::kCoils];
  numeric::SinCosQ30 table[kForcers];
#pragma GCC unroll 4
  for (int k = 0; k < kForcers; ++k) {
    const int j = state.commutation.same_as[k];
    table[k] = j < 0 ? numeric::sin_cos_q30(phase[k])
                     : numeric::rotate_quarters(table[j], state.commutation.quarter_turns[k]);
    const bool leads = state.commutation.second_coil_leads[k];
    if constexpr (Traits::kIsFixed) {
      const std::int32_t sn = table[k].sin, cs = table[k].cos;  // |.| <= 2^30: negation exact
      sin_q30[2 * k] = sn;
      cos_q30[2 * k] = cs;
      sin_q30[2 * k + 1] = leads ? cs : -cs;
      cos_q30[2 * k + 1] = leads ? -sn : sn;
    } else {
      const auto sc = Traits::from_q30(table[k]);
      sin_psi[2 * k] = sc.sin;
      cos_psi[2 * k] = sc.cos;
      sin_psi[2 * k + 1] = leads ? sc.cos : -sc.cos;
      cos_psi[2 * k + 1] = leads ? -sc.sin : sc.sin;
    }
  }
  if (state.coil_centres_active) {
    // Coil j's vertical force (units of 2 b*) is h_j cos psi_j, acting at its
    // own centre, not at the forcer centre eq (18) assumes: it adds a torque
    // p = Q G to theta_x / theta_y. Per forcer (coils a, b a quarter turn
    // apart: s_b c_b = -s c, c_b^2 = s^2), its share is
    //   (arm_a - arm_b) s c G_h + (arm_a c^2 + arm_b s^2) G_z.
    // Solve A G + Q G = U on G = B V exactly: G = G0 - B45 p with
    // (I + Q B45) p = Q G0 (B45: B's theta_x / theta_y columns), a 2 x 2
    // system. One reciprocal, no iteration. p is formed in float for the
    // float kernel and in double for Q7.24 (a fixed-point product costs
    // ~10 M7 instructions, a double one ~2; same bits on host and M7 either
    // way), then G is corrected in Scalar.
    using C = typename ForceAllocationState<Scalar>::CorrectionScalar;
    const auto to_c = [](Scalar v) -> C {
      if constexpr (Traits::kIsFixed) {
        return Traits::to_double(v);
      } else {
        return v;
      }
    };
    // Per row (theta_x, theta_y), only the forcers with a non-zero arm
    // (state.arm_active): a forcer whose two arms are exactly 0
    // has qh = 0 * sc and qz = 0 * cc + 0 * ss, +-0, so its terms add +-0 to
    // sums that start at +0 -- the same bits as summing all four. (Coil
    // offsets along the thrust: each forcer turns about one axis only, so
    // two of four per row.) B45's F_h entries are zero (the block structure
    // above): the tilt-column torques take only the qz terms.
    C gc[kForcerForces];
    for (int r = 0; r < kForcerForces; ++r) gc[r] = to_c(g[r]);
    C p0[2], tilt0[2], tilt1[2];
#pragma GCC unroll 2
    for (int row = 0; row < 2; ++row) {
      C p = C(0), t0 = C(0), t1 = C(0);
#pragma GCC unroll 4
      for (int k = 0; k < kForcers; ++k) {
        if (!state.arm_active[row][k]) continue;
        C s, c;
        if constexpr (Traits::kIsFixed) {  // Q30, exact in double
          s = static_cast<double>(sin_q30[2 * k]) * 0x1.0p-30;
          c = static_cast<double>(cos_q30[2 * k]) * 0x1.0p-30;
        } else {
          s = sin_psi[2 * k];
          c = cos_psi[2 * k];
        }
        const C arm_a = state.coil_torque_arm[row][2 * k], arm_b = state.coil_torque_arm[row][2 * k + 1];
        const C qh = (arm_a - arm_b) * (s * c);
        const C qz = arm_a * (c * c) + arm_b * (s * s);
        p += qh * gc[2 * k] + qz * gc[2 * k + 1];
        t0 += qz * state.b_tilt_columns[0][2 * k + 1];
        t1 += qz * state.b_tilt_columns[1][2 * k + 1];
      }
      p0[row] = p;
      tilt0[row] = t0;
      tilt1[row] = t1;
    }
    const C p0x = p0[0], p0y = p0[1];
    const C a = C(1) + tilt0[0], d01 = tilt1[0];
    const C d10 = tilt0[1], d = C(1) + tilt1[1];
    const C inv_det = C(1) / (a * d - d01 * d10);
    C pxc = (d * p0x - d01 * p0y) * inv_det;
    C pyc = (a * p0y - d10 * p0x) * inv_det;
    Scalar px, py;
    if constexpr (Traits::kIsFixed) {
      px = Traits::from_double(pxc);
      py = Traits::from_double(pyc);
    } else {
      px = pxc;
      py = pyc;
    }
    // Only the F_z rows: an F_h row's B[r][4], B[r][5] are +-0, and g - (+-0)
    // is g (g is never -0: it is a sum that started at +0).
#pragma GCC unroll 4
    for (int r = 1; r < kForcerForces; r += 2) {
      if constexpr (Traits::kIsFixed) {
        g[r] = detail_fa::Dot3(state.b_below_32, g[r], Traits::one(), -state.b[r][4], px, -state.b[r][5], py);
      } else {
        g[r] = g[r] - state.b[r][4] * px - state.b[r][5] * py;
      }
    }
  }
  // Work with half-currents h = i / 2 until the limit is applied: doubles
  // the Q7.24 headroom (|h| < 128 A), so efforts up to ~20 A per axis never
  // saturate an intermediate (which would bend the wrench direction).
  // From the (corrected) G, once.
  Scalar half_i[io::kCoils];
#pragma GCC unroll 8
  for (int j = 0; j < io::kCoils; ++j) {
    const int f = j & ~1;
    if constexpr (Traits::kIsFixed) {
      // Q30 x Q24 products, exact sum below 2^62, rounded once to Q24.
      half_i[j] = Scalar::template round_product_sum<30>(
          numeric::detail::product_sum2(sin_q30[j], g[f].raw(), cos_q30[j], g[f + 1].raw()));
    } else {
      half_i[j] = sin_psi[j] * g[f] + cos_psi[j] * g[f + 1];
    }
  }
  Scalar max_abs = Traits::zero();
#pragma GCC unroll 8
  for (int j = 0; j < io::kCoils; ++j) max_abs = detail_fa::MaxScalar(max_abs, detail_fa::AbsScalar(half_i[j]));
  // One common factor k <= 1 keeps the wrench direction: saturation never
  // becomes a cross-axis force. k = (peak/2) / max(max|h|, peak/2) is exactly
  // 1 when nothing is limited (x / x == 1 in float and in Fixed).
  const bool saturated = state.half_peak_current_A < max_abs;
  out->saturated = saturated;
  // Nothing limited (nearly every tick): k is exactly one (x / x), and a
  // product with one is exact (Fixed; float for every number, and a NaN the
  // arithmetic made is a quiet one, which 1 * NaN returns as it is), so
  // skipping the division and the 14 products gives the same bits (~17 M7
  // instructions a product in Q7.24, ~2 in float).
  if (!saturated) {
    out->scale_k = Traits::one();
    for (int j = 0; j < io::kCoils; ++j) out->current_A[j] = half_i[j] + half_i[j];
    for (int c = 0; c < kEfforts; ++c) out->applied_effort_A[c] = effort_A[c];
    return;
  }
  const Scalar k = state.half_peak_current_A / detail_fa::MaxScalar(max_abs, state.half_peak_current_A);
  out->scale_k = k;
  for (int j = 0; j < io::kCoils; ++j) {
    const Scalar scaled = k * half_i[j];
    out->current_A[j] = scaled + scaled;
  }
  for (int c = 0; c < kEfforts; ++c) out->applied_effort_A[c] = k * effort_A[c];
}

template <typename Scalar>
Scalar GravityFeedForward_A(Scalar ramp_fraction, const ForceAllocationState<Scalar>& state) {
  using Traits = numeric::ScalarTraits<Scalar>;
  const Scalar zero = Traits::zero();
  const Scalar one = Traits::one();
  const Scalar r = ramp_fraction < zero ? zero : (one < ramp_fraction ? one : ramp_fraction);
  return r * state.gravity_effort_A;
}

template <typename Scalar>
Scalar EffortFromForce_A(Scalar force, const ForceAllocationState<Scalar>& state) {
  return force * state.inv_two_b_star_A_per_N;
}

template <typename Scalar>
std::int16_t CurrentToDacCode(Scalar current_A, const ForceAllocationState<Scalar>& state) {
  using Traits = numeric::ScalarTraits<Scalar>;
  if constexpr (Traits::kIsFixed) {
    // raw (|.| < 2^31) * q32 (< 2^31, checked at configuration: one SMULL)
    // < 2^62: exact. Round half away from zero: floor((p + 2^31) / 2^32)
    // for p >= 0 and ceil((p - 2^31) / 2^32) = floor((p + 2^31 - 1) / 2^32)
    // for p < 0 -- one 64-bit sum with p's sign (p >> 63 is 0 or -1) and the
    // high word, an int32 below 2^30; then the DAC's range (SSAT on the M7).
    // The value of shift_round(p, 32) and the int64 clamp it replaced
    // (~20 M7 instructions a coil; issue 16).
    const std::int64_t p = std::int64_t{current_A.raw()} * static_cast<std::int32_t>(state.dac_q32_per_raw);
    const auto code = static_cast<std::int32_t>((p + (std::int64_t{1} << 31) + (p >> 63)) >> 32);
    return numeric::SaturateToInt16(code);
  } else {
    return numeric::DacCode(static_cast<double>(current_A) * state.dac_codes_per_A);
  }
}

template <typename Scalar>
Scalar MonitorCodeToCurrent_A(std::int16_t code, const ForceAllocationState<Scalar>& state) {
  using Traits = numeric::ScalarTraits<Scalar>;
  if constexpr (Traits::kIsFixed) {
    return Scalar::from_raw(static_cast<std::int32_t>(
        numeric::detail::shift_round(std::int64_t{code} * state.monitor_raw_per_code_q16, 16)));
  } else {
    return MonitorCodeToCurrentFloat_A(code, state.monitor_A_per_code);
  }
}

}  // namespace maglev::kernel
