// force_allocation: A, pinv, commutation, currents -> wrench, current limit,
// feed-forward, DAC scaling. The wrench produced by the kernel's currents is
// checked with an INDEPENDENT forcer model (ForcerModelWrench below), written
// from paper 000 eqs (12)-(15) and the cross geometry, not from the kernel's
// A or S_xy.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>

#include "CppUTest/TestHarness.h"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/fixed.hpp"

namespace {

using maglev::kernel::AllocateCurrents;
using maglev::kernel::AllocationOutput;
using maglev::kernel::ApplyForceAllocationConfig;
using maglev::kernel::DefaultForceAllocationConfig;
using maglev::kernel::ForceAllocationConfig;
using maglev::kernel::ForceAllocationError;
using maglev::kernel::ForceAllocationState;
using maglev::kernel::ForceLayout;
using maglev::numeric::Q7_24;
using maglev::kernel::ForcerPhases;
using maglev::kernel::kEfforts;
using maglev::kernel::kForcers;
namespace io = maglev::io;
namespace stage = maglev::io::stage;

constexpr double kPi = stage::kPi;

// Each forcer: acting point (px, py), thrust direction (hx, hy), which world
// coordinate its commutation follows. Written from the paper's figures /
// matrices, independently of force_allocation.cpp.
struct TestForcer {
  double px, py, hx, hy;
  bool used;
};

void TestGeometry(ForceLayout layout, double l, double alpha, TestForcer f[4]) {
  if (layout == ForceLayout::kCross) {
    // paper 000 Fig. 5(a): coils 1&2 and 5&6 push along X at y = -l / +l,
    // coils 3&4 and 7&8 push along Y at x = +l / -l (read off eq (18)'s Tz row).
    f[0] = {0, -l, 1, 0, true};
    f[1] = {l, 0, 0, 1, true};
    f[2] = {0, l, 1, 0, true};
    f[3] = {-l, 0, 0, 1, true};
  } else if (layout == ForceLayout::kSquare) {
    f[0] = {l, l, 1, 0, true};
    f[1] = {-l, l, 0, 1, true};
    f[2] = {-l, -l, 1, 0, true};
    f[3] = {l, -l, 0, 1, true};
  } else {
    f[0] = {l * std::cos(alpha), l * std::sin(alpha), -std::sin(alpha), std::cos(alpha), true};
    f[1] = {-l * std::cos(alpha), l * std::sin(alpha), -std::sin(alpha), -std::cos(alpha), true};
    f[2] = {0, -l, 1, 0, true};
    f[3] = {0, 0, 0, 0, false};
  }
}

// Where coil j sits along its forcer's thrust axis, from the forcer centre
// (the plant's layout rule, written here from the coil phases, not from the
// kernel's table): coil j's force (sin, cos)(gamma_1 s + phase_j) comes from
// a side at s0 = (phase_j + pi/2) / gamma_1; it is centred at 0 when s0 is
// L/4 off a multiple of L/2, else at +L/4 (forcers 1, 2) or -L/4 (3, 4).
double CoilCentreAlong(int j) {
  const double L = stage::kPitch_m;
  const double s0 = (stage::kCoilPhase_rad[j] + kPi / 2.0) / (2.0 * kPi / L);
  const double m = (s0 - L / 4.0) / (L / 2.0);
  if (std::fabs(m - std::nearbyint(m)) <= 1e-9) return 0.0;
  return (j / 2 < 2) ? L / 4.0 : -L / 4.0;
}

// Independent physics: coil j of forcer k at platen coordinate s along the
// forcer's axis (the base point x2 / y8) feels, by eqs (10)-(15) reduced to
// the fundamental, the force b* i_j (sin, cos)(gamma_1 s + phase_j) along
// (thrust axis, Z), acting at the coil's own centre (the forcer point plus
// CoilCentreAlong(j) along the thrust axis; 0 for the triangle, whose coil
// places this model does not know). Then the wrench Sum r x F about the
// platen centre. Returns [Fx Fy Tz Fz Tx Ty].
void ForcerModelWrench(const double current[8], double x, double y, ForceLayout layout, double l, double alpha,
                       double b_star, double w[6]) {
  TestForcer f[4];
  TestGeometry(layout, l, alpha, f);
  const double g1 = 2.0 * kPi / stage::kPitch_m;
  for (int i = 0; i < 6; ++i) w[i] = 0.0;
  for (int k = 0; k < 4; ++k) {
    if (!f[k].used) continue;
    const double s = f[k].hx * (x + stage::kBasePointX2_m) + f[k].hy * (y + stage::kBasePointY8_m);
    for (int c = 0; c < 2; ++c) {
      const int j = 2 * k + c;
      const double psi = g1 * s + stage::kCoilPhase_rad[j];
      const double fh = b_star * current[j] * std::sin(psi);
      const double fz = b_star * current[j] * std::cos(psi);
      const double along = layout == ForceLayout::kTriangular ? 0.0 : CoilCentreAlong(j);
      const double px = f[k].px + along * f[k].hx, py = f[k].py + along * f[k].hy;
      const double fx = fh * f[k].hx, fy = fh * f[k].hy;
      // r x F with r = (px, py, 0), F = (fx, fy, fz)
      w[0] += fx;
      w[1] += fy;
      w[2] += px * fy - py * fx;
      w[3] += fz;
      w[4] += py * fz;
      w[5] += -px * fz;
    }
  }
}

template <typename Scalar>
double ToD(Scalar v) {
  return maglev::numeric::ScalarTraits<Scalar>::to_double(v);
}
template <typename Scalar>
Scalar FromD(double v) {
  return maglev::numeric::ScalarTraits<Scalar>::from_double(v);
}

// Max over 1000 random (x, y) and random U of |wrench/(2b*) - U|_inf / |U|_inf.
// coil_centres = false: the kernel as paper 000 writes it (every coil's force
// at its forcer centre), against the same physics.
template <typename Scalar>
double WorstRelativeWrenchError(ForceLayout layout, std::uint32_t seed, bool coil_centres = true) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  cfg.layout = layout;
  if (layout == ForceLayout::kTriangular || !coil_centres) {
    for (auto& o : cfg.coil_centre_offset_m) o[0] = o[1] = 0.0;
  }
  static ForceAllocationState<Scalar> st;
  CHECK(ApplyForceAllocationConfig<Scalar>(cfg, &st) == ForceAllocationError::kOk);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-0.03, 0.03);
  // Forces up to 0.3 A, torques up to 0.06 A of effort: no current limit (any layout).
  std::uniform_real_distribution<double> eff(-0.3, 0.3);
  const double b_star = cfg.two_b_star_identified_N_per_A / 2.0;
  double worst = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const double x = pos(rng), y = pos(rng);
    const std::int64_t x_pm = std::llround(x * 1e12), y_pm = std::llround(y * 1e12);
    Scalar u[6];
    double ud[6], umax = 0.0;
    for (int a = 0; a < 6; ++a) {
      u[a] = FromD<Scalar>(eff(rng) * ((a == 2 || a == 4 || a == 5) ? 0.2 : 1.0));
      ud[a] = ToD(u[a]);
      umax = std::fmax(umax, std::fabs(ud[a]));
    }
    AllocationOutput<Scalar> out{};
    AllocateCurrents<Scalar>(u, x_pm, y_pm, st, &out);
    CHECK_FALSE(out.saturated);
    double i[8];
    for (int j = 0; j < 8; ++j) i[j] = ToD(out.current_A[j]);
    double w[6];
    ForcerModelWrench(i, static_cast<double>(x_pm) * 1e-12, static_cast<double>(y_pm) * 1e-12, layout,
                      cfg.lever_arm_m, cfg.triangle_alpha_rad, b_star, w);
    for (int a = 0; a < 6; ++a) worst = std::fmax(worst, std::fabs(w[a] / (2.0 * b_star) - ud[a]) / umax);
  }
  return worst;
}

}  // namespace

