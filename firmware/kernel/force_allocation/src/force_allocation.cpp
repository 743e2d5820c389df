#include "maglev/io/code_placement.hpp"
#include "maglev/force_allocation/force_allocation.hpp"

#include <cmath>
#include <cstdint>

#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/fixed.hpp"
#include "maglev/numeric/elementary.hpp"
#include "maglev/numeric/int64_double.hpp"

namespace maglev::kernel {
namespace {

namespace stage = io::stage;

struct ForcerGeometry {
  double px, py;  // acting point, platen frame
  double hx, hy;  // horizontal thrust direction
  bool used;
};

// Layout geometry. A follows from it by r x F (see BuildA); the cross layout
// reproduces eq (18) of paper 000 entry by entry, the triangle eq (8) of
// paper 003 (tests/kernel/force_allocation checks both against the printed
// matrices).
MAGLEV_CONFIG_CODE void LayoutGeometry(const ForceAllocationConfig& c, ForcerGeometry g[kForcers]) {
  const double l = c.lever_arm_m;
  switch (c.layout) {
    case ForceLayout::kCross:
      // Forcers 1&2 (x) at (0,-l), 3&4 (y) at (l,0), 5&6 (x) at (0,l), 7&8 (y) at (-l,0).
      g[0] = {0.0, -l, 1.0, 0.0, true};
      g[1] = {l, 0.0, 0.0, 1.0, true};
      g[2] = {0.0, l, 1.0, 0.0, true};
      g[3] = {-l, 0.0, 0.0, 1.0, true};
      break;
    case ForceLayout::kSquare:
      // Forcers at the corners, thrust lines at distance l from the centre;
      // the Fx, Fy, Tz and Fz rows equal paper 003 eq (6). Its printed Tx/Ty
      // rows are not those of any rigid layout (see docs/EQUATIONS.md), so
      // they come from r x F here.
      g[0] = {l, l, 1.0, 0.0, true};
      g[1] = {-l, l, 0.0, 1.0, true};
      g[2] = {-l, -l, 1.0, 0.0, true};
      g[3] = {l, -l, 0.0, 1.0, true};
      break;
    case ForceLayout::kTriangular: {
      const double s = numeric::dsin(c.triangle_alpha_rad);
      const double co = numeric::dcos(c.triangle_alpha_rad);
      g[0] = {l * co, l * s, -s, co, true};
      g[1] = {-l * co, l * s, -s, -co, true};
      g[2] = {0.0, -l, 1.0, 0.0, true};
      g[3] = {0.0, 0.0, 0.0, 0.0, false};  // coils 7, 8 unused: zero columns, zero B rows
      break;
    }
  }
}

MAGLEV_CONFIG_CODE void BuildA(const ForcerGeometry g[kForcers], double a[kEfforts][kForcerForces]) {
  for (int r = 0; r < kEfforts; ++r)
    for (int c = 0; c < kForcerForces; ++c) a[r][c] = 0.0;
  for (int k = 0; k < kForcers; ++k) {
    if (!g[k].used) continue;
    const int h = 2 * k;
    const int z = 2 * k + 1;
    // Horizontal force F_h (hx, hy, 0) at (px, py): Tz = px Fy - py Fx.
    a[0][h] = g[k].hx;
    a[1][h] = g[k].hy;
    a[2][h] = g[k].px * g[k].hy - g[k].py * g[k].hx;
    // Vertical force F_z at (px, py): Tx = py Fz, Ty = -px Fz. The horizontal
    // force acts in the coil plane, through the centre of mass height
    // (paper 000 Sec. IV neglects its Tx/Ty lever): no Tx/Ty from F_h.
    a[3][z] = 1.0;
    a[4][z] = g[k].py;
    a[5][z] = -g[k].px;
  }
}

// Solve M X = R for 6x6 M (Gauss-Jordan, partial pivoting), R 6 x 8 in place.
MAGLEV_CONFIG_CODE bool Solve6(double m[6][6], double rhs[6][kForcerForces]) {
  double scale = 0.0;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) scale = std::fmax(scale, std::fabs(m[r][c]));
  if (!(scale > 0.0)) return false;
  for (int col = 0; col < 6; ++col) {
    int piv = col;
    for (int r = col + 1; r < 6; ++r)
      if (std::fabs(m[r][col]) > std::fabs(m[piv][col])) piv = r;
    if (!(std::fabs(m[piv][col]) > 1e-12 * scale)) return false;
    if (piv != col) {
      for (int c = 0; c < 6; ++c) {
        const double t = m[col][c];
        m[col][c] = m[piv][c];
        m[piv][c] = t;
      }
      for (int c = 0; c < kForcerForces; ++c) {
        const double t = rhs[col][c];
        rhs[col][c] = rhs[piv][c];
        rhs[piv][c] = t;
      }
    }
    const double inv = 1.0 / m[col][col];
    for (int c = 0; c < 6; ++c) m[col][c] *= inv;
    for (int c = 0; c < kForcerForces; ++c) rhs[col][c] *= inv;
    for (int r = 0; r < 6; ++r) {
      if (r == col) continue;
      const double f = m[r][col];
      for (int c = 0; c < 6; ++c) m[r][c] -= f * m[col][c];
      for (int c = 0; c < kForcerForces; ++c) rhs[r][c] -= f * rhs[col][c];
    }
  }
  return true;
}

MAGLEV_CONFIG_CODE std::int64_t RoundToInt64(double v) { return static_cast<std::int64_t>(std::llround(v)); }

MAGLEV_CONFIG_CODE std::uint32_t RadToTurn(double rad) {
  double t = rad / (2.0 * stage::kPi);
  t -= std::floor(t);
  const double scaled = std::floor(t * 4294967296.0 + 0.5);
  return static_cast<std::uint32_t>(static_cast<std::uint64_t>(scaled) & 0xffffffffu);
}

}  // namespace

