// Sensors: wrapping interferometer counters, beam loss, ADC quantization,
// displacement range bit, Hall channels from the same field model.
#include <cmath>
#include <cstdio>

#include "maglev/plant/plant.hpp"

// CppUTest last: its leak-checking operator new macros break STL headers.
#include <CppUTest/TestHarness.h>

using maglev::hil::BodyState;
using maglev::hil::Plant;
using maglev::hil::PlantConfig;
namespace io = maglev::io;
namespace stage = maglev::io::stage;

TEST_GROUP(PlantSensors){};

namespace {
PlantConfig Still() {
  PlantConfig c = PlantConfig::Ideal();
  c.body.gravity_enabled = false;
  c.suspension.enabled = false;
  c.contact.enabled = false;
  return c;
}
BodyState Pose(double x, double y, double z, double thx, double thy, double thz) {
  BodyState s;
  s.position_m = {x, y, z};
  s.attitude = Eigen::Quaterniond(Plant::RotationFromAngles(thx, thy, thz));
  return s;
}
std::int32_t Delta(std::uint32_t now, std::uint32_t start) { return static_cast<std::int32_t>(now - start); }
}  // namespace

TEST(PlantSensors, InterferometerCountersWrap) {
  const PlantConfig c = Still();
  Plant plant(c, 1);
  const double lsb = stage::kInterferometerLsb_m;
  io::SensorSample s = plant.sample();
  CHECK_EQUAL(c.interferometer.start_count[0], s.interferometer_counts[0]);
  // +1 um in x crosses the unsigned wrap of axis 0 (starts 256 counts below it).
  plant.set_body_state(Pose(1e-6, 0, 0, 0, 0, 0));
  s = plant.sample();
  CHECK(s.interferometer_counts[0] < 2000u);  // wrapped past 0xffffffff
  CHECK_EQUAL(static_cast<std::int32_t>(std::floor(1e-6 / lsb)), Delta(s.interferometer_counts[0], c.interferometer.start_count[0]));
  // -1 um in y crosses the signed boundary of axis 1 the other way: fine for a uint32 counter.
  plant.set_body_state(Pose(0, -1e-6, 0, 0, 0, 0));
  s = plant.sample();
  CHECK_EQUAL(static_cast<std::int32_t>(std::floor(-1e-6 / lsb)), Delta(s.interferometer_counts[1], c.interferometer.start_count[1]));
  CHECK_EQUAL(static_cast<std::int32_t>(std::floor(-1e-6 / lsb)), Delta(s.interferometer_counts[2], c.interferometer.start_count[2]));
}

TEST(PlantSensors, BeamLayoutAbbeAndCosineTerms) {
  const PlantConfig c = Still();
  Plant plant(c, 1);
  const double thz = 20e-6, x = 3e-3, y = -2e-3, d = c.interferometer.mirror_distance_m;
  plant.set_body_state(Pose(x, y, 0, 0, 0, thz));
  const io::SensorSample s = plant.sample();
  const double lsb = stage::kInterferometerLsb_m;
  // sensors_to_pose's beam model: x + y thz + d thz^2/2 ; y + (x_b - x) thz + d thz^2/2
  const double mx = x + y * thz + d * thz * thz / 2;
  const double my1 = y + (-0.05 - x) * thz + d * thz * thz / 2;
  const double my2 = y + (0.05 - x) * thz + d * thz * thz / 2;
  LONGS_EQUAL(static_cast<long>(std::floor(mx / lsb)), Delta(s.interferometer_counts[0], c.interferometer.start_count[0]));
  LONGS_EQUAL(static_cast<long>(std::floor(my1 / lsb)), Delta(s.interferometer_counts[1], c.interferometer.start_count[1]));
  LONGS_EQUAL(static_cast<long>(std::floor(my2 / lsb)), Delta(s.interferometer_counts[2], c.interferometer.start_count[2]));
}