TEST_GROUP(ForceAllocation){};

TEST(ForceAllocation, PseudoInverseAllLayouts) {
  for (ForceLayout layout : {ForceLayout::kCross, ForceLayout::kSquare, ForceLayout::kTriangular}) {
    ForceAllocationConfig cfg = DefaultForceAllocationConfig();
    cfg.layout = layout;
    static ForceAllocationState<float> st;
    CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
    std::printf("\n  layout %d: max|A B - I| = %.3g", static_cast<int>(layout), st.tables.max_abs_ab_minus_i);
    CHECK(st.tables.max_abs_ab_minus_i <= 1e-12);
    // Recompute A*B here, independently of the stored check.
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < 6; ++c) {
        double acc = 0.0;
        for (int k = 0; k < 8; ++k) acc += st.tables.a[r][k] * st.tables.b[k][c];
        DOUBLES_EQUAL(r == c ? 1.0 : 0.0, acc, 1e-12);
      }
  }
  // Triangle: coils 7, 8 get exactly zero rows of B.
  ForceAllocationConfig tri = DefaultForceAllocationConfig();
  tri.layout = ForceLayout::kTriangular;
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(tri, &st) == ForceAllocationError::kOk);
  for (int c = 0; c < 6; ++c) {
    DOUBLES_EQUAL(0.0, st.tables.b[6][c], 0.0);
    DOUBLES_EQUAL(0.0, st.tables.b[7][c], 0.0);
  }
}