MAGLEV_CONFIG_CODE void SetCoilCentreOffsets(ForceAllocationConfig* c) {
  for (int j = 0; j < io::kCoils; ++j) {
    const double along = stage::kCoilCentreQuarterPitches[j] * (c->pitch_m / 4.0);
    const bool fx_coil = (j / 2) % 2 == 0;  // coils 1, 2, 5, 6 thrust along x
    c->coil_centre_offset_m[j][0] = fx_coil ? along : 0.0;
    c->coil_centre_offset_m[j][1] = fx_coil ? 0.0 : along;
  }
}

MAGLEV_CONFIG_CODE ForceAllocationConfig DefaultForceAllocationConfig() {
  ForceAllocationConfig c{};
  c.layout = ForceLayout::kCross;
  c.lever_arm_m = stage::kLeverArm_m;
  c.triangle_alpha_rad = stage::kPi / 6.0;
  c.pitch_m = stage::kPitch_m;
  for (int j = 0; j < io::kCoils; ++j) c.coil_phase_rad[j] = stage::kCoilPhase_rad[j];
  c.base_point_x_m = stage::kBasePointX2_m;
  c.base_point_y_m = stage::kBasePointY8_m;
  SetCoilCentreOffsets(&c);
  c.two_b_star_identified_N_per_A = stage::kTwoBStarIdentified_N_per_A;
  c.magnetization_A_per_m = 0.0;
  c.coil_effective_length_m = stage::kCoilEffectiveLength_m;
  c.coil_side_width_m = stage::kCoilSideWidth_m;
  c.coil_thickness_m = stage::kCoilThickness_m;
  c.coil_turns = stage::kCoilTurns;
  c.magnet_thickness_m = stage::kMagnetThickness_m;
  c.nominal_gap_m = stage::kRestGap_m;
  c.peak_current_A = stage::kPeakCoilCurrent_A;
  c.mass_kg = stage::kMass_kg;
  c.payload_kg = 0.0;
  c.gravity_m_per_s2 = stage::kGravity_m_per_s2;
  c.inertia_kgm2[0] = stage::kIx_kgm2;
  c.inertia_kgm2[1] = stage::kIy_kgm2;
  c.inertia_kgm2[2] = stage::kIz_kgm2;
  c.amplifier_gain_A_per_V = stage::kAmplifierGain_A_per_V;
  c.dac_full_scale_V = stage::kDacFullScale_V;
  c.current_monitor_gain_V_per_A = stage::kCurrentMonitorGain_V_per_A;
  c.adc_full_scale_V = stage::kAdcFullScale_V;
  return c;
}

MAGLEV_CONFIG_CODE double BStarFromGeometry(const ForceAllocationConfig& c) {
  // eq (3), n = 1:  c_1(z) = 2 sqrt(2) mu0 M0 / pi (1 - e^{-g Delta}) e^{-g z}
  // eq (20):        b*(z)  = p c_1(z) 4N / (d a g^2) sin(g a / 2) (1 - e^{-g d})
  const double g = 2.0 * stage::kPi / c.pitch_m;
  const double c1 = 2.0 * std::sqrt(2.0) * stage::kMu0 * c.magnetization_A_per_m / stage::kPi *
                    (1.0 - numeric::dexp(-g * c.magnet_thickness_m)) * numeric::dexp(-g * c.nominal_gap_m);
  return c.coil_effective_length_m * c1 * 4.0 * c.coil_turns /
         (c.coil_thickness_m * c.coil_side_width_m * g * g) * numeric::dsin(g * c.coil_side_width_m / 2.0) *
         (1.0 - numeric::dexp(-g * c.coil_thickness_m));
}

