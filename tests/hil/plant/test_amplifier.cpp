// Amplifiers: DAC scaling, first-order current loop, Table 1 noise, limits, enable.
#include <cmath>
#include <cstdio>

#include "maglev/plant/plant.hpp"

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

TEST(PlantAmplifier, Table1Interpolation) {
  // Interpolation points reproduce paper 003 Table 1.
  DOUBLES_EQUAL(4.79e-3, maglev::hil::Table1CurrentNoiseStd_A(0.0), 1e-12);
  DOUBLES_EQUAL(7.09e-3, maglev::hil::Table1CurrentNoiseStd_A(0.2134), 1e-12);
  DOUBLES_EQUAL((5.60 + 7.09) / 2 * 1e-3, maglev::hil::Table1CurrentNoiseStd_A((0.10774 + 0.2134) / 2), 1e-12);
}

namespace {
struct NoiseStats {
  double force_std_A;    // true coil current about the nominal
  double force_mean_A;
  double monitor_std_A;  // monitored current (ADC codes) about the nominal
};
NoiseStats MeasureNoise(const PlantConfig& c, std::int16_t code, int coil) {
  Plant plant(c, 42);
  const auto cmd = AllCoils(code, true);
  const double nominal = 0.5 * code * 10.0 / 32768.0;
  double sum = 0, sum2 = 0, msum = 0, msum2 = 0;
  const int n = 8000;  // 0.8 % sampling error on a std
  for (int k = 0; k < n; ++k) {
    const maglev::io::SensorSample s = plant.sample();
    const double monitored = s.coil_current_adc[coil] * (10.0 / 32768.0) / c.amplifier.monitor_gain_V_per_A;
    plant.apply(cmd);
    plant.advance_tick();
    if (k < 10) continue;  // settle
    const double e = plant.truth().coil_current_A[coil] - nominal;
    sum += e;
    sum2 += e * e;
    msum += monitored - nominal;
    msum2 += (monitored - nominal) * (monitored - nominal);
  }
  const double m = n - 10;
  return {std::sqrt(sum2 / m - (sum / m) * (sum / m)), sum / m, std::sqrt(msum2 / m - (msum / m) * (msum / m))};
}
}  // namespace

TEST(PlantAmplifier, ForceNoiseIsTheIdentifiedInBandDensity) {
  // Default noise model: white additive force noise, 10 uA/sqrt(Hz) over the
  // 1250 Hz band of per-tick samples = 0.354 mA per tick, at any current.
  PlantConfig c = Floating();
  const PlantConfig d = PlantConfig::Default();
  c.amplifier.current_noise_density_A_per_rtHz = d.amplifier.current_noise_density_A_per_rtHz;
  c.amplifier.current_noise_scale = 1.0;
  DOUBLES_EQUAL(10e-6, d.amplifier.current_noise_density_A_per_rtHz, 1e-15);
  const double expected = 10e-6 * std::sqrt(1250.0);
  DOUBLES_EQUAL(expected, maglev::hil::ForceNoiseStd_A(c.amplifier), 1e-12);
  for (const std::int16_t code : {std::int16_t{0}, std::int16_t{1399}, std::int16_t{14000}}) {  // 0, 213 mA, 2.14 A
    const NoiseStats st = MeasureNoise(c, code, 4);
    std::printf("\n  force noise at %.3f A: %.4f mA (expected %.4f), mean %.4f mA", 0.5 * code * 10.0 / 32768.0,
                st.force_std_A * 1e3, expected * 1e3, st.force_mean_A * 1e3);
    DOUBLES_EQUAL(expected, st.force_std_A, 0.04 * expected);
    CHECK(std::fabs(st.force_mean_A) < 0.02e-3);
  }
}

TEST(PlantAmplifier, MonitorChannelReproducesTable1) {
  // The reported (monitored) current's std about the command is Table 1's
  // measured std: force noise + the monitor chain's own noise.
  PlantConfig c = Floating();
  c.sensor_noise_enabled = true;
  c.interferometer.noise_m = 0.0;
  c.amplifier.current_noise_density_A_per_rtHz = 12e-6;
  c.amplifier.current_noise_scale = 1.0;
  c.amplifier.monitor_reproduces_table1 = true;
  const double table_mA[3] = {4.82, 7.09, 10.93};
  const std::int16_t codes[3] = {83, 1399, 2784};  // 12.7, 213.5, 424.8 mA
  for (int k = 0; k < 3; ++k) {
    const NoiseStats st = MeasureNoise(c, codes[k], 2);
    std::printf("\n  monitored std at %.1f mA: %.3f mA (Table 1: %.2f)", 0.5 * codes[k] * 10.0 / 32768.0 * 1e3,
                st.monitor_std_A * 1e3, table_mA[k]);
    DOUBLES_EQUAL(table_mA[k] * 1e-3, st.monitor_std_A, 0.04 * table_mA[k] * 1e-3);
  }
}

// Issue 16 (integrator `fast`): RkCurrent's stage currents make RK4's two
// quadratures of the current exact for the closed-form transient, the pose
// held: (i0 + 4 i_mid + i_end) / 6 = mean of i over the step, and
// (i0 + 2 i_mid) / 6 = int (h - t) i dt / h^2. Checked against a fine
// midpoint-rule integration of i(t) = it + (i0 - it) exp(-w t), for the
// 400 us tick (w h = 12.6), the 200 us sub-step and a short step (w h = 0.06).
TEST(PlantAmplifier, RkStageCurrentsIntegrateTheTransientExactly) {
  maglev::hil::AmplifierConfig ac = PlantConfig::Ideal().amplifier;
  const double omega = ac.loop_transresistance_V_per_A / ac.coil_inductance_H;
  for (const double h : {400e-6, 200e-6, 2e-6}) {
    maglev::hil::Amplifiers amps(ac);
    amps.set_current(2, -0.7);
    amps.Apply(AllCoils(6554, true), nullptr, false);  // target 1.0000 A
    amps.BeginSubstep(h, true);
    const double i0 = amps.RkCurrent(2, 0), im = amps.RkCurrent(2, 1), ie = amps.RkCurrent(2, 2);
    const double it = amps.target_A(2);
    DOUBLES_EQUAL(-0.7, i0, 0.0);
    constexpr int kN = 200000;
    double mean = 0.0, moment = 0.0;
    for (int n = 0; n < kN; ++n) {
      const double t = (n + 0.5) * h / kN;
      const double i = it + (i0 - it) * std::exp(-omega * t);
      mean += i / kN;
      moment += (h - t) * i * (h / kN) / (h * h);
    }
    DOUBLES_EQUAL(mean, (i0 + 4.0 * im + ie) / 6.0, 1e-9);
    DOUBLES_EQUAL(moment, (i0 + 2.0 * im) / 6.0, 1e-9);
    // Without exact_quadrature: the physical samples at 0, h/2, h.
    amps.BeginSubstep(h, false);
    DOUBLES_EQUAL(amps.CurrentAt(2, 1), amps.RkCurrent(2, 1), 0.0);
    DOUBLES_EQUAL(amps.CurrentAt(2, 2), amps.RkCurrent(2, 2), 0.0);
  }
}
