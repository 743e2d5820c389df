#include "maglev/coupling_calibration/coupling_calibration.hpp"

#include <cmath>
#include <cstdint>

#include "CppUTest/TestHarness.h"

using namespace maglev::kernel;

namespace {

constexpr int kN = kAxisCount;
constexpr double kPi = 3.14159265358979323846;
constexpr double kFs = 2500.0;
// Radii of gyration of the default stage: sqrt(I / m) for Iz, Ix, Iy.
const float kRadius[kN] = {1.0f, 1.0f, 0.0693f, 1.0f, 0.0503f, 0.0503f};

// A known mixing: coil yaw / CoM-offset-like terms, scaled like the real ones
// (translation -> rotation ~ c = 3 mm; rotation -> translation ~ c m / I).
void known_mixing(double m[kN][kN]) {
  const double v[kN][kN] = {
      {1.02, 0.015, 0.30, 0.004, 0.0, 0.10},
      {-0.012, 0.98, -0.25, 0.0, 0.08, 0.0},
      {0.0031, -0.0024, 1.01, 0.0, 0.0, 0.0},
      {0.01, 0.0, 0.0, 0.99, 0.05, -0.04},
      {0.0, 0.0042, 0.0, 0.0028, 1.03, 0.02},
      {-0.0055, 0.0, 0.0, -0.0021, 0.015, 0.97},
  };
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) m[i][j] = v[i][j];
}

struct C64 {
  double re, im;
};
C64 cmul(C64 a, C64 b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }

// Each axis' own dynamics at w: gain / (k - m w^2 + j c w) with the common
// 1.5-tick delay (mass-like x, y, theta_z; suspended z, theta_x, theta_y).
C64 axis_dynamics(int a, double w) {
  const double mass[kN] = {0.75, 0.75, 0.0036, 0.75, 0.0019, 0.0019};
  const double k[kN] = {0.0, 0.0, 0.0, 94600.0, 128.2, 128.2};
  const double c[kN] = {0.0, 0.0, 0.0, 890.0, 1.207, 1.207};
  const double re = k[a] - mass[a] * w * w, im = c[a] * w;
  const double d = re * re + im * im;
  const C64 p{1.7 * re / d, -1.7 * im / d};
  const double ph = -w * 1.5 / kFs;
  return cmul(p, {std::cos(ph), std::sin(ph)});
}

// Runs the six experiments through accumulate() tick by tick.
void identify(const double m[kN][kN], float r[kCouplingMatrixSize], float* coupling, float* spread,
              CouplingCalibrationResult* res) {
  static CouplingIdentifier id;
  id.reset();
  const double f0 = 20.0;
  const auto inc = static_cast<std::uint32_t>(std::llround(f0 / kFs * 4294967296.0));
  const int window = 40 * 125;  // 40 periods of 20 Hz
  for (int j = 0; j < kN; ++j) {
    // Line amplitudes/phases of U: the excited axis j large, the others
    // (the loops' reactions) smaller and with their own phases.
    C64 u[kCouplingLines][kN];
    C64 y[kCouplingLines][kN];
    for (int k = 0; k < kCouplingLines; ++k) {
      for (int a = 0; a < kN; ++a) {
        const double amp = a == j ? 0.1 : 0.02 * (1 + ((a + 2 * j + k) % 3));
        const double ph = 0.7 * a + 1.3 * j + 0.4 * k;
        u[k][a] = {amp * std::cos(ph), amp * std::sin(ph)};
      }
      const double w = 2 * kPi * f0 * (k + 1);
      for (int i = 0; i < kN; ++i) {
        C64 f{0, 0};
        for (int a = 0; a < kN; ++a) {
          f.re += m[i][a] * u[k][a].re;
          f.im += m[i][a] * u[k][a].im;
        }
        y[k][i] = cmul(axis_dynamics(i, w), f);
      }
    }
    std::uint32_t phase = 0;
    for (int n = 0; n < window; ++n) {
      float uf[kN], yf[kN];
      for (int a = 0; a < kN; ++a) {
        double us = 0.0, ys = 0.0;
        for (int k = 0; k < kCouplingLines; ++k) {
          const double th = 2 * kPi * f0 * (k + 1) * n / kFs;
          us += u[k][a].re * std::cos(th) - u[k][a].im * std::sin(th);
          ys += y[k][a].re * std::cos(th) - y[k][a].im * std::sin(th);
        }
        uf[a] = static_cast<float>(us + 0.3);  // a DC offset (the gravity lift, integrators): not at the lines
        yf[a] = static_cast<float>(ys);
      }
      id.accumulate(phase, uf, yf);
      phase += inc;
    }
    id.finish_experiment(j);
  }
  *res = id.solve(kRadius, r, coupling, spread);
}

}  // namespace