MAGLEV_CONFIG_CODE ForceAllocationError ComputeForceAllocationTables(const ForceAllocationConfig& c,
                                                  ForceAllocationTablesDouble* out) {
  ForceAllocationTablesDouble t{};
  if (!(c.lever_arm_m >= 0.0 && c.lever_arm_m < 10.0) || !(c.pitch_m > 1e-4 && c.pitch_m < 1.0)) {
    return ForceAllocationError::kBadGeometry;
  }
  ForcerGeometry g[kForcers] = {};  // zero for a layout value outside the enum (gcc -O2 arm: maybe-uninitialized)
  LayoutGeometry(c, g);
  BuildA(g, t.a);
  for (int k = 0; k < kForcers; ++k) {
    t.h_dir[k][0] = g[k].hx;
    t.h_dir[k][1] = g[k].hy;
    t.forcer_used[k] = g[k].used;
  }
  // B = A^T (A A^T)^-1: solve (A A^T) X = A, then B = X^T.
  double aat[6][6];
  for (int r = 0; r < 6; ++r)
    for (int s = 0; s < 6; ++s) {
      double acc = 0.0;
      for (int k = 0; k < kForcerForces; ++k) acc += t.a[r][k] * t.a[s][k];
      aat[r][s] = acc;
    }
  double x[6][kForcerForces];
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < kForcerForces; ++k) x[r][k] = t.a[r][k];
  if (!Solve6(aat, x)) return ForceAllocationError::kSingularLayout;
  for (int k = 0; k < kForcerForces; ++k)
    for (int r = 0; r < 6; ++r) t.b[k][r] = x[r][k];
  double worst = 0.0;
  for (int r = 0; r < 6; ++r)
    for (int s = 0; s < 6; ++s) {
      double acc = 0.0;
      for (int k = 0; k < kForcerForces; ++k) acc += t.a[r][k] * t.b[k][s];
      worst = std::fmax(worst, std::fabs(acc - (r == s ? 1.0 : 0.0)));
    }
  t.max_abs_ab_minus_i = worst;
  if (!(worst <= 1e-9)) return ForceAllocationError::kPseudoInverseCheck;
  // The block structure AllocateCurrents relies on (kHorizontalEfforts):
  // exact by construction (the elimination's factors across the blocks are
  // exactly 0), checked so that no layout added later can break it silently.
  for (int k = 0; k < kForcerForces; ++k) {
    const int other = (k & 1) == 0 ? kHorizontalEfforts : 0;
    for (int r = other; r < other + kHorizontalEfforts; ++r) {
      if (t.b[k][r] != 0.0) return ForceAllocationError::kPseudoInverseCheck;
    }
  }

  // Coil pairs must be in quadrature (orthogonal 2x2 commutation blocks).
  for (int k = 0; k < kForcers; ++k) {
    if (!t.forcer_used[k]) continue;
    if (!(std::fabs(numeric::dcos(c.coil_phase_rad[2 * k] - c.coil_phase_rad[2 * k + 1])) < 1e-9)) {
      return ForceAllocationError::kBadCoilPhases;
    }
  }

  for (int j = 0; j < io::kCoils; ++j) {
    for (int a = 0; a < 2; ++a) {
      const double d = c.coil_centre_offset_m[j][a];
      if (!(d >= -c.pitch_m && d <= c.pitch_m)) return ForceAllocationError::kBadCoilCentres;  // NaN too
    }
  }

  t.two_b_star_N_per_A =
      c.magnetization_A_per_m > 0.0 ? 2.0 * BStarFromGeometry(c) : c.two_b_star_identified_N_per_A;
  if (!(t.two_b_star_N_per_A > 1e-3 && t.two_b_star_N_per_A < 1e3)) return ForceAllocationError::kBadBStar;
  *out = t;
  return ForceAllocationError::kOk;
}

MAGLEV_CONFIG_CODE void CommutationPhases(std::int64_t x_pm, std::int64_t y_pm, const CommutationTables& t,
                       std::uint32_t coil_phase_turn[io::kCoils]) {
  std::uint32_t first[kForcers] = {};  // every one written (GCC cannot see it through same_as)
  ForcerPhases(x_pm, y_pm, t, first);
  for (int k = 0; k < kForcers; ++k) {
    coil_phase_turn[2 * k] = first[k];
    coil_phase_turn[2 * k + 1] = first[k] + (t.coil_offset_turn[2 * k + 1] - t.coil_offset_turn[2 * k]);
  }
}