TEST(PlantSensors, BeamLossSetsBitAndFreezesCounter) {
  PlantConfig c = Still();
  c.interferometer.beam_loss_events.push_back({1, 0.010, 0.020});
  Plant plant(c, 1);
  BodyState s = Pose(0, 0, 0, 0, 0, 0);
  s.velocity_m_per_s = {0.0, 1e-3, 0.0};  // 1 mm/s in y: 400 nm per tick
  plant.set_body_state(s);
  std::uint32_t frozen = 0;
  std::uint32_t after_loss = 0;
  bool saw_loss = false;
  for (int k = 0; k < 75; ++k) {
    const io::SensorSample smp = plant.sample();
    const double t = plant.truth().time_s;
    const bool lost = (smp.status_flags & io::kBeamLoss1) != 0;
    CHECK_EQUAL(t >= 0.010 && t < 0.020, lost);
    CHECK((smp.status_flags & (io::kBeamLoss0 | io::kBeamLoss2)) == 0);
    if (lost) {
      if (!saw_loss) frozen = smp.interferometer_counts[1];
      CHECK_EQUAL(frozen, smp.interferometer_counts[1]);
      saw_loss = true;
    } else if (saw_loss && after_loss == 0) {
      after_loss = smp.interferometer_counts[1];
      // Resumes from the frozen value (the 10 ms of motion is not counted).
      CHECK(std::abs(Delta(after_loss, frozen)) <= 1);
    }
    plant.advance_tick();
  }
  CHECK(saw_loss);
  CHECK(after_loss != 0);
}

TEST(PlantSensors, DisplacementAdcQuantizationAndRange) {
  const PlantConfig c = Still();
  Plant plant(c, 1);
  io::SensorSample s = plant.sample();
  // z = 0: (0 - 100 um) / 20 um/V = -5 V -> code -16384 exactly.
  for (int i = 0; i < 3; ++i) CHECK_EQUAL(-16384, s.displacement_adc[i]);
  // 10 um up, tilted: each sensor reads its own corner height, quantized to 6.1 nm.
  const double z = 10e-6, thx = 50e-6, thy = -30e-6;
  plant.set_body_state(Pose(0, 0, z, thx, thy, 0));
  s = plant.sample();
  for (int i = 0; i < 3; ++i) {
    const double px = stage::kDisplacementSensorX_m[i], py = stage::kDisplacementSensorY_m[i];
    const Eigen::Vector3d w = Plant::RotationFromAngles(thx, thy, 0) * Eigen::Vector3d(px, py, 0);
    const double h = z + w.z();
    const double v = (h - stage::kDisplacementZeroHeight_m) / stage::kDisplacementScale_m_per_V;
    CHECK_EQUAL(static_cast<int>(std::nearbyint(v * 3276.8)), s.displacement_adc[i]);
  }
  CHECK((s.status_flags & (io::kDisplacementOutOfRange0 | io::kDisplacementOutOfRange1 | io::kDisplacementOutOfRange2)) == 0);
  // 350 um: beyond +200 um about 100 um -> out of range, code at the rail.
  plant.set_body_state(Pose(0, 0, 350e-6, 0, 0, 0));
  s = plant.sample();
  CHECK_EQUAL(32767, s.displacement_adc[0]);
  CHECK((s.status_flags & io::kDisplacementOutOfRange0) != 0);
  CHECK((s.status_flags & io::kDisplacementOutOfRange2) != 0);
}

TEST(PlantSensors, HallChannelsGiveTheMagnetPhase) {
  PlantConfig c = Still();
  c.field.harmonics = 1;  // pure fundamental: atan2 is exact up to quantization
  Plant plant(c, 1);
  const double g = stage::kGamma1_per_m;
  for (double x : {0.0, 0.0071, -0.0133, 0.0301}) {
    const double y = -0.6 * x + 0.002;
    plant.set_body_state(Pose(x, y, 0, 0, 0, 0));
    const io::SensorSample s = plant.sample();
    const double phase_x = std::atan2(s.hall_adc[0], s.hall_adc[2]);
    const double phase_y = std::atan2(s.hall_adc[1], s.hall_adc[3]);
    const auto wrap = [](double a) { return std::remainder(a, 2 * stage::kPi); };
    DOUBLES_EQUAL(0.0, wrap(phase_x - g * (x + stage::kHallAX_m)), 2e-4);
    DOUBLES_EQUAL(0.0, wrap(phase_y - g * (y + stage::kHallAY_m)), 2e-4);
    const double amp = std::hypot(s.hall_adc[0], s.hall_adc[2]);
    const double expected = plant.field().C1(stage::kHallHeightAboveMagnets_m) * stage::kHallSensitivity_V_per_T * 3276.8;
    DOUBLES_EQUAL(expected, amp, 2.0);
  }
}

