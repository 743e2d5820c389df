// The triangle layout (paper 003 eq (8)) on the bench plant: the oblique
// coil-side field model against a fine numerical integration of the point
// field, the coils' forces against the kernel's commutation, and the wrench
// of the kernel's hover currents against the same numerical physics.
#include <cmath>
#include <cstdio>
#include <vector>

#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::BodyConfig;
using maglev::hil::BodyState;
using maglev::hil::FieldConfig;
using maglev::hil::FieldSZ;
using maglev::hil::FieldXYZ;
using maglev::hil::HalbachField;
using maglev::hil::ObliqueSideAmplitudes;
using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace stage = maglev::io::stage;
namespace kn = maglev::kernel;

namespace {

constexpr double kAlpha_rad = stage::kPi / 6.0;

// n-point Gauss-Legendre nodes and weights on [-1, 1] (Newton on P_n).
struct Gauss {
  std::vector<double> x, w;
  explicit Gauss(int n) : x(static_cast<std::size_t>(n)), w(static_cast<std::size_t>(n)) {
    for (int i = 0; i < n; ++i) {
      double z = std::cos(stage::kPi * (i + 0.75) / (n + 0.5));
      double dp = 1.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0, p1 = z;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1.0);
        const double dz = p1 / dp;
        z -= dz;
        if (std::fabs(dz) < 1e-16) break;
      }
      x[static_cast<std::size_t>(i)] = z;
      w[static_cast<std::size_t>(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

// Mean of f over [lo, hi]: `pieces` sub-intervals of an 8-point rule.
template <typename F>
void MeanOver(double lo, double hi, int pieces, const Gauss& g, F f) {
  const double h = (hi - lo) / pieces;
  for (int k = 0; k < pieces; ++k) {
    const double mid = lo + (k + 0.5) * h;
    for (std::size_t i = 0; i < g.x.size(); ++i) f(mid + 0.5 * h * g.x[i], 0.5 * g.w[i] * h / (hi - lo));
  }
}

// The matrix's field (X array + Y array point fields) averaged over a side
// along (cos phi, sin phi) with midpoint (x0, y0): length p, width a, from the
// gap up through the coil thickness d. Brute force, independent of the
// sinc factors under test.
FieldXYZ NumericalSideField(const HalbachField& field, const FieldConfig& fc, double cos_phi, double sin_phi,
                            double x0, double y0, double gap) {
  const Gauss g(8);  // (not static: CppUTest counts a first-use allocation as a leak)
  FieldXYZ sum{0.0, 0.0, 0.0};
  MeanOver(-fc.coil_effective_length_m / 2, fc.coil_effective_length_m / 2, 16, g, [&](double t, double wt) {
    MeanOver(-fc.coil_side_width_m / 2, fc.coil_side_width_m / 2, 6, g, [&](double w, double ww) {
      MeanOver(gap, gap + fc.coil_thickness_m, 3, g, [&](double z, double wz) {
        const double x = x0 + t * cos_phi - w * sin_phi;
        const double y = y0 + t * sin_phi + w * cos_phi;
        const FieldSZ bx = field.PointField(x, z);
        const FieldSZ by = field.PointField(y, z);
        const double weight = wt * ww * wz;
        sum.b_x_T += weight * bx.b_s_T;
        sum.b_y_T += weight * by.b_s_T;
        sum.b_z_T += weight * (bx.b_z_T + by.b_z_T);
      });
    });
  });
  return sum;
}

PlantConfig TrianglePlant(int harmonics) {
  PlantConfig c = PlantConfig::Ideal();
  c.body.layout = BodyConfig::Layout::kTriangle;
  c.body.triangle_alpha_rad = kAlpha_rad;
  c.field.harmonics = harmonics;
  return c;
}

BodyState Levitated() {
  BodyState s;
  s.position_m.z() = stage::kNominalHeight_m;
  return s;
}

kn::ForceAllocationConfig TriangleAllocation() {
  kn::ForceAllocationConfig c = kn::DefaultForceAllocationConfig();
  c.layout = kn::ForceLayout::kTriangular;
  c.triangle_alpha_rad = kAlpha_rad;
  return c;
}

// Wrench (world force, torque about the CoM) of the plant's coil sides from
// the numerical side field: N I p (u x B_avg) at each side's midpoint, level
// platen at the given height.
void NumericalWrench(const Plant& plant, const double* currents_A, double height_m, double force[3],
                     double torque[3]) {
  const FieldConfig& fc = plant.config().field;
  const HalbachField& field = plant.field();
  for (int a = 0; a < 3; ++a) force[a] = torque[a] = 0.0;
  for (const auto& cs : plant.coil_sides()) {
    if (cs.coil < 0) continue;
    const double c = cs.u_body.x(), s = cs.u_body.y();
    const FieldXYZ b = NumericalSideField(field, fc, c, s, cs.r_body_m.x(), cs.r_body_m.y(), fc.rest_gap_m + height_m);
    const double k = fc.coil_turns * fc.coil_effective_length_m * currents_A[cs.coil];
    const double f[3] = {k * (s * b.b_z_T), k * (-c * b.b_z_T), k * (c * b.b_y_T - s * b.b_x_T)};
    const double* r = cs.r_body_m.data();
    force[0] += f[0];
    force[1] += f[1];
    force[2] += f[2];
    torque[0] += r[1] * f[2] - r[2] * f[1];
    torque[1] += r[2] * f[0] - r[0] * f[2];
    torque[2] += r[0] * f[1] - r[1] * f[0];
  }
}

}  // namespace

TEST_GROUP(TrianglePlant){};

// The analytical sinc factors equal the brute-force average of both arrays'
// point fields over the side's volume, at every angle (along X and Y too).
TEST(TrianglePlant, ObliqueSideFieldEqualsNumericalIntegration) {
  const PlantConfig c = TrianglePlant(4);
  const HalbachField field(c.field);
  const double angles_deg[] = {0.0, 17.0, 30.0, 60.0, 90.0, 120.0, 210.0, -45.0};
  const double points[][3] = {{0.0, 0.0, 0.0016}, {0.0123, -0.0311, 0.00163}, {-0.0451, 0.026, 0.0019}};
  double worst = 0.0;
  for (double deg : angles_deg) {
    const double phi = deg * stage::kPi / 180.0;
    const ObliqueSideAmplitudes amp = field.ObliqueAmplitudes(std::cos(phi), std::sin(phi));
    for (const auto& pt : points) {
      const FieldXYZ a = field.ObliqueSideField(amp, pt[0], pt[1], pt[2]);
      const FieldXYZ n = NumericalSideField(field, c.field, std::cos(phi), std::sin(phi), pt[0], pt[1], pt[2]);
      worst = std::fmax(worst, std::fabs(a.b_x_T - n.b_x_T));
      worst = std::fmax(worst, std::fabs(a.b_y_T - n.b_y_T));
      worst = std::fmax(worst, std::fabs(a.b_z_T - n.b_z_T));
      // The field is of order 0.1 T: the comparison is not trivially small.
      CHECK(std::fabs(n.b_z_T) + std::fabs(n.b_x_T) + std::fabs(n.b_y_T) > 1e-3);
    }
  }
  std::printf("\n  oblique side field: analytical vs numerical, worst |dB| = %.3g T\n", worst);
  CHECK(worst < 1e-12);
}

// Along Y the oblique model's X-array amplitudes are the cross layout's own
// side amplitudes (same physics, other arithmetic).
TEST(TrianglePlant, ObliqueAmplitudesReduceToTheArraySideModel) {
  const PlantConfig c = TrianglePlant(4);
  const HalbachField field(c.field);
  const ObliqueSideAmplitudes amp = field.ObliqueAmplitudes(0.0, 1.0);
  for (int h = 0; h < maglev::hil::kMaxHarmonics; ++h) {
    DOUBLES_EQUAL(field.side_amplitudes_T()[h], amp.x_array_T[h], 1e-14);
  }
}

// Each coil's force at home lies exactly along the kernel's commutation
// direction (sin psi_j, cos psi_j) on (its forcer's thrust axis, Z); coils 7
// and 8 do not exist. Magnitudes: b* for the X forcer, less for the oblique
// ones (two arrays instead of one travelling wave along the thrust axis).
TEST(TrianglePlant, CoilForcesFollowTheKernelsCommutation) {
  const Plant plant(TrianglePlant(1), 1);
  kn::ForceAllocationState<float> st{};
  CHECK(kn::ApplyForceAllocationConfig(TriangleAllocation(), &st) == kn::ForceAllocationError::kOk);
  std::uint32_t turn[maglev::io::kCoils];
  kn::CommutationPhases(0, 0, st.commutation, turn);
  const double b_star = plant.field().BStar(stage::kRestGap_m + stage::kNominalHeight_m);
  std::printf("\n");
  for (int j = 0; j < 8; ++j) {
    const Eigen::Vector3d f = plant.CoilForceWorld(Levitated(), j, 1.0);
    if (j >= 6) {
      DOUBLES_EQUAL(0.0, f.norm(), 0.0);
      continue;
    }
    const int forcer = j / 2;
    const double psi = turn[j] * (2.0 * stage::kPi / 4294967296.0);
    const double hx = st.tables.h_dir[forcer][0], hy = st.tables.h_dir[forcer][1];
    const Eigen::Vector3d want(std::sin(psi) * hx, std::sin(psi) * hy, std::cos(psi));
    const double along = f.dot(want);
    const double off = (f - along * want).norm();
    std::printf("  coil %d: |F| = %.4f b*, off the kernel's direction %.2g b*\n", j + 1, along / b_star,
                off / b_star);
    CHECK(along > 0.5 * b_star);
    CHECK(off < 1e-12 * b_star);
    if (forcer == 2) DOUBLES_EQUAL(1.0, along / b_star, 1e-12);
  }
}

// The kernel's hover currents (gravity feed-forward through its triangle
// allocation) on the plant: no in-plane force, no yaw or roll torque, as the
// allocation intends; the vertical force and pitch torque are what the
// numerical physics of the plant's coil sides gives (the oblique forcers lift
// less than b* per ampere: docs/PLANT.md), and the plant's assembly of
// sides, currents and arms reproduces that physics.
TEST(TrianglePlant, HoverCurrentsGiveTheIntendedWrenchDirections) {
  for (int harmonics : {1, 4}) {
    const Plant plant(TrianglePlant(harmonics), 1);
    kn::ForceAllocationState<float> st{};
    CHECK(kn::ApplyForceAllocationConfig(TriangleAllocation(), &st) == kn::ForceAllocationError::kOk);
    const float effort[kn::kEfforts] = {0.0f, 0.0f, 0.0f, kn::GravityFeedForward_A(1.0f, st), 0.0f, 0.0f};
    kn::AllocationOutput<float> out{};
    kn::AllocateCurrents(effort, 0, 0, st, &out);
    double currents[maglev::io::kCoils];
    for (int j = 0; j < maglev::io::kCoils; ++j) currents[j] = out.current_A[j];
    DOUBLES_EQUAL(0.0, currents[6], 0.0);
    DOUBLES_EQUAL(0.0, currents[7], 0.0);
    const maglev::hil::Wrench w = plant.MagneticWrench(Levitated(), currents);
    double fn[3], tn[3];
    NumericalWrench(plant, currents, stage::kNominalHeight_m, fn, tn);
    const double weight = stage::kMass_kg * stage::kGravity_m_per_s2;
    std::printf("\n  harmonics %d: F = (%.3g, %.3g, %.5f) N = %.4f m g, T = (%.3g, %.3g, %.3g) N m\n", harmonics,
                w.force_world_N.x(), w.force_world_N.y(), w.force_world_N.z(), w.force_world_N.z() / weight,
                w.torque_body_Nm.x(), w.torque_body_Nm.y(), w.torque_body_Nm.z());
    for (int a = 0; a < 3; ++a) {
      DOUBLES_EQUAL(fn[a], w.force_world_N[a], 1e-10);
      DOUBLES_EQUAL(tn[a], w.torque_body_Nm[a], 1e-12);
    }
    // The allocation's intent: in-plane force, yaw and roll zero. Float
    // currents (2^-24 relative) and, with 4 harmonics, the higher harmonics'
    // share (~0.3 %) bound what remains.
    const double tol_f = harmonics == 1 ? 1e-6 * weight : 5e-3 * weight;
    DOUBLES_EQUAL(0.0, w.force_world_N.x(), tol_f);
    DOUBLES_EQUAL(0.0, w.force_world_N.y(), tol_f);
    DOUBLES_EQUAL(0.0, w.torque_body_Nm.z(), tol_f * stage::kLeverArm_m);
    DOUBLES_EQUAL(0.0, w.torque_body_Nm.y(), tol_f * stage::kLeverArm_m);
    // It lifts: between the oblique forcers' share and the full weight.
    CHECK(w.force_world_N.z() > 0.75 * weight && w.force_world_N.z() < weight);
  }
}