namespace detail_fa {

MAGLEV_CONFIG_CODE ForceAllocationError FillCommon(const ForceAllocationConfig& c, const ForceAllocationTablesDouble& t,
                                CommutationTables* ct) {
  const std::int64_t pitch_pm = RoundToInt64(c.pitch_m * 1e12);
  if (pitch_pm >= (std::int64_t{1} << 36)) return ForceAllocationError::kBadGeometry;
  ct->inv_pitch_pm = 1.0 / static_cast<double>(pitch_pm);  // of the whole-pm pitch
  ct->base_x_pm = RoundToInt64(c.base_point_x_m * 1e12);
  ct->base_y_pm = RoundToInt64(c.base_point_y_m * 1e12);
  for (int k = 0; k < kForcers; ++k) {
    ct->h_dir[k][0] = t.h_dir[k][0];
    ct->h_dir[k][1] = t.h_dir[k][1];
  }
  // Coil 2k+1 exactly a quarter turn from coil 2k (ComputeForceAllocationTables
  // checked quadrature to 1e-9 rad for every forcer in use; an unused
  // forcer's coils carry no current whatever their phase).
  for (int k = 0; k < kForcers; ++k) {
    const std::uint32_t first = RadToTurn(c.coil_phase_rad[2 * k]);
    const bool leads = numeric::dsin(c.coil_phase_rad[2 * k + 1] - c.coil_phase_rad[2 * k]) >= 0.0;
    ct->coil_offset_turn[2 * k] = first;
    ct->coil_offset_turn[2 * k + 1] = first + (leads ? 0x40000000u : 0xC0000000u);
    ct->second_coil_leads[k] = leads;
  }
  for (int k = 0; k < kForcers; ++k) {
    ct->same_as[k] = -1;
    ct->quarter_turns[k] = 0;
    for (int j = 0; j < k; ++j) {
      const std::uint32_t apart = ct->coil_offset_turn[2 * k] - ct->coil_offset_turn[2 * j];
      if (ct->same_as[j] < 0 && ct->h_dir[k][0] == ct->h_dir[j][0] && ct->h_dir[k][1] == ct->h_dir[j][1] &&
          (apart & 0x3FFFFFFFu) == 0u) {
        ct->same_as[k] = static_cast<std::int8_t>(j);
        ct->quarter_turns[k] = static_cast<std::uint8_t>(apart >> 30);
        break;
      }
    }
  }
  if (!(c.peak_current_A > 0.0 && c.peak_current_A < 100.0) || !(c.mass_kg > 0.0) || !(c.payload_kg >= 0.0) ||
      !(c.amplifier_gain_A_per_V > 0.0) || !(c.dac_full_scale_V > 0.0) ||
      !(c.current_monitor_gain_V_per_A > 0.0) || !(c.adc_full_scale_V > 0.0)) {
    return ForceAllocationError::kBadLimits;
  }
  return ForceAllocationError::kOk;
}

}  // namespace detail_fa

// Instantiate the templates here so the strict warnings check them.
template ForceAllocationError ApplyForceAllocationConfig<float>(const ForceAllocationConfig&,
                                                                ForceAllocationState<float>*);
template ForceAllocationError ApplyForceAllocationConfig<numeric::Q7_24>(const ForceAllocationConfig&,
                                                                         ForceAllocationState<numeric::Q7_24>*);
template void AllocateCurrents<float>(const float[kEfforts], std::int64_t, std::int64_t,
                                      const ForceAllocationState<float>&, AllocationOutput<float>*);
template void AllocateCurrents<numeric::Q7_24>(const numeric::Q7_24[kEfforts], std::int64_t, std::int64_t,
                                               const ForceAllocationState<numeric::Q7_24>&,
                                               AllocationOutput<numeric::Q7_24>*);
template std::int16_t CurrentToDacCode<float>(float, const ForceAllocationState<float>&);
template std::int16_t CurrentToDacCode<numeric::Q7_24>(numeric::Q7_24, const ForceAllocationState<numeric::Q7_24>&);
template float MonitorCodeToCurrent_A<float>(std::int16_t, const ForceAllocationState<float>&);
template numeric::Q7_24 MonitorCodeToCurrent_A<numeric::Q7_24>(std::int16_t,
                                                               const ForceAllocationState<numeric::Q7_24>&);
template float GravityFeedForward_A<float>(float, const ForceAllocationState<float>&);
template numeric::Q7_24 GravityFeedForward_A<numeric::Q7_24>(numeric::Q7_24,
                                                             const ForceAllocationState<numeric::Q7_24>&);
template float EffortFromForce_A<float>(float, const ForceAllocationState<float>&);
template numeric::Q7_24 EffortFromForce_A<numeric::Q7_24>(numeric::Q7_24, const ForceAllocationState<numeric::Q7_24>&);

}  // namespace maglev::kernel