TEST(ForceAllocation, DegenerateLayoutsRefused) {
  static ForceAllocationState<float> st;
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  cfg.lever_arm_m = 0.0;  // no torques possible: A loses rank 3
  const ForceAllocationError e = ApplyForceAllocationConfig<float>(cfg, &st);
  CHECK(e == ForceAllocationError::kSingularLayout || e == ForceAllocationError::kPseudoInverseCheck);
  cfg = DefaultForceAllocationConfig();
  cfg.layout = ForceLayout::kTriangular;
  cfg.triangle_alpha_rad = kPi / 2;  // all three thrusts along X: no Fy
  const ForceAllocationError e2 = ApplyForceAllocationConfig<float>(cfg, &st);
  CHECK(e2 == ForceAllocationError::kSingularLayout || e2 == ForceAllocationError::kPseudoInverseCheck);
  cfg = DefaultForceAllocationConfig();
  cfg.coil_phase_rad[1] = 0.3;  // coils 1, 2 no longer in quadrature
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kBadCoilPhases);
  // A refused config leaves the previous state alone.
  CHECK_FALSE(st.configured);
}

TEST(ForceAllocation, CrossMatrixIsEq18AndTriangleIsEq8) {
  static ForceAllocationState<float> st;
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  const double l = cfg.lever_arm_m;
  const double eq18[6][8] = {{1, 0, 0, 0, 1, 0, 0, 0},   {0, 0, 1, 0, 0, 0, 1, 0},
                             {l, 0, l, 0, -l, 0, -l, 0}, {0, 1, 0, 1, 0, 1, 0, 1},
                             {0, -l, 0, 0, 0, l, 0, 0},  {0, 0, 0, -l, 0, 0, 0, l}};
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 8; ++c) DOUBLES_EQUAL(eq18[r][c], st.tables.a[r][c], 1e-15);

  cfg.layout = ForceLayout::kTriangular;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  const double s = std::sin(cfg.triangle_alpha_rad), co = std::cos(cfg.triangle_alpha_rad);
  // Paper 003 eq (8), rows [Fx Fy Tz Tx Ty Fz].
  const double eq8[6][6] = {{-s, 0, -s, 0, 1, 0},         {co, 0, -co, 0, 0, 0}, {l, 0, l, 0, l, 0},
                            {0, l * s, 0, l * s, 0, -l}, {0, -l * co, 0, l * co, 0, 0}, {0, 1, 0, 1, 0, 1}};
  const int row_of[6] = {0, 1, 2, 4, 5, 3};  // 003 row -> kernel row [Fx Fy Tz Fz Tx Ty]
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) DOUBLES_EQUAL(eq8[r][c], st.tables.a[row_of[r]][c], 1e-15);

  cfg.layout = ForceLayout::kSquare;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  // Paper 003 eq (6), square: rows Fx, Fy, Tz, Fz as printed.
  const double sq[4][8] = {{1, 0, 0, 0, 1, 0, 0, 0},
                           {0, 0, 1, 0, 0, 0, 1, 0},
                           {-l, 0, -l, 0, l, 0, l, 0},
                           {0, 1, 0, 1, 0, 1, 0, 1}};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 8; ++c) DOUBLES_EQUAL(sq[r][c], st.tables.a[r][c], 1e-15);
}

TEST(ForceAllocation, CoilPhasesReproduceEq19AndKernelReproducesEq23) {
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> pos(-0.1, 0.1);
  const double g1 = 2.0 * kPi / stage::kPitch_m;
  static ForceAllocationState<float> st;
  // Eq (23) as printed: every coil's force at its forcer centre (the kernel
  // with its coil-centre torque correction off).
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  for (auto& o : cfg.coil_centre_offset_m) o[0] = o[1] = 0.0;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  for (int n = 0; n < 200; ++n) {
    const double x = pos(rng), y = pos(rng);
    const double sx = std::sin(g1 * x), cx = std::cos(g1 * x), sy = std::sin(g1 * y), cy = std::cos(g1 * y);
    // eq (19), printed
    const double s19[8][8] = {{sx, -cx, 0, 0, 0, 0, 0, 0},  {cx, sx, 0, 0, 0, 0, 0, 0},
                              {0, 0, cy, sy, 0, 0, 0, 0},   {0, 0, -sy, cy, 0, 0, 0, 0},
                              {0, 0, 0, 0, cx, -sx, 0, 0},  {0, 0, 0, 0, -sx, -cx, 0, 0},
                              {0, 0, 0, 0, 0, 0, -sy, -cy}, {0, 0, 0, 0, 0, 0, -cy, sy}};
    // Column j of (19) from kCoilPhase_rad: (sin, cos)(gamma1 * base + phase_j)
    for (int j = 0; j < 8; ++j) {
      const int k = j / 2;
      const double base = (k == 0 || k == 2) ? x : y;
      const double psi = g1 * base + stage::kCoilPhase_rad[j];
      DOUBLES_EQUAL(s19[2 * k][j], std::sin(psi), 1e-12);
      DOUBLES_EQUAL(s19[2 * k + 1][j], std::cos(psi), 1e-12);
      for (int r = 0; r < 8; ++r)
        if (r / 2 != k) DOUBLES_EQUAL(0.0, s19[r][j], 0.0);
    }
    // eq (23), printed (without the 1/b*): the kernel with B = I-like probing.
    const double s23[8][8] = {{sx, cx, 0, 0, 0, 0, 0, 0},   {-cx, sx, 0, 0, 0, 0, 0, 0},
                              {0, 0, cy, -sy, 0, 0, 0, 0},  {0, 0, sy, cy, 0, 0, 0, 0},
                              {0, 0, 0, 0, cx, -sx, 0, 0},  {0, 0, 0, 0, -sx, -cx, 0, 0},
                              {0, 0, 0, 0, 0, 0, -sy, -cy}, {0, 0, 0, 0, 0, 0, -cy, sy}};
    float u[6] = {0.3f, -0.2f, 0.1f, 0.25f, -0.05f, 0.07f};
    AllocationOutput<float> out{};
    AllocateCurrents<float>(u, std::llround(x * 1e12), std::llround(y * 1e12), st, &out);
    for (int j = 0; j < 8; ++j) {
      double expect = 0.0;
      for (int r = 0; r < 8; ++r) {
        double g = 0.0;
        for (int c = 0; c < 6; ++c) g += st.tables.b[r][c] * static_cast<double>(u[c]);
        expect += 2.0 * s23[j][r] * g;
      }
      DOUBLES_EQUAL(expect, static_cast<double>(out.current_A[j]), 5e-6);
    }
  }
}