TEST_GROUP(CouplingCalibration){};

TEST(CouplingCalibration, GaussJordanInvertsAKnownMatrixWithPivoting) {
  // Zero on the first pivot: needs the row swap.
  float a[9] = {0, 2, 1, 1, 1, 0, 3, 0, 1};
  const float orig[9] = {0, 2, 1, 1, 1, 0, 3, 0, 1};
  CHECK_TRUE(invert_matrix(a, 3));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      float s = 0;
      for (int k = 0; k < 3; ++k) s += orig[i * 3 + k] * a[k * 3 + j];
      DOUBLES_EQUAL(i == j ? 1.0 : 0.0, s, 1e-6);
    }
  float sing[4] = {1, 2, 2, 4};
  CHECK_FALSE(invert_matrix(sing, 2));
}

TEST(CouplingCalibration, IdentifiesAKnownMixingThroughEachAxisOwnDynamics) {
  double m[kN][kN];
  known_mixing(m);
  float r[kCouplingMatrixSize];
  float coupling = 0, spread = 0;
  CouplingCalibrationResult res{};
  identify(m, r, &coupling, &spread, &res);
  CHECK_EQUAL(static_cast<int>(CouplingCalibrationResult::kPassed), static_cast<int>(res));
  // R = diag(M)^-1 M, whatever mass, spring, damper and delay each axis has.
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      const double want = m[i][j] / m[i][i];
      DOUBLES_EQUAL(want, r[i * kN + j], 2e-4 * (1.0 + std::fabs(want)));
    }
  CHECK(spread < 1e-3f);
  // The scaled coupling: largest is theta_y <- x, 0.0055 / 0.97 / 0.0503 (a
  // 5.5 mm lever over theta_y's 50 mm radius of gyration).
  DOUBLES_EQUAL(0.0055 / 0.97 / 0.0503, coupling, 1e-3);

  // The correction C = R^-1 decouples: M C = diag(M) (each axis keeps its gain).
  const float identity[kCouplingMatrixSize] = {1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0,
                                               0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1};
  float c[kCouplingMatrixSize];
  CHECK_EQUAL(static_cast<int>(CouplingCalibrationResult::kPassed),
              static_cast<int>(correction_from(r, identity, kRadius, CouplingCalibrationConfig{}, c)));
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      double s = 0;
      for (int k = 0; k < kN; ++k) s += m[i][k] * static_cast<double>(c[k * kN + j]);
      DOUBLES_EQUAL(i == j ? m[i][i] : 0.0, s, 5e-4);
    }

  // Identifying the corrected plant M C finds no coupling left.
  double mc[kN][kN];
  for (int i = 0; i < kN; ++i)
    for (int j = 0; j < kN; ++j) {
      double s = 0;
      for (int k = 0; k < kN; ++k) s += m[i][k] * static_cast<double>(c[k * kN + j]);
      mc[i][j] = s;
    }
  float r2[kCouplingMatrixSize];
  float coupling2 = 1;
  identify(mc, r2, &coupling2, &spread, &res);
  CHECK(coupling2 < 0.01f * coupling);
}

TEST(CouplingCalibration, RefusesACorrectionBeyondItsBoundAndAnInvalidStoredOne) {
  float r[kCouplingMatrixSize] = {};
  for (int i = 0; i < kN; ++i) r[i * kN + i] = 1.0f;
  r[0 * kN + 1] = 0.8f;  // 80 % y -> x: not a tolerance, the check refuses it
  const float identity[kCouplingMatrixSize] = {1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0,
                                               0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1};
  float c[kCouplingMatrixSize] = {};
  c[0] = 42.0f;
  CHECK_EQUAL(static_cast<int>(CouplingCalibrationResult::kFailedCorrectionTooLarge),
              static_cast<int>(correction_from(r, identity, kRadius, CouplingCalibrationConfig{}, c)));
  CHECK_EQUAL(42.0f, c[0]);  // untouched
  r[0 * kN + 1] = 1.0f;
  r[1 * kN + 0] = 1.0f;  // rows 0 and 1 equal: singular
  CHECK_EQUAL(static_cast<int>(CouplingCalibrationResult::kFailedSingular),
              static_cast<int>(correction_from(r, identity, kRadius, CouplingCalibrationConfig{}, c)));

  CouplingCorrection ok;
  CHECK_TRUE(correction_valid(ok, kRadius));
  CouplingCorrection bad = ok;
  bad.matrix[1] = NAN;
  CHECK_FALSE(correction_valid(bad, kRadius));
  bad = ok;
  bad.matrix[1] = 1.5f;
  CHECK_FALSE(correction_valid(bad, kRadius));
  bad = ok;
  bad.reserved[0] = 1;
  CHECK_FALSE(correction_valid(bad, kRadius));
}
