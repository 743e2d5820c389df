// Field and force model: M0 calibration, eq (19) reproduced exactly with
// n = 1, and the paper's harmonic check (0.3 % / 0.1 % at z = 2 mm).
#include <cmath>
#include <cstdio>

#include "allocation_copy.hpp"
#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::BodyState;
using maglev::hil::HalbachField;
using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace stage = maglev::io::stage;
namespace t = maglev::hil::test;

TEST_GROUP(PlantField){};

TEST(PlantField, M0CalibratedToIdentifiedTwoBStar) {
  const PlantConfig c = PlantConfig::Ideal();
  const HalbachField field(c.field);
  const double m0 = field.peak_magnetization_A_per_m();
  const double two_b_star = 2.0 * field.BStar(stage::kRestGap_m);
  std::printf("\n  M0 = %.1f A/m (mu0*M0 = %.4f T), 2b*(z0) = %.6f N/A, c1(z0) = %.4f T\n", m0, stage::kMu0 * m0,
              two_b_star, field.C1(stage::kRestGap_m));
  DOUBLES_EQUAL(stage::kTwoBStarIdentified_N_per_A, two_b_star, 1e-12);
  // mu0*M0 is ~0.71 T: below NdFeB 35's Br of ~1.2 T (documented in PLANT.md).
  CHECK(stage::kMu0 * m0 > 0.6 && stage::kMu0 * m0 < 0.8);
  // Eq (20) written out by hand for the same M0.
  const double g = stage::kGamma1_per_m;
  const double c1 = 2.0 * std::sqrt(2.0) * stage::kMu0 * m0 / stage::kPi *
                    (1.0 - std::exp(-g * stage::kMagnetThickness_m)) * std::exp(-g * stage::kRestGap_m);
  const double b_star = stage::kCoilEffectiveLength_m * c1 * 4.0 * stage::kCoilTurns /
                        (stage::kCoilThickness_m * stage::kCoilSideWidth_m * g * g) *
                        std::sin(g * stage::kCoilSideWidth_m / 2.0) * (1.0 - std::exp(-g * stage::kCoilThickness_m));
  DOUBLES_EQUAL(b_star, field.BStar(stage::kRestGap_m), 1e-12);
}

TEST(PlantField, HarmonicRatiosMatchPaperCheckAtTwoMillimetres) {
  const HalbachField field(PlantConfig::Ideal().field);
  const double r5 = field.HarmonicForceRatio(5, 0.002);
  const double r9 = field.HarmonicForceRatio(9, 0.002);
  std::printf("\n  harmonic force ratios at z = 2 mm: n=5 %.4f %%, n=9 %.4f %%\n", 100 * r5, 100 * r9);
  DOUBLES_EQUAL(0.003, r5, 0.0005);  // "only 0.3% ..."
  DOUBLES_EQUAL(0.001, r9, 0.0003);  // "... and 0.1%"
}

// Forcer forces [F12x F12z F34y F34z F56x F56z F78y F78z] from per-coil forces.
static t::Vector8 ForcerForces(const Plant& plant, const BodyState& s, const t::Vector8& i, Eigen::Vector3d* stray) {
  t::Vector8 f = t::Vector8::Zero();
  *stray = Eigen::Vector3d::Zero();
  for (int j = 0; j < 8; ++j) {
    const Eigen::Vector3d fc = plant.CoilForceWorld(s, j, i[j]);
    const int forcer = j / 2;
    const int tangential = (forcer % 2 == 0) ? 0 : 1;
    f[2 * forcer] += fc[tangential];
    f[2 * forcer + 1] += fc.z();
    (*stray)[0] += std::fabs(fc[1 - tangential]);  // the other in-plane axis must be 0
  }
  return f;
}

TEST(PlantField, Eq19ReproducedExactlyAtNominalGapWithFundamentalOnly) {
  PlantConfig c = PlantConfig::Ideal();
  c.field.harmonics = 1;
  const Plant plant(c, 1);
  const double b_star = plant.field().BStar(stage::kRestGap_m);
  const double xs[] = {0.0, 0.0031, -0.0127, 0.0212, 0.04};
  const double ys[] = {0.0, -0.0077, 0.0093, 0.0254, -0.017};
  int checked = 0;
  for (double x : xs) {
    for (double y : ys) {
      BodyState s;
      s.position_m = {x, y, 0.0};  // z = 0: the nominal gap z0 = 1.6 mm, level
      t::Vector8 i;
      i << 0.7, -1.3, 0.4, 2.1, -0.9, 1.1, -1.7, 0.25;
      Eigen::Vector3d stray;
      const t::Vector8 f = ForcerForces(plant, s, i, &stray);
      const t::Vector8 expected =
          b_star * t::S19(x + stage::kBasePointX2_m, y + stage::kBasePointY8_m) * i;
      for (int k = 0; k < 8; ++k) {
        DOUBLES_EQUAL(expected[k], f[k], 1e-12);
      }
      DOUBLES_EQUAL(0.0, stray[0], 1e-15);
      ++checked;
    }
  }
  CHECK_EQUAL(25, checked);
}