// Forcers that share a thrust direction and sit whole quarter turns apart
// (the cross layout: 1 with 3, 2 with 4) take the earlier one's phase and
// table values: the same bits as computing each forcer on its own.
TEST(ForceAllocation, ForcersWithTheSamePhaseUpToQuarterTurnsGiveTheSameBits) {
  static ForceAllocationState<float> shared;
  static ForceAllocationState<Q7_24> shared_q;
  const ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  CHECK(ApplyForceAllocationConfig<float>(cfg, &shared) == ForceAllocationError::kOk);
  CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &shared_q) == ForceAllocationError::kOk);
  LONGS_EQUAL(-1, shared.commutation.same_as[0]);
  LONGS_EQUAL(-1, shared.commutation.same_as[1]);
  LONGS_EQUAL(0, shared.commutation.same_as[2]);
  LONGS_EQUAL(1, shared.commutation.same_as[3]);
  LONGS_EQUAL(1, shared.commutation.quarter_turns[2]);
  LONGS_EQUAL(1, shared.commutation.quarter_turns[3]);
  // The same tables with every forcer computed on its own.
  static ForceAllocationState<float> alone;
  static ForceAllocationState<Q7_24> alone_q;
  alone = shared;
  alone_q = shared_q;
  for (int k = 0; k < kForcers; ++k) {
    alone.commutation.same_as[k] = -1;
    alone_q.commutation.same_as[k] = -1;
  }
  std::mt19937 rng(23);
  std::uniform_int_distribution<std::int64_t> pos(-60'000'000'000, 60'000'000'000);  // +-60 mm in pm
  std::uniform_real_distribution<float> eff(-2.0f, 2.0f);
  long differ = 0;
  for (int n = 0; n < 20000; ++n) {
    const std::int64_t x = pos(rng), y = pos(rng);
    std::uint32_t a[kForcers], b[kForcers];
    ForcerPhases(x, y, shared.commutation, a);
    ForcerPhases(x, y, alone.commutation, b);
    for (int k = 0; k < kForcers; ++k) differ += a[k] != b[k] ? 1 : 0;
    float u[kEfforts];
    Q7_24 uq[kEfforts];
    for (int c = 0; c < kEfforts; ++c) {
      u[c] = eff(rng);
      uq[c] = Q7_24::from_double(static_cast<double>(u[c]));
    }
    AllocationOutput<float> o1{}, o2{};
    AllocateCurrents<float>(u, x, y, shared, &o1);
    AllocateCurrents<float>(u, x, y, alone, &o2);
    AllocationOutput<Q7_24> q1{}, q2{};
    AllocateCurrents<Q7_24>(uq, x, y, shared_q, &q1);
    AllocateCurrents<Q7_24>(uq, x, y, alone_q, &q2);
    for (int j = 0; j < io::kCoils; ++j) {
      differ += std::memcmp(&o1.current_A[j], &o2.current_A[j], sizeof(float)) != 0 ? 1 : 0;
      differ += q1.current_A[j].raw() != q2.current_A[j].raw() ? 1 : 0;
    }
  }
  LONGS_EQUAL(0, differ);
}

// The seed layout's coil centres, as the kernel holds them, are the ones the
// plant's rule gives (CoilCentreAlong, from the phases).
TEST(ForceAllocation, CoilCentresAreThoseThePhasesPlace) {
  const ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  for (int j = 0; j < 8; ++j) {
    const bool fx = (j / 2) % 2 == 0;
    DOUBLES_EQUAL(fx ? CoilCentreAlong(j) : 0.0, cfg.coil_centre_offset_m[j][0], 1e-15);
    DOUBLES_EQUAL(fx ? 0.0 : CoilCentreAlong(j), cfg.coil_centre_offset_m[j][1], 1e-15);
  }
}