TEST(PlantSensors, CurrentMonitorCodes) {
  PlantConfig c = Still();
  Plant plant(c, 1);
  plant.set_coil_currents({1.5, -0.25, 0, 0, 0, 0, 0, 4.0});
  const io::SensorSample s = plant.sample();
  CHECK_EQUAL(static_cast<int>(std::nearbyint(3.0 * 3276.8)), s.coil_current_adc[0]);
  CHECK_EQUAL(static_cast<int>(std::nearbyint(-0.5 * 3276.8)), s.coil_current_adc[1]);
  CHECK_EQUAL(26214, s.coil_current_adc[7]);
}

TEST(PlantSensors, NoiseIsDeterministicGivenTheSeed) {
  const PlantConfig c = PlantConfig::Default();
  Plant a(c, 99), b(c, 99), d(c, 100);
  bool any_diff = false;
  double sum2 = 0.0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const io::SensorSample sa = a.sample(), sb = b.sample(), sd = d.sample();
    for (int i = 0; i < 3; ++i) CHECK_EQUAL(sa.interferometer_counts[i], sb.interferometer_counts[i]);
    for (int i = 0; i < 4; ++i) CHECK_EQUAL(sa.hall_adc[i], sb.hall_adc[i]);
    any_diff = any_diff || sa.interferometer_counts[0] != sd.interferometer_counts[0];
    const double e = Delta(sa.interferometer_counts[0], c.interferometer.start_count[0]) * stage::kInterferometerLsb_m;
    sum2 += e * e;
  }
  CHECK(any_diff);
  // rms of the x reading at rest: white noise (0.5 nm) + counter quantization.
  const double rms = std::sqrt(sum2 / n);
  std::printf("\n  interferometer x reading at rest: rms %.3f nm\n", rms * 1e9);
  CHECK(rms > 0.3e-9 && rms < 1.0e-9);
}

// Each sensor draws its own figure (a lab's profile may mix parts: its
// interferometers' and heights' `noise`, sensor by sensor): beam 1 at 5 nm
// beside beams 0 and 2 at 0.5 nm, height 2 at 50 nm beside 0 and 1 at 5 nm.
// One figure for the kind (set_noise_m) is every sensor's again.
TEST(PlantSensors, EachSensorDrawsItsOwnNoiseFigure) {
  PlantConfig c = Still();
  c.sensor_noise_enabled = true;
  c.interferometer.set_noise_m(0.5e-9);
  c.interferometer.sensor_noise_m[1] = 5e-9;
  c.displacement.set_noise_m(5e-9);
  c.displacement.sensor_noise_m[2] = 50e-9;
  const auto rms = [](const PlantConfig& cfg, double* beam, double* height) {
    Plant plant(cfg, 7);
    const io::SensorSample s0 = plant.sample();
    double b2[3] = {}, h1[3] = {}, h2[3] = {};
    const int n = 4000;
    for (int k = 0; k < n; ++k) {
      const io::SensorSample s = plant.sample();
      for (int i = 0; i < 3; ++i) {
        const double e = Delta(s.interferometer_counts[i], cfg.interferometer.start_count[i]) * stage::kInterferometerLsb_m;
        b2[i] += e * e;
        const double h = (s.displacement_adc[i] - s0.displacement_adc[i]);
        h1[i] += h;
        h2[i] += h * h;
      }
    }
    for (int i = 0; i < 3; ++i) {
      beam[i] = std::sqrt(b2[i] / n);
      height[i] = std::sqrt(h2[i] / n - (h1[i] / n) * (h1[i] / n));  // ADC codes
    }
  };
  double beam[3], height[3];
  rms(c, beam, height);
  std::printf("\n  per-sensor noise: beams %.2f %.2f %.2f nm, heights %.2f %.2f %.2f codes\n", beam[0] * 1e9,
              beam[1] * 1e9, beam[2] * 1e9, height[0], height[1], height[2]);
  CHECK(beam[0] < 1.0e-9 && beam[2] < 1.0e-9);
  CHECK(beam[1] > 4.5e-9 && beam[1] < 5.5e-9);
  CHECK(height[2] > 8.0 * height[0] && height[2] > 8.0 * height[1]);  // 10x the rms (codes: 2.5 and 25 nominal)
  c.interferometer.set_noise_m(0.5e-9);
  c.displacement.set_noise_m(5e-9);
  rms(c, beam, height);
  CHECK(beam[1] < 1.0e-9);
  CHECK(height[2] < 1.5 * height[0]);
}
