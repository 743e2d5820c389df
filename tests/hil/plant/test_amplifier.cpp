// Amplifiers: DAC scaling, first-order current loop, Table 1 noise, limits, enable.
#include <cmath>
#include <cstdio>

#include "maglev/hil/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace stage = maglev::io::stage;

TEST_GROUP(PlantAmplifier){};

namespace {
maglev::io::ActuatorCommand AllCoils(std::int16_t code, bool enable) {
  maglev::io::ActuatorCommand c{};
  for (auto& d : c.dac_code) d = code;
  c.amplifier_enable = enable;
  return c;
}
PlantConfig Floating() {
  PlantConfig c = PlantConfig::Ideal();
  c.body.gravity_enabled = false;  // keep the platen still while coils carry current
  c.contact.enabled = false;
  return c;
}
}  // namespace

TEST(PlantAmplifier, DacCodesScaleToCurrent) {
  CHECK_EQUAL(-10.0, maglev::hil::DacCodeToVolts(-32768, 10.0));
  DOUBLES_EQUAL(10.0 * 32767.0 / 32768.0, maglev::hil::DacCodeToVolts(32767, 10.0), 1e-15);
  Plant plant(Floating(), 1);
  plant.apply(AllCoils(16384, true));  // 5 V -> 2.5 A
  plant.advance(1e-3);
  DOUBLES_EQUAL(2.5, plant.truth().coil_current_A[0], 1e-9);
  // One DAC LSB is a physical 0.1526 mA step.
  plant.apply(AllCoils(16385, true));
  plant.advance(1e-3);
  DOUBLES_EQUAL(2.5 + 0.5 * 10.0 / 32768.0, plant.truth().coil_current_A[3], 1e-9);
}

TEST(PlantAmplifier, FirstOrderCurrentLoopBandwidth) {
  Plant plant(Floating(), 1);
  const double bw = plant.amplifiers().bandwidth_Hz();
  std::printf("\n  current-loop bandwidth %.1f Hz (K = %.4f V/A, L = %.0f uH)\n", bw,
              plant.config().amplifier.loop_transresistance_V_per_A, stage::kCoilInductance_H * 1e6);
  DOUBLES_EQUAL(5000.0, bw, 1.0);
  plant.apply(AllCoils(6554, true));  // 1.0000 A
  const double target = 0.5 * 6554 * 10.0 / 32768.0;
  const double tau = 1.0 / (2 * stage::kPi * bw);
  plant.advance(tau);
  DOUBLES_EQUAL(target * (1 - std::exp(-1.0)), plant.truth().coil_current_A[5], 1e-9);
  plant.advance(4 * tau);
  DOUBLES_EQUAL(target * (1 - std::exp(-5.0)), plant.truth().coil_current_A[5], 1e-9);
}

TEST(PlantAmplifier, VoltageSaturationLimitsSlewRate) {
  PlantConfig c = Floating();
  c.amplifier.supply_voltage_V = 2.0;
  c.amplifier.output_dropout_V = 0.0;
  Plant plant(c, 1);
  plant.apply(AllCoils(26214, true));  // 4 A: needs K*4 = 7.4 V > 2 V
  plant.advance(20e-6);
  const double r = stage::kCoilResistance_Ohm, l = stage::kCoilInductance_H;
  DOUBLES_EQUAL(2.0 / r * (1 - std::exp(-r / l * 20e-6)), plant.truth().coil_current_A[0], 1e-9);
}

TEST(PlantAmplifier, CurrentLimitAndEnable) {
  PlantConfig c = Floating();
  c.amplifier.gain_error[2] = 0.10;
  Plant plant(c, 1);
  plant.apply(AllCoils(32767, true));
  plant.advance(1e-3);
  DOUBLES_EQUAL(5.0, plant.truth().coil_current_A[2], 1e-9);  // clipped at the limit
  DOUBLES_EQUAL(0.5 * 32767 * 10.0 / 32768.0, plant.truth().coil_current_A[0], 1e-9);
  plant.apply(AllCoils(32767, false));
  plant.advance(1e-3);
  for (double i : plant.truth().coil_current_A) DOUBLES_EQUAL(0.0, i, 1e-9);
}

TEST(PlantAmplifier, GainAndOffsetErrors) {
  PlantConfig c = Floating();
  c.amplifier.gain_error[1] = -0.01;
  c.amplifier.offset_A[1] = 0.003;
  Plant plant(c, 1);
  plant.apply(AllCoils(13107, true));  // 2.0 A nominal
  plant.advance(1e-3);
  const double nominal = 0.5 * 13107 * 10.0 / 32768.0;
  DOUBLES_EQUAL(nominal * 0.99 + 0.003, plant.truth().coil_current_A[1], 1e-9);
}

TEST(PlantAmplifier, NoiseFollowsPaper003Table1) {
  // Interpolation points reproduce Table 1.
  DOUBLES_EQUAL(4.79e-3, maglev::hil::Table1CurrentNoiseStd_A(0.0), 1e-12);
  DOUBLES_EQUAL(7.09e-3, maglev::hil::Table1CurrentNoiseStd_A(0.2134), 1e-12);
  DOUBLES_EQUAL((5.60 + 7.09) / 2 * 1e-3, maglev::hil::Table1CurrentNoiseStd_A((0.10774 + 0.2134) / 2), 1e-12);
  // Measured through the plant, scale 1: per-tick ZOH noise settled by the loop.
  PlantConfig c = Floating();
  c.amplifier.current_noise_scale = 1.0;
  Plant plant(c, 42);
  const auto cmd = AllCoils(1399, true);  // 213.5 mA
  const double nominal = 0.5 * 1399 * 10.0 / 32768.0;
  double sum = 0, sum2 = 0;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    plant.apply(cmd);
    plant.advance_tick();
    const double e = plant.truth().coil_current_A[4] - nominal;
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n;
  const double std = std::sqrt(sum2 / n - mean * mean);
  std::printf("\n  current error at 213.4 mA: std %.3f mA (Table 1: 7.09), mean %.3f mA\n", std * 1e3, mean * 1e3);
  DOUBLES_EQUAL(7.09e-3, std, 0.04 * 7.09e-3);
  CHECK(std::fabs(mean) < 0.2e-3);
}