// Without the coil centres the tilt torques are off by up to a quarter of the
// effort away from home (the forcer's vertical force moves between its coils
// with the commutation): what the bench measured as theta_x -> theta_y
// coupling. With them, the exact 2 x 2 solve leaves float round-off.
TEST(ForceAllocation, ForcerCentreModelLeavesTiltTorqueCoupling) {
  for (ForceLayout layout : {ForceLayout::kCross, ForceLayout::kSquare}) {
    const double worst = WorstRelativeWrenchError<float>(layout, 3000u + static_cast<unsigned>(layout), false);
    std::printf("\n  forcer-centre model, layout %d: worst |W/2b* - U|/|U| = %.3g", static_cast<int>(layout), worst);
    CHECK(worst > 0.05);
  }
}

TEST(ForceAllocation, CoilCentresBeyondAPitchOrNotFiniteRefused) {
  static ForceAllocationState<float> st;
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  cfg.coil_centre_offset_m[3][1] = 1.5 * cfg.pitch_m;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kBadCoilCentres);
  cfg = DefaultForceAllocationConfig();
  cfg.coil_centre_offset_m[0][0] = std::nan("");
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kBadCoilCentres);
}

TEST(ForceAllocation, CurrentsProduceCommandedWrenchFloat) {
  for (ForceLayout layout : {ForceLayout::kCross, ForceLayout::kSquare, ForceLayout::kTriangular}) {
    const double worst = WorstRelativeWrenchError<float>(layout, 1000u + static_cast<unsigned>(layout));
    std::printf("\n  float  layout %d: worst |W/2b* - U|/|U| = %.3g", static_cast<int>(layout), worst);
    CHECK(worst < 1e-5);
  }
}

// Q7.24 bound: each B entry and each U is quantised to 2^-25 (3e-8); each
// G = B U sums 6 rounded products (<= 6 * 3e-8 + B-quantisation 6 * 0.6 * 3e-8);
// sin/cos carry <= 4.2e-7 (numeric/sin_cos.hpp) on |G| <= ~1 A; two more
// roundings in 2(s G_h + c G_z). Per current <= ~2.5e-6 A, and the wrench
// inverse map (A S19 / 2) has gain <= 1/(4 l) = 4.8 on the torque rows:
// worst ~1.2e-5 A of effort on |U| = 0.6 A, i.e. 2e-5 relative; we assert 5e-5.
TEST(ForceAllocation, CurrentsProduceCommandedWrenchQ7_24) {
  for (ForceLayout layout : {ForceLayout::kCross, ForceLayout::kSquare, ForceLayout::kTriangular}) {
    const double worst = WorstRelativeWrenchError<Q7_24>(layout, 2000u + static_cast<unsigned>(layout));
    std::printf("\n  Q7.24  layout %d: worst |W/2b* - U|/|U| = %.3g", static_cast<int>(layout), worst);
    CHECK(worst < 5e-5);
  }
}

// Q7.24: the unsaturated three-product sum (every |B| < 32) gives the bits of
// Fixed::dot3, with and without the current limit, for every shipped layout.
TEST(ForceAllocation, BoundedRowSumsEqualTheSaturatingForm) {
  for (ForceLayout layout : {ForceLayout::kCross, ForceLayout::kSquare, ForceLayout::kTriangular}) {
    ForceAllocationConfig cfg = DefaultForceAllocationConfig();
    cfg.layout = layout;
    static ForceAllocationState<Q7_24> fast, general;
    CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &fast) == ForceAllocationError::kOk);
    CHECK(fast.b_below_32);
    general = fast;
    general.b_below_32 = false;
    std::mt19937 rng(11u + static_cast<unsigned>(layout));
    std::uniform_real_distribution<double> pos(-0.03, 0.03);
    std::uniform_real_distribution<double> eff(-6.0, 6.0);  // past the current limit too
    for (int n = 0; n < 2000; ++n) {
      const std::int64_t x_pm = std::llround(pos(rng) * 1e12), y_pm = std::llround(pos(rng) * 1e12);
      Q7_24 u[6];
      for (auto& v : u) v = Q7_24::from_double(eff(rng));
      AllocationOutput<Q7_24> a{}, b{};
      AllocateCurrents<Q7_24>(u, x_pm, y_pm, fast, &a);
      AllocateCurrents<Q7_24>(u, x_pm, y_pm, general, &b);
      for (int j = 0; j < 8; ++j) LONGS_EQUAL(b.current_A[j].raw(), a.current_A[j].raw());
      LONGS_EQUAL(b.scale_k.raw(), a.scale_k.raw());
    }
  }
}

