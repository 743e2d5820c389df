// Issue 15, the plant as built: error sets drawn reproducibly inside their
// bounds, zero errors = the nominal stage, and the drawn errors make real
// cross-coupling (off-axis wrench of a pure thrust command) of the size the
// geometry predicts.
#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "maglev/plant/amplifier.hpp"
#include "maglev/plant/as_built.hpp"
#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::DrawAsBuilt;
using maglev::hil::DrawnErrors;
using maglev::hil::ErrorSet;
using maglev::hil::NominalPlant;
using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace hil = maglev::hil;

TEST_GROUP(AsBuilt){};

namespace {

double Value(const DrawnErrors& d, const std::string& name) {
  for (const auto& [n, v] : d) {
    if (n == name) return v;
  }
  FAIL(("no drawn error " + name).c_str());
  return 0.0;
}

PlantConfig Quiet(PlantConfig c) {
  c.sensor_noise_enabled = false;
  c.amplifier.current_noise_scale = 0.0;
  return c;
}

// Magnetic wrench (force world, torque body) per unit current of each coil
// at the plant's own initial pose: the 6x8 allocation the plant realizes.
Eigen::Matrix<double, 6, 8> Allocation(const Plant& p) {
  Eigen::Matrix<double, 6, 8> a;
  for (int j = 0; j < 8; ++j) {
    double i[8] = {};
    i[j] = 1.0;
    const hil::Wrench w = p.MagneticWrench(p.body_state(), i);
    a.col(j) << w.force_world_N, w.torque_body_Nm;
  }
  return a;
}

}  // namespace

TEST(AsBuilt, DrawIsReproducibleAndInsideItsBounds) {
  ErrorSet set;
  set.error_seed = 7;
  PlantConfig a = NominalPlant(PlantConfig::Ideal());
  PlantConfig b = NominalPlant(PlantConfig::Ideal());
  const DrawnErrors da = DrawAsBuilt(set, &a);
  const DrawnErrors db = DrawAsBuilt(set, &b);
  CHECK_EQUAL(da.size(), db.size());
  for (std::size_t i = 0; i < da.size(); ++i) {
    CHECK(da[i].first == db[i].first);
    CHECK_EQUAL(da[i].second, db[i].second);  // bit for bit
  }
  set.error_seed = 8;
  PlantConfig c = NominalPlant(PlantConfig::Ideal());
  const DrawnErrors dc = DrawAsBuilt(set, &c);
  int differ = 0;
  for (std::size_t i = 0; i < da.size(); ++i) differ += da[i].second != dc[i].second;
  CHECK(differ > 60);  // all but the seed-independent trailer
  // Every drawn value inside its term's law: tolerance classes within +-M,
  // bands within [lo M, M].
  for (int j = 1; j <= 8; ++j) {
    CHECK(std::fabs(Value(da, "amp" + std::to_string(j) + "_gain_error")) <= 0.01);
    CHECK(std::fabs(Value(da, "amp" + std::to_string(j) + "_offset_A")) <= 5e-3);
    CHECK(std::fabs(Value(da, "amp" + std::to_string(j) + "_bandwidth_error")) <= 0.10);
  }
  for (const char* k : {"com_x_m", "com_y_m"}) {
    const double v = std::fabs(Value(da, k));
    CHECK(v >= 2e-3 - 1e-15 && v <= 5e-3);
  }
  const double h = Value(da, "com_height_m");
  CHECK(h >= 3e-3 - 1e-15 && h <= 8e-3);
  CHECK(std::fabs(Value(da, "x_mirror_yaw_rad")) <= 0.3e-3);
  // And the drawn values are the ones the plant got.
  DOUBLES_EQUAL(Value(da, "amp3_gain_error"), a.amplifier.gain_error[2], 0.0);
  DOUBLES_EQUAL(Value(da, "com_height_m"), a.body.com_above_coil_midplane_m, 0.0);
  DOUBLES_EQUAL(Value(da, "forcer2_yaw_rad"), a.forcer_errors.misalignment_rad[1], 0.0);
  CHECK(a.as_built.active);
}

