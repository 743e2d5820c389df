// Force laws (1)-(4) against values computed independently (numpy, straight
// from the printed equations with sigma_m = H_c, k_w1 = 1, mu_rec = 1.05).
#include <cmath>

#include "maglev/pmlsm_plant/force_law.hpp"

// CppUTest last: its leak-detection macros redefine new.
#include <CppUTest/TestHarness.h>

using namespace maglev::pmlsm_plant;

TEST_GROUP(ForceLaw) {
  MotorParams m;
  ForceConstants k = ComputeForceConstants(m);
};

TEST(ForceLaw, ConstantsMatchHandComputation) {
  // K_v1 = L_A p_m tau / (4 mu0) = 0.05 * 4 * 0.05715 / (4 * 4e-7 pi).
  DOUBLES_EQUAL(2273.93, k.Kv1, 0.01);
  DOUBLES_EQUAL(84.8528, k.Kv2, 1e-4);            // 3 sqrt2 L_A p_m W / p^2
  DOUBLES_EQUAL(0.05 * 7.12424, k.Kv3, 1e-5);     // printed K_v3 times kv3_scale
  DOUBLES_EQUAL(70.1806, k.Kh, 1e-4);
}

TEST(ForceLaw, GapFunctionsAt25mm) {
  const double g = 25e-3;
  DOUBLES_EQUAL(0.0406415442, Gamma1(m, g), 1e-9);
  DOUBLES_EQUAL(1.0563402895, CarterFactor_Kc(m, g), 1e-9);
  DOUBLES_EQUAL(0.9413859036, Lambda(m, g), 1e-9);
  DOUBLES_EQUAL(0.1100528308, PmField_B_T(m, g), 1e-9);
  DOUBLES_EQUAL(25.9266557848, k.Kv1 * Lv1(m, g), 1e-6);   // PM attraction [N]
  DOUBLES_EQUAL(8.9606194058, k.Kv2 * Lv2(m, g), 1e-6);    // N per A of i_d
  DOUBLES_EQUAL(0.05 * 6.9680631704, k.Kv3 * Lv3(m, g), 1e-7);
  DOUBLES_EQUAL(24.9662070201, k.Kh * Lh(m, g), 1e-6);     // N per A of i_q
}

TEST(ForceLaw, MotorForceCombinesTerms) {
  const double g = 20e-3;
  const MotorForce f = ComputeMotorForce(m, k, g, 2.0, -1.5);
  const double expect_v = -47.0849774563 + 12.5117046763 * 2.0 - 0.05 * 7.4805429528 * (4.0 + 2.25);
  DOUBLES_EQUAL(expect_v, f.vertical_N, 1e-6);
  DOUBLES_EQUAL(-33.0182440451 * -1.5, f.horizontal_N, 1e-6);
}

TEST(ForceLaw, AttractionFallsWithGap) {
  double prev = 1e9;
  for (double g = 18e-3; g <= 31e-3; g += 1e-3) {
    const double a = k.Kv1 * Lv1(m, g);
    CHECK(a < prev);
    prev = a;
  }
}

TEST(ForceLaw, HoverCurrentAtNominalGaps) {
  const double weight_per_motor = 6.9 * 9.81 / 4.0;
  double i = 0;
  CHECK(HoverDirectCurrent_A(m, k, 20e-3, weight_per_motor, &i));
  DOUBLES_EQUAL(2.6152180, i, 1e-6);
  CHECK(HoverDirectCurrent_A(m, k, 25e-3, weight_per_motor, &i));
  DOUBLES_EQUAL(1.0475540, i, 1e-6);
  CHECK(HoverDirectCurrent_A(m, k, 30e-3, weight_per_motor, &i));
  DOUBLES_EQUAL(-0.3458964, i, 1e-6);
  // The force law at that current carries the weight exactly.
  CHECK(HoverDirectCurrent_A(m, k, 25e-3, weight_per_motor, &i));
  DOUBLES_EQUAL(-weight_per_motor, ComputeMotorForce(m, k, 25e-3, i, 0.0).vertical_N, 1e-9);
}

TEST(ForceLaw, PrintedKv3HasNoEquilibriumAtSmallGaps) {
  // Why kv3_scale exists: with K_v3 as printed, no i_d holds the weight at 20 mm.
  MotorParams printed;
  printed.kv3_scale = 1.0;
  const ForceConstants kp = ComputeForceConstants(printed);
  double i = 0;
  CHECK_FALSE(HoverDirectCurrent_A(printed, kp, 20e-3, 6.9 * 9.81 / 4.0, &i));
  CHECK(HoverDirectCurrent_A(printed, kp, 30e-3, 6.9 * 9.81 / 4.0, &i));
}