TEST(ForceAllocation, CurrentLimitKeepsDirectionAndReportsK) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  static ForceAllocationState<Q7_24> sq;
  CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &sq) == ForceAllocationError::kOk);
  const double b_star = cfg.two_b_star_identified_N_per_A / 2.0;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-0.03, 0.03);
  std::uniform_real_distribution<double> eff(-1.0, 1.0);
  int saturated = 0;
  for (int n = 0; n < 200; ++n) {
    const double x = pos(rng), y = pos(rng);
    const std::int64_t x_pm = std::llround(x * 1e12), y_pm = std::llround(y * 1e12);
    float u[6];
    Q7_24 uq[6];
    for (int a = 0; a < 6; ++a) {
      u[a] = static_cast<float>(eff(rng) * ((a == 2 || a == 4 || a == 5) ? 0.4 : 1.0));
      uq[a] = Q7_24::from_float(u[a]);
    }
    AllocationOutput<float> out{};
    AllocateCurrents<float>(u, x_pm, y_pm, st, &out);
    AllocationOutput<Q7_24> oq{};
    AllocateCurrents<Q7_24>(uq, x_pm, y_pm, sq, &oq);
    double i[8], imax = 0.0;
    for (int j = 0; j < 8; ++j) {
      i[j] = static_cast<double>(out.current_A[j]);
      imax = std::fmax(imax, std::fabs(i[j]));
    }
    if (out.saturated) ++saturated;
    CHECK(imax <= cfg.peak_current_A * (1.0 + 1e-6));
    CHECK(static_cast<double>(out.scale_k) <= 1.0);
    if (out.saturated) DOUBLES_EQUAL(cfg.peak_current_A, imax, 1e-5);  // the limit is used fully
    // The wrench is 2 b* k U: same direction, no cross-axis force.
    double w[6];
    ForcerModelWrench(i, static_cast<double>(x_pm) * 1e-12, static_cast<double>(y_pm) * 1e-12, ForceLayout::kCross,
                      cfg.lever_arm_m, cfg.triangle_alpha_rad, b_star, w);
    double umax = 0.0;
    for (int a = 0; a < 6; ++a) umax = std::fmax(umax, std::fabs(static_cast<double>(u[a])));
    const double k = static_cast<double>(out.scale_k);
    for (int a = 0; a < 6; ++a) {
      DOUBLES_EQUAL(k * static_cast<double>(u[a]), w[a] / (2.0 * b_star), 1e-5 * k * umax);
      DOUBLES_EQUAL(k * static_cast<double>(u[a]), static_cast<double>(out.applied_effort_A[a]), 1e-6 * umax);
    }
    // Fixed point agrees on the saturation decision and on k.
    CHECK_EQUAL(out.saturated, oq.saturated);
    DOUBLES_EQUAL(k, oq.scale_k.to_double(), 2e-6);
  }
  std::printf("\n  current limit: %d of 200 random efforts saturated", saturated);
  CHECK(saturated > 20 && saturated < 180);
  // Small effort: k == 1 exactly, not saturated.
  float u[6] = {0.1f, 0.1f, 0.01f, 0.2f, 0.01f, 0.01f};
  AllocationOutput<float> out{};
  AllocateCurrents<float>(u, 0, 0, st, &out);
  CHECK_FALSE(out.saturated);
  DOUBLES_EQUAL(1.0, static_cast<double>(out.scale_k), 0.0);
  Q7_24 uq[6];
  for (int a = 0; a < 6; ++a) uq[a] = Q7_24::from_float(u[a]);
  AllocationOutput<Q7_24> oq{};
  AllocateCurrents<Q7_24>(uq, 0, 0, sq, &oq);
  CHECK(oq.scale_k == Q7_24::one());
}

TEST(ForceAllocation, GravityFeedForwardAndEffortConversion) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  const double full = 0.75 * 9.80665 / 1.7037;  // 4.3170 A
  DOUBLES_EQUAL(full, static_cast<double>(maglev::kernel::GravityFeedForward_A<float>(1.0f, st)), 1e-5);
  DOUBLES_EQUAL(full / 2, static_cast<double>(maglev::kernel::GravityFeedForward_A<float>(0.5f, st)), 1e-5);
  DOUBLES_EQUAL(0.0, static_cast<double>(maglev::kernel::GravityFeedForward_A<float>(-0.5f, st)), 0.0);
  DOUBLES_EQUAL(full, static_cast<double>(maglev::kernel::GravityFeedForward_A<float>(3.0f, st)), 1e-5);
  cfg.payload_kg = stage::kTestPayload_kg;
  static ForceAllocationState<Q7_24> sq;
  CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &sq) == ForceAllocationError::kOk);
  DOUBLES_EQUAL((0.75 + 0.5396) * 9.80665 / 1.7037,
                maglev::kernel::GravityFeedForward_A<Q7_24>(Q7_24::one(), sq).to_double(), 1e-6);
  // 1 N -> 1/1.7037 A
  DOUBLES_EQUAL(1.0 / 1.7037, static_cast<double>(maglev::kernel::EffortFromForce_A<float>(1.0f, st)), 1e-6);
  // The lift effort alone, through the kernel, levitates: Fz = 2 b* U_z = m g.
  float u[6] = {0, 0, 0, static_cast<float>(full), 0, 0};
  AllocationOutput<float> out{};
  AllocateCurrents<float>(u, std::llround(0.0123 * 1e12), std::llround(-0.0071 * 1e12), st, &out);
  double i[8], w[6];
  for (int j = 0; j < 8; ++j) i[j] = static_cast<double>(out.current_A[j]);
  ForcerModelWrench(i, 0.0123, -0.0071, ForceLayout::kCross, cfg.lever_arm_m, 0.0, 1.7037 / 2, w);
  DOUBLES_EQUAL(0.75 * 9.80665, w[3], 1e-4);
}