TEST(AsBuilt, ZeroErrorScaleIsTheNominalStage) {
  const PlantConfig nominal = Quiet(NominalPlant(PlantConfig::Default()));
  PlantConfig zero = nominal;
  ErrorSet set;
  set.error_scale = 0.0;
  DrawAsBuilt(set, &zero);
  CHECK(zero.as_built.active);  // the as-built code paths run, with zero errors
  Plant pn(nominal, 3), pz(zero, 3);
  hil::BodyState s;
  s.position_m = {4.1e-3, -2.3e-3, 30e-6};
  s.attitude = Eigen::Quaterniond(Plant::RotationFromAngles(20e-6, -15e-6, 40e-6));
  pn.set_body_state(s);
  pz.set_body_state(s);
  const double i[8] = {0.3, -0.2, 0.5, 0.1, -0.4, 0.25, 0.05, -0.15};
  const hil::Wrench wn = pn.MagneticWrench(s, i), wz = pz.MagneticWrench(s, i);
  CHECK((wn.force_world_N - wz.force_world_N).norm() <= 1e-12 * wn.force_world_N.norm());
  CHECK((wn.torque_body_Nm - wz.torque_body_Nm).norm() <= 1e-12 * wn.torque_body_Nm.norm() + 1e-15);
  const maglev::io::SensorSample a = pn.sample(), b = pz.sample();
  for (int k = 0; k < 3; ++k) {
    CHECK(std::abs(static_cast<std::int64_t>(a.interferometer_counts[k]) -
                   static_cast<std::int64_t>(b.interferometer_counts[k])) <= 1);
    CHECK(std::abs(a.displacement_adc[k] - b.displacement_adc[k]) <= 1);
  }
}

TEST(AsBuilt, PureThrustCouplesIntoTiltAndYawAsTheGeometrySays) {
  // Currents that make the NOMINAL stage produce exactly Fx = 0.9 N (0.75 kg
  // at 1.2 m/s^2, paper 000's acceleration) and its weight in Fz.
  const PlantConfig nominal = Quiet(NominalPlant(PlantConfig::Default()));
  PlantConfig built = nominal;
  ErrorSet set;
  set.error_seed = 1;
  const DrawnErrors d = DrawAsBuilt(set, &built);
  Plant pn(nominal, 1), pb(built, 1);
  const double m = pn.mass_kg(), g = nominal.body.gravity_m_per_s2;
  Eigen::Matrix<double, 6, 1> want;
  want << 0.9, 0.0, m * g, 0.0, 0.0, 0.0;
  const Eigen::Matrix<double, 6, 8> a = Allocation(pn);
  const Eigen::Matrix<double, 8, 1> i = a.completeOrthogonalDecomposition().solve(want);
  double cur[8];
  for (int j = 0; j < 8; ++j) cur[j] = i[j];
  const hil::Wrench wn = pn.MagneticWrench(pn.body_state(), cur);
  const hil::Wrench wb = pb.MagneticWrench(pb.body_state(), cur);
  // Nominal: no off-axis torque (the allocation is exact).
  CHECK(wn.torque_body_Nm.norm() < 1e-9);
  // As built: the thrust acts at the coils, com_height below the CoM -> a
  // theta_y torque of Fx * h; the weight carried at the coils' centre, c off
  // the CoM -> m g c about x and y. Both within 30 % (roll, b* and yaw add).
  const double h = Value(d, "com_height_m"), cx = Value(d, "com_x_m"), cy = Value(d, "com_y_m");
  const double ty_expected = std::fabs(0.9 * h) + 0.0;
  const double tx_expected = m * g * std::fabs(cy);
  std::printf("\n  as built seed 1: torque %.3g %.3g %.3g N m; expected |Tx| ~ %.3g (m g c_y), "
              "|Ty| ~ m g c_x +- Fx h = %.3g +- %.3g\n",
              wb.torque_body_Nm.x(), wb.torque_body_Nm.y(), wb.torque_body_Nm.z(), tx_expected, m * g * std::fabs(cx),
              ty_expected);
  DOUBLES_EQUAL(tx_expected, std::fabs(wb.torque_body_Nm.x()), 0.3 * tx_expected);
  // Ty = (weight about the offset) and (thrust below the CoM): their sum in
  // magnitude is between | |a| - |b| | and |a| + |b|.
  const double ay = m * g * std::fabs(cx);
  CHECK(std::fabs(wb.torque_body_Nm.y()) >= 0.7 * std::fabs(ay - ty_expected));
  CHECK(std::fabs(wb.torque_body_Nm.y()) <= 1.3 * (ay + ty_expected));
  // Yaw: b* spread and coil yaw make a theta_z torque from pure thrust: at
  // least 1e-5 N m (0.9 N x 1 % x 52 mm ~ 4.7e-4), far above the nominal's.
  CHECK(std::fabs(wb.torque_body_Nm.z()) > 1e-5);
  // And lateral force leaks into y (coil yaw ~1.5 mrad x 0.9 N ~ 1.4 mN).
  CHECK(std::fabs(wb.force_world_N.y()) > 1e-4);
}