TEST(PlantField, NominalAllocationGivesTheCommandedWrench) {
  // Level, z = 0, n = 1: A * F(i = 2 S B U) = 2 b* U (eq 22) in the plant's
  // own per-side torques (the acting points come from the coil geometry).
  PlantConfig c = PlantConfig::Ideal();
  c.field.harmonics = 1;
  const Plant plant(c, 1);
  const double two_b_star = 2.0 * plant.field().BStar(stage::kRestGap_m);
  BodyState s;
  s.position_m = {0.0, 0.0, 0.0};
  t::Vector6 u;
  u << 0.3, -0.2, 0.1, 1.5, 0.05, -0.04;
  const t::Vector8 i = t::CurrentsFromEffort(u, 0.0, 0.0);
  const auto w = plant.MagneticWrench(s, i.data());
  DOUBLES_EQUAL(two_b_star * u[0], w.force_world_N.x(), 1e-12);
  DOUBLES_EQUAL(two_b_star * u[1], w.force_world_N.y(), 1e-12);
  DOUBLES_EQUAL(two_b_star * u[3], w.force_world_N.z(), 1e-12);
  DOUBLES_EQUAL(two_b_star * u[2], w.torque_body_Nm.z(), 1e-12);
  DOUBLES_EQUAL(two_b_star * u[4], w.torque_body_Nm.x(), 1e-12);
  DOUBLES_EQUAL(two_b_star * u[5], w.torque_body_Nm.y(), 1e-12);
}

TEST(PlantField, CoilSidesOfAPairAreAQuarterPitchApart) {
  const Plant plant(PlantConfig::Ideal(), 1);
  for (int f = 0; f < 4; ++f) {
    double pos[4];
    int n = 0;
    for (const auto& side : plant.coil_sides()) {
      if (side.forcer == f) {
        pos[n++] = side.r_body_m[side.array_axis];
      }
    }
    CHECK_EQUAL(4, n);
    std::sort(pos, pos + 4);
    for (int k = 0; k < 3; ++k) {
      DOUBLES_EQUAL(stage::kPitch_m / 4, pos[k + 1] - pos[k], 1e-12);
    }
  }
}

TEST(PlantField, FastWrenchEqualsPerSideReference) {
  // The force loop derives side phases per forcer; CoilForceWorld evaluates
  // every side with its own sincos/exp. They must agree at any pose.
  const Plant plant(PlantConfig::Default(), 1);
  BodyState s;
  s.position_m = {0.0123, -0.0071, 25e-6};
  s.attitude = Eigen::Quaterniond(Plant::RotationFromAngles(40e-6, -25e-6, 2.5e-3));
  const double i[8] = {0.7, -1.3, 0.4, 2.1, -0.9, 1.1, -1.7, 0.25};
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int j = 0; j < 8; ++j) sum += plant.CoilForceWorld(s, j, i[j]);
  const auto w = plant.MagneticWrench(s, i);
  for (int a = 0; a < 3; ++a) DOUBLES_EQUAL(sum[a], w.force_world_N[a], 1e-12);
}

TEST(PlantField, FastWrenchEqualsPerSideReferenceWithShiftedCoils) {
  // As built, the coils sit off their places along the array (a commutation
  // phase error, 0.1 mm sigma): a side's phase is no longer its reference
  // side's plus whole quarter turns. The force loop folds the constant
  // residual into the side's offset (Plant's SideConstants::q_half_pi);
  // per side the field is still the library's at the side's own place.
  PlantConfig c = PlantConfig::Default();
  c.as_built.active = true;
  const double shift_m[8] = {1.5e-4, -0.8e-4, 2.1e-4, -1.2e-4, 0.4e-4, -2.4e-4, 0.9e-4, 1.8e-4};
  for (int j = 0; j < 8; ++j) c.as_built.coil_shift_m[j] = shift_m[j];
  const Plant plant(c, 1);
  for (const double theta_z : {0.0, 2.5e-3, -3.7e-3}) {
    BodyState s;
    s.position_m = {0.0123, -0.0071, 25e-6};
    s.attitude = Eigen::Quaterniond(Plant::RotationFromAngles(40e-6, -25e-6, theta_z));
    const double i[8] = {0.7, -1.3, 0.4, 2.1, -0.9, 1.1, -1.7, 0.25};
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j = 0; j < 8; ++j) sum += plant.CoilForceWorld(s, j, i[j]);
    const auto w = plant.MagneticWrench(s, i);
    for (int a = 0; a < 3; ++a) DOUBLES_EQUAL(sum[a], w.force_world_N[a], 1e-12);
  }
}