TEST(ForceAllocation, BStarFromMagnetisation) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  cfg.magnetization_A_per_m = 1.0;
  const double b1 = maglev::kernel::BStarFromGeometry(cfg);
  // Hand evaluation of eq (20) with eq (3) at z0 = 1.6 mm, M0 = 1 A/m.
  const double g = 2 * kPi / 0.0508;
  const double c1 = 2 * std::sqrt(2.0) * 4e-7 * kPi / kPi * (1 - std::exp(-g * 0.0127)) * std::exp(-g * 0.0016);
  const double expect = 0.04229 * c1 * 4 * 30 / (0.00254 * 0.00965 * g * g) * std::sin(g * 0.00965 / 2) *
                        (1 - std::exp(-g * 0.00254));
  DOUBLES_EQUAL(expect, b1, 1e-18);
  const double m0 = 1.7037 / (2 * b1);
  std::printf("\n  b* per (A/m) = %.6g; 2b* = 1.7037 N/A <=> M0 = %.6g A/m (mu0 M0 = %.4f T)", b1, m0,
              4e-7 * kPi * m0);
  cfg.magnetization_A_per_m = m0;
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  DOUBLES_EQUAL(1.7037, st.two_b_star_N_per_A, 1e-9);
}

// The float kernel's DAC code (the M7's tick converts eight a tick; on the
// M7 it is VRINTA, a saturating VCVT and SSAT, on the host the portable
// form: this test runs on both). The same code as the reference form --
// NaN -> 0, clamp to [-32768, 32767] in double, round half away from zero
// -- for currents around every half code of the range and beyond it (each
// float and its two neighbours), the bounds, values beyond the int32 range
// (where the M7's VCVT saturates before SSAT does), signed zeros,
// infinities and NaN.
TEST(ForceAllocation, DacCodeRoundsHalfAwayAndSaturates) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  auto reference = [&](float amps) {
    const double v = static_cast<double>(amps) * st.dac_codes_per_A;
    if (!(v == v)) return 0;
    const double c = v > 32767.0 ? 32767.0 : (v < -32768.0 ? -32768.0 : v);
    return static_cast<int>(std::round(c));
  };
  auto check = [&](float amps) {
    const int got = maglev::kernel::CurrentToDacCode<float>(amps, st);
    if (got != reference(amps)) CHECK_EQUAL(reference(amps), got);
  };
  const float special[] = {0.0f, -0.0f, INFINITY, -INFINITY, NAN, 1e30f, -1e30f,
                           static_cast<float>(32767.0 / st.dac_codes_per_A), static_cast<float>(-32768.0 / st.dac_codes_per_A)};
  for (float a : special) check(a);
  for (double v : {2147483647.0, 2147483648.0, 4294967296.0, 1e15, 65535.5, 65536.0, 98304.0}) {
    for (double sign : {1.0, -1.0}) {
      const float a = static_cast<float>(sign * v / st.dac_codes_per_A);
      check(a);
      check(std::nextafter(a, INFINITY));
      check(std::nextafter(a, -INFINITY));
    }
  }
  int checked = 0;
  for (int k = -33000; k <= 33000; ++k) {
    for (double d : {-0.5, -0.25, 0.0, 0.25, 0.5}) {
      const float a = static_cast<float>((k + d) / st.dac_codes_per_A);
      check(a);
      check(std::nextafter(a, INFINITY));
      check(std::nextafter(a, -INFINITY));
      checked += 3;
    }
  }
  CHECK(checked > 900000);
}