TEST(AsBuilt, ComponentNoiseIsFromTheFiguresNotTheFit) {
  const hil::ComponentNoise n = hil::component_noise();
  const double density = hil::component_current_noise_density_A_per_rtHz(n, 0.5);
  // 0.5 A/V x sqrt(60^2 + 100^2 + 10^2) nV/sqrt(Hz) = 58.6 nA/sqrt(Hz).
  DOUBLES_EQUAL(0.5 * std::sqrt(60.0 * 60 + 100 * 100 + 10 * 10) * 1e-9, density, 1e-15);
  const PlantConfig c = NominalPlant(PlantConfig::Default());
  DOUBLES_EQUAL(density, c.amplifier.current_noise_density_A_per_rtHz, 0.0);
  DOUBLES_EQUAL(0.3e-9, c.interferometer.noise_m, 0.0);
  DOUBLES_EQUAL(10e-9, c.displacement.noise_m, 0.0);
  // The fitted density stays the default plant's (docs/BENCH.md).
  DOUBLES_EQUAL(10e-6, PlantConfig::Default().amplifier.current_noise_density_A_per_rtHz, 0.0);
  // Nominal: no hand-set errors.
  for (int j = 0; j < 8; ++j) DOUBLES_EQUAL(0.0, c.amplifier.gain_error[j], 0.0);
  CHECK(!c.as_built.active);
}

// `ideal` on any stage (2026-11-29): the stage's own plant -- its geometry
// and sensors kept -- without imperfections or noise; Ideal() is the same
// for the default PlantConfig. Before, `ideal` was always the default stage's.
TEST(AsBuilt, IdealOfAStageKeepsItsGeometryAndDropsErrorsAndNoise) {
  PlantConfig stage = NominalPlant(PlantConfig::Default());
  stage.body.layout = hil::BodyConfig::Layout::kSquare;
  stage.body.mass_kg = 1.25;
  stage.interferometer.y_beam_x_m[0] = -0.04;
  stage.displacement.sensor_x_m[2] = 0.07;
  // The as-built block as a drawn set leaves it (the part of a draw that
  // moves geometry, e.g. a beam's Abbe offset, is the stage's own place:
  // IdealOf is for a profile's plant, before any draw).
  stage.as_built.active = true;
  stage.as_built.magnet_pitch_error = 3e-4;
  const PlantConfig ideal = PlantConfig::IdealOf(stage);
  CHECK_TRUE(ideal.body.layout == hil::BodyConfig::Layout::kSquare);
  DOUBLES_EQUAL(1.25, ideal.body.mass_kg, 0.0);
  DOUBLES_EQUAL(-0.04, ideal.interferometer.y_beam_x_m[0], 0.0);
  DOUBLES_EQUAL(0.07, ideal.displacement.sensor_x_m[2], 0.0);
  CHECK_FALSE(ideal.as_built.active);
  CHECK_FALSE(ideal.sensor_noise_enabled);
  DOUBLES_EQUAL(0.0, ideal.amplifier.current_noise_scale, 0.0);
  DOUBLES_EQUAL(0.0, ideal.amplifier.monitor_noise_A, 0.0);
  for (int j = 0; j < 8; ++j) {
    DOUBLES_EQUAL(0.0, ideal.amplifier.gain_error[j], 0.0);
    DOUBLES_EQUAL(0.0, ideal.amplifier.offset_A[j], 0.0);
    DOUBLES_EQUAL(0.0, ideal.amplifier.bandwidth_error[j], 0.0);
  }
  for (int f = 0; f < 4; ++f) {
    DOUBLES_EQUAL(0.0, ideal.forcer_errors.misalignment_rad[f], 0.0);
    DOUBLES_EQUAL(0.0, ideal.forcer_errors.epsilon_tangential[f], 0.0);
  }
  // Ideal() = IdealOf of the default-constructed plant = IdealOf(Default()):
  // Default() differs from PlantConfig{} only by the errors IdealOf drops.
  const PlantConfig a = PlantConfig::Ideal(), b = PlantConfig::IdealOf(PlantConfig::Default());
  for (int j = 0; j < 8; ++j) DOUBLES_EQUAL(a.amplifier.gain_error[j], b.amplifier.gain_error[j], 0.0);
  for (int f = 0; f < 4; ++f) DOUBLES_EQUAL(a.forcer_errors.misalignment_rad[f], b.forcer_errors.misalignment_rad[f], 0.0);
  // And the plant behaves alike: the same wrench for the same currents.
  const Plant pa(a, 1), pb(b, 1);
  const Eigen::Matrix<double, 6, 8> da = Allocation(pa) - Allocation(pb);
  DOUBLES_EQUAL(0.0, da.cwiseAbs().maxCoeff(), 0.0);
}