// The Q7.24 kernel's DAC code (one SMULL, the rounding in one 64-bit sum,
// SSAT on the M7; this test runs on the host and on the M7) against the
// form it replaced: shift_round of the exact product (half away from zero)
// and an int64 clamp. Every raw value whose product lies within a few LSB
// of a half code (the ties and their neighbours, both signs) over the DAC's
// range and beyond, the Q7.24 extremes, and pseudo-random raws.
// The default gains put exact ties only beyond the range; 0.8 A/V (4096
// codes per A, q32 = 2^20) puts one in every code.
static void CheckFixedDacCodes(double amplifier_gain_A_per_V) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  cfg.amplifier_gain_A_per_V = amplifier_gain_A_per_V;
  static ForceAllocationState<Q7_24> sq;
  CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &sq) == ForceAllocationError::kOk);
  auto reference = [&](std::int32_t raw) {
    std::int64_t code = maglev::numeric::detail::shift_round(std::int64_t{raw} * sq.dac_q32_per_raw, 32);
    code = code > 32767 ? 32767 : (code < -32768 ? -32768 : code);
    return static_cast<int>(code);
  };
  long checked = 0;
  auto check = [&](std::int64_t raw64) {
    if (raw64 > INT32_MAX || raw64 < INT32_MIN) return;
    const auto raw = static_cast<std::int32_t>(raw64);
    const int got = maglev::kernel::CurrentToDacCode<Q7_24>(Q7_24::from_raw(raw), sq);
    if (got != reference(raw)) CHECK_EQUAL(reference(raw), got);
    ++checked;
  };
  const double raw_per_code = 4294967296.0 / static_cast<double>(sq.dac_q32_per_raw);
  for (int k = -33000; k <= 33000; ++k) {
    const auto tie = static_cast<std::int64_t>(std::floor((k + 0.5) * raw_per_code));
    for (std::int64_t d = -3; d <= 3; ++d) check(tie + d);
  }
  for (std::int64_t raw : {std::int64_t{INT32_MAX}, std::int64_t{INT32_MIN}, std::int64_t{INT32_MIN} + 1, std::int64_t{0},
                           std::int64_t{1}, std::int64_t{-1}}) {
    check(raw);
  }
  std::mt19937 rng(16);
  for (int n = 0; n < 200000; ++n) check(static_cast<std::int32_t>(rng()));
  CHECK(checked > 600000);
}

TEST(ForceAllocation, DacCodeFixedRoundsHalfAwayAndSaturates) {
  CheckFixedDacCodes(DefaultForceAllocationConfig().amplifier_gain_A_per_V);
  CheckFixedDacCodes(0.8);
}

TEST(ForceAllocation, DacCodesRoundAndSaturate) {
  ForceAllocationConfig cfg = DefaultForceAllocationConfig();
  static ForceAllocationState<float> st;
  CHECK(ApplyForceAllocationConfig<float>(cfg, &st) == ForceAllocationError::kOk);
  static ForceAllocationState<Q7_24> sq;
  CHECK(ApplyForceAllocationConfig<Q7_24>(cfg, &sq) == ForceAllocationError::kOk);
  // 0.5 A/V, 10 V: 6553.6 codes per A.
  const struct {
    double amps;
    int code;
  } cases[] = {{0.0, 0},          {1.0, 6554},     {-1.0, -6554},     {0.25, 1638},   {-0.25, -1638},
               {4.0, 26214},      {-4.0, -26214},  {4.9999, 32767},   {5.0, 32767},   {-5.0, -32768},
               {12.0, 32767},     {-12.0, -32768}, {2.6 / 32768, 1},  {-2.6 / 32768, -1},
               {2.4 / 32768, 0},  {1.6 / 32768, 0}};
  for (const auto& c : cases) {
    CHECK_EQUAL(c.code, maglev::kernel::CurrentToDacCode<float>(static_cast<float>(c.amps), st));
    CHECK_EQUAL(c.code, maglev::kernel::CurrentToDacCode<Q7_24>(Q7_24::from_double(c.amps), sq));
  }
  // Every code over the range: float and Q7.24 agree within one code.
  for (int n = -40000; n <= 40000; n += 7) {
    const double a = n / 6553.6 + 0.37 / 6553.6;
    const int cf = maglev::kernel::CurrentToDacCode<float>(static_cast<float>(a), st);
    const int cq = maglev::kernel::CurrentToDacCode<Q7_24>(Q7_24::from_double(a), sq);
    CHECK(cf - cq <= 1 && cq - cf <= 1);
  }
  // Monitor: +-10 V over +-5 A, 2 V/A: code 6554 = 2.0001 V = 1.00006 A.
  DOUBLES_EQUAL(6554 * 10.0 / 32768 / 2, static_cast<double>(maglev::kernel::MonitorCodeToCurrent_A<float>(6554, st)),
                1e-7);
  DOUBLES_EQUAL(-32768 * 10.0 / 32768 / 2, maglev::kernel::MonitorCodeToCurrent_A<Q7_24>(-32768, sq).to_double(), 1e-7);
  DOUBLES_EQUAL(1234 * 10.0 / 32768 / 2, maglev::kernel::MonitorCodeToCurrent_A<Q7_24>(1234, sq).to_double(), 1e-7);
}
