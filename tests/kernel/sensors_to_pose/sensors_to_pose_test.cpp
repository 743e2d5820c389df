// sensors_to_pose: counter extension, exact count -> pm, beam-layout solve
// with Abbe/cosine terms, LDS plane fit, validity, Hall phase and homing,
// pose errors. Synthetic sensors are generated here from the forward models
// (exact trigonometry in double), not from the kernel's inverses.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>

#include "CppUTest/TestHarness.h"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/fixed.hpp"
#include "maglev/sensors_to_pose/pose_error.hpp"
#include "maglev/sensors_to_pose/sensors_to_pose.hpp"
#include "maglev/sensors_to_pose/internal/wide_math.hpp"

namespace {

using namespace maglev::kernel;  // NOLINT
namespace io = maglev::io;
namespace stage = maglev::io::stage;

// Exact reference arithmetic, portable (32-bit Arm has no __int128): a
// 128-bit magnitude in four 32-bit limbs, least significant first, plus a
// sign. Only what the references need: signed 64 x 64 -> 128 (schoolbook on
// 32-bit limbs, every partial product exact in uint64), add, shift right,
// and "fits in int64". The kernel itself never uses it.
struct Wide128 {
  bool negative = false;
  std::uint32_t limb[4] = {0, 0, 0, 0};
};

std::uint64_t Magnitude(std::int64_t v) {
  return v < 0 ? std::uint64_t{0} - static_cast<std::uint64_t>(v) : static_cast<std::uint64_t>(v);
}

Wide128 MulExact(std::int64_t a, std::int64_t b) {
  const std::uint64_t ma = Magnitude(a), mb = Magnitude(b);
  const std::uint32_t x[2] = {static_cast<std::uint32_t>(ma), static_cast<std::uint32_t>(ma >> 32)};
  const std::uint32_t y[2] = {static_cast<std::uint32_t>(mb), static_cast<std::uint32_t>(mb >> 32)};
  Wide128 r;
  r.negative = (a < 0) != (b < 0) && ma != 0 && mb != 0;
  for (int i = 0; i < 2; ++i) {
    std::uint64_t carry = 0;
    for (int j = 0; j < 2; ++j) {
      // <= (2^32-1)^2 + 2 (2^32-1) = 2^64 - 1: no overflow.
      const std::uint64_t t = static_cast<std::uint64_t>(x[i]) * y[j] + r.limb[i + j] + carry;
      r.limb[i + j] = static_cast<std::uint32_t>(t);
      carry = t >> 32;
    }
    r.limb[i + 2] = static_cast<std::uint32_t>(carry);
  }
  return r;
}

// |w| + v (the magnitude; no overflow for the values used here: < 2^127).
Wide128 AddMagnitude(Wide128 w, std::uint64_t v) {
  std::uint64_t carry = v;
  for (auto& l : w.limb) {
    const std::uint64_t t = static_cast<std::uint64_t>(l) + (carry & 0xFFFFFFFFu);
    carry = (carry >> 32) + (t >> 32);
    l = static_cast<std::uint32_t>(t);
  }
  return w;
}

// |w| >> n, 0 < n < 32.
Wide128 ShiftRightMagnitude(Wide128 w, int n) {
  for (int i = 0; i < 4; ++i) {
    const std::uint32_t next = i < 3 ? w.limb[i + 1] : 0u;
    w.limb[i] = (w.limb[i] >> n) | static_cast<std::uint32_t>(static_cast<std::uint64_t>(next) << (32 - n));
  }
  return w;
}

Wide128 ShiftRightMagnitudeBy(Wide128 w, int n) {
  for (; n >= 31; n -= 31) w = ShiftRightMagnitude(w, 31);
  return n > 0 ? ShiftRightMagnitude(w, n) : w;
}

// The signed value if |w| <= INT64_MAX.
bool ToInt64(const Wide128& w, std::int64_t* out) {
  if (w.limb[3] != 0 || w.limb[2] != 0 || (w.limb[1] & 0x80000000u) != 0) return false;
  const auto m = static_cast<std::int64_t>((static_cast<std::uint64_t>(w.limb[1]) << 32) | w.limb[0]);
  *out = w.negative ? -m : m;
  return true;
}

constexpr double kLsb_m = 632.991e-9 / 1024.0;

SensorsToPoseState& FreshState(const SensorsToPoseConfig& cfg) {
  static SensorsToPoseState st;
  CHECK(ApplySensorsToPoseConfig(cfg, &st) == SensorsToPoseError::kOk);
  return st;
}

io::SensorSample ZeroSample() {
  io::SensorSample s{};
  return s;
}

// Forward interferometer model (beams fixed in the world, mirror on the platen).
double BeamReading_m(const BeamConfig& b, double x, double y, double th) {
  const double t = std::tan(th), sec1 = 1.0 / std::cos(th) - 1.0;
  if (b.axis == BeamAxis::kX) return b.sign * (x - (b.perpendicular_m - y) * t + b.mirror_distance_m * sec1);
  return b.sign * (y + (b.perpendicular_m - x) * t + b.mirror_distance_m * sec1);
}

}  // namespace

TEST_GROUP(SensorsToPose){};

TEST(SensorsToPose, CounterExtensionAcrossWrapsBothWays) {
  std::uint32_t last = 0xFFFFFF00u;
  std::int64_t counts = 0;
  // Up across the wrap in steps of 100.
  for (int n = 1; n <= 10; ++n) {
    const std::uint32_t raw = 0xFFFFFF00u + static_cast<std::uint32_t>(100 * n);  // wraps after n = 2
    CHECK(ExtendCounter(raw, &last, &counts, 1000));
    CHECK_EQUAL(100 * n, counts);
  }
  // Down back across the wrap, further down to -5000.
  for (int n = 9; n >= -50; --n) {
    const std::uint32_t raw = 0xFFFFFF00u + static_cast<std::uint32_t>(100 * n);
    CHECK(ExtendCounter(raw, &last, &counts, 1000));
    CHECK_EQUAL(100 * n, counts);
  }
  // A 2^31-1 step is a glitch: flagged, not absorbed, and stays flagged until
  // the hardware counter comes back near the last good value.
  const std::uint32_t good = last;
  CHECK_FALSE(ExtendCounter(good + 0x7FFFFFFFu, &last, &counts, 1000));
  CHECK_EQUAL(-5000, counts);
  CHECK_EQUAL(good, last);
  CHECK_FALSE(ExtendCounter(good - 1001u, &last, &counts, 1000));
  CHECK(ExtendCounter(good - 1000u, &last, &counts, 1000));
  CHECK_EQUAL(-6000, counts);
  // Many turns of the 32-bit counter: 5e9 counts in 1e6-count steps.
  last = 123u;
  counts = 0;
  for (int n = 0; n < 5000; ++n) CHECK(ExtendCounter(last + 1000000u, &last, &counts, 1000000));
  CHECK_EQUAL(std::int64_t{5000000000}, counts);
}

TEST(SensorsToPose, ExactCountToPicometre) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  CHECK_EQUAL(632991, st.lsb_num);
  CHECK_EQUAL(1024, st.lsb_den);
  CHECK_EQUAL(632991, CountsToPicometres(1024, st));
  CHECK_EQUAL(-632991, CountsToPicometres(-1024, st));
  CHECK_EQUAL(618, CountsToPicometres(1, st));      // 618.155
  CHECK_EQUAL(-618, CountsToPicometres(-1, st));
  CHECK_EQUAL(1854, CountsToPicometres(3, st));     // 1854.466
  // Exhaustive check against an exact 128-bit reference (Wide128, host and M7).
  std::mt19937_64 rng(42);
  for (int n = 0; n < 200000; ++n) {
    const std::int64_t c = static_cast<std::int64_t>(rng() >> 22) - (std::int64_t{1} << 41);
    // c * 632991 / 1024, rounded half away from zero: (|num| + 512) >> 10 on the magnitude.
    std::int64_t expect = 0;
    CHECK(ToInt64(ShiftRightMagnitudeBy(AddMagnitude(MulExact(c, 632991), 512), 10), &expect));
    if (CountsToPicometres(c, st) != expect) {
      std::printf("\n counts %lld", static_cast<long long>(c));
      CHECK_EQUAL(expect, CountsToPicometres(c, st));
    }
  }
  // Ties: 512 counts = 316495.5 pm -> 316496; -512 -> -316496.
  CHECK_EQUAL(316496, CountsToPicometres(512, st));
  CHECK_EQUAL(-316496, CountsToPicometres(-512, st));
}

TEST(SensorsToPose, ExactReferenceArithmetic) {
  // The reference itself, on values with known 128-bit results.
  const Wide128 max_sq = MulExact(INT64_MAX, INT64_MAX);  // (2^63-1)^2 = 2^126 - 2^64 + 1
  CHECK_EQUAL(1u, max_sq.limb[0]);
  CHECK_EQUAL(0u, max_sq.limb[1]);
  CHECK_EQUAL(0xFFFFFFFFu, max_sq.limb[2]);
  CHECK_EQUAL(0x3FFFFFFFu, max_sq.limb[3]);
  CHECK_FALSE(max_sq.negative);
  const Wide128 min_sq = MulExact(INT64_MIN, -1);  // 2^63: one past INT64_MAX
  CHECK_EQUAL(0x80000000u, min_sq.limb[1]);
  CHECK(min_sq.negative == false);
  std::int64_t v = 0;
  CHECK_FALSE(ToInt64(min_sq, &v));
  CHECK(ToInt64(MulExact(-3037000499LL, 3037000499LL), &v));  // -(2^31.5)^2, just below 2^63
  CHECK_EQUAL(-9223372030926249001LL, v);
  // Carries across every limb: (2^96 - 1) + 1 = 2^96.
  Wide128 w;
  w.limb[0] = w.limb[1] = w.limb[2] = 0xFFFFFFFFu;
  w = AddMagnitude(w, 1);
  CHECK_EQUAL(0u, w.limb[0]);
  CHECK_EQUAL(0u, w.limb[2]);
  CHECK_EQUAL(1u, w.limb[3]);
  w = ShiftRightMagnitudeBy(w, 40);  // 2^56
  CHECK(ToInt64(w, &v));
  CHECK_EQUAL(std::int64_t{1} << 56, v);
  CHECK(ToInt64(MulExact(0, -5), &v));
  CHECK_EQUAL(0, v);
}

TEST(SensorsToPose, WideMulShiftMatchesExactReference) {
  std::mt19937_64 rng(5);
  int checked = 0;
  for (int n = 0; n < 100000; ++n) {
    const std::int64_t a = static_cast<std::int64_t>(rng()) >> (static_cast<int>(rng() % 30) + 1);
    const std::int64_t c = static_cast<std::int64_t>(rng()) >> (static_cast<int>(rng() % 30) + 20);
    // a * c / 2^40, rounded half away from zero, where the result fits int64.
    std::int64_t expect = 0;
    if (!ToInt64(ShiftRightMagnitudeBy(AddMagnitude(MulExact(a, c), std::uint64_t{1} << 39), 40), &expect)) continue;
    CHECK_EQUAL(expect, wide::MulShiftRound(a, c));
    ++checked;
  }
  CHECK(checked > 50000);  // most draws fit; the reference did not skip them all
}

TEST(SensorsToPose, BeamLayoutSolveWithAbbeAndCosine) {
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> px(-0.028, 0.028), py(-0.0175, 0.0175), pth(-3.7e-3, 3.7e-3);
  double worst_xy = 0, worst_th = 0, worst_uncorrected = 0;
  for (int layout = 0; layout < 3; ++layout) {
    if (layout == 1) {
      // A different layout: two X beams at y = -/+ 40 mm, one Y beam at x = 10 mm, one sign flipped.
      cfg.beam[0] = {BeamAxis::kX, -0.040, 0.06, 1};
      cfg.beam[1] = {BeamAxis::kX, 0.040, 0.06, -1};
      cfg.beam[2] = {BeamAxis::kY, 0.010, 0.05, 1};
    }
    if (layout == 2) {
      // The closed form's quadratic branch: the pair's mirrors at different
      // distances (its difference then holds a t^2 term), the pair listed
      // first and in the order that makes dp < 0 (the configuration swaps it).
      cfg.beam[0] = {BeamAxis::kY, 0.045, 0.0715, 1};
      cfg.beam[1] = {BeamAxis::kY, -0.055, 0.030, 1};
      cfg.beam[2] = {BeamAxis::kX, 0.005, 0.090, -1};
    }
    for (int n = 0; n < 300; ++n) {
      SensorsToPoseState& st = FreshState(cfg);
      io::SensorSample s = ZeroSample();
      (void)SensorsToPoseStep(s, &st);  // seed at counts = 0: pose zero here
      const double x = px(rng), y = py(rng), th = pth(rng);
      for (int b = 0; b < 3; ++b) {
        // Counts relative to the zero pose (the reading at x = y = th = 0 is 0).
        const double m = BeamReading_m(cfg.beam[b], x, y, th) - BeamReading_m(cfg.beam[b], 0, 0, 0);
        s.interferometer_counts[b] = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::llround(m / kLsb_m)));
      }
      // Walk there in plausible steps (the plausibility bound is 1.29e6 counts/tick).
      io::SensorSample target = s;
      PoseMeasurement pm{};
      for (int k = 1; k <= 100; ++k) {
        io::SensorSample step = target;
        for (int b = 0; b < 3; ++b) {
          const double frac = k / 100.0;
          step.interferometer_counts[b] = static_cast<std::uint32_t>(
              static_cast<std::int32_t>(std::llround(static_cast<std::int32_t>(target.interferometer_counts[b]) * frac)));
        }
        pm = SensorsToPoseStep(step, &st);
      }
      CHECK_EQUAL(kPoseValidAll, pm.valid_axes);
      const double ex = static_cast<double>(pm.pose[maglev::kernel::Axis::kX]) * 1e-12 - x;
      const double ey = static_cast<double>(pm.pose[maglev::kernel::Axis::kY]) * 1e-12 - y;
      const double et = static_cast<double>(pm.pose[maglev::kernel::Axis::kThetaZ]) * 1e-12 - th;
      worst_xy = std::fmax(worst_xy, std::fmax(std::fabs(ex), std::fabs(ey)));
      worst_th = std::fmax(worst_th, std::fabs(et));
    }
  }
  // Without the correction the Abbe term (y * theta_z) shows up in full.
  cfg = DefaultSensorsToPoseConfig();
  cfg.abbe_cosine_correction = false;
  for (int n = 0; n < 50; ++n) {
    SensorsToPoseState& st = FreshState(cfg);
    io::SensorSample s = ZeroSample();
    (void)SensorsToPoseStep(s, &st);
    const double x = 0.0, y = 0.017, th = 1e-3 * (n + 1) / 50.0;
    for (int b = 0; b < 3; ++b) {
      const double m = BeamReading_m(cfg.beam[b], x, y, th) - BeamReading_m(cfg.beam[b], 0, 0, 0);
      s.interferometer_counts[b] = static_cast<std::uint32_t>(static_cast<std::int32_t>(std::llround(m / kLsb_m)));
    }
    const PoseMeasurement pm = SensorsToPoseStep(s, &st);
    worst_uncorrected = std::fmax(worst_uncorrected, std::fabs(static_cast<double>(pm.pose[maglev::kernel::Axis::kX]) * 1e-12 - x));
  }
  std::printf("\n  beam solve: worst |x,y err| = %.3g m, |theta_z err| = %.3g rad (LSB 0.618 nm);"
              " uncorrected Abbe error = %.3g m",
              worst_xy, worst_th, worst_uncorrected);
  // Quantisation: each beam +-0.5 LSB (0.31 nm); x,y mix two beams, theta_z
  // = (y2 - y1)/s -> 1 LSB / 0.08 m; plus < 1 pm arithmetic.
  CHECK(worst_xy < 1.0e-9);
  CHECK(worst_th < 1.0e-8);
  CHECK(worst_uncorrected > 1.5e-5);  // 17 mm * 1 mrad
}

TEST(SensorsToPose, DisplacementPlaneFit) {
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  SensorsToPoseState& st = FreshState(cfg);
  const double gain = 20e-6 * 10.0 / 32768.0;  // m per code
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> code(-30000, 30000);
  for (int n = 0; n < 2000; ++n) {
    io::SensorSample s = ZeroSample();
    double h[3];
    for (int i = 0; i < 3; ++i) {
      s.displacement_adc[i] = static_cast<std::int16_t>(code(rng));
      h[i] = 100e-6 + s.displacement_adc[i] * gain;
    }
    // Independent solve: z_i = z + tx*y_i - ty*x_i with the stage's corners
    // (x, y) = (a, a), (-a, a), (-a, -a):
    //   h0 - h1 = -ty*2a  ->  ty = (h1 - h0)/(2a);   h1 - h2 = tx*2a.
    const double a = 0.0615;
    const double ty = (h[1] - h[0]) / (2 * a);
    const double tx = (h[1] - h[2]) / (2 * a);
    const double z = h[1] - tx * a - ty * a;
    const PoseMeasurement pm = SensorsToPoseStep(s, &st);
    DOUBLES_EQUAL(z, static_cast<double>(pm.pose[maglev::kernel::Axis::kZ]) * 1e-12, 2e-12);
    DOUBLES_EQUAL(tx, static_cast<double>(pm.pose[maglev::kernel::Axis::kThetaX]) * 1e-12, 2e-11);
    DOUBLES_EQUAL(ty, static_cast<double>(pm.pose[maglev::kernel::Axis::kThetaY]) * 1e-12, 2e-11);
  }
  // Sign convention: a positive theta_x lifts the sensors at positive y.
  io::SensorSample s = ZeroSample();
  s.displacement_adc[0] = 1000;  // (a, a)
  s.displacement_adc[1] = 1000;  // (-a, a)
  s.displacement_adc[2] = -1000; // (-a, -a)
  const PoseMeasurement pm = SensorsToPoseStep(s, &st);
  CHECK(pm.pose[maglev::kernel::Axis::kThetaX] > 0);
  CHECK_EQUAL(0, pm.pose[maglev::kernel::Axis::kThetaY]);
}

// lds_z_point = 1: z is the mean of the three heights (the plane at the
// sensors' centroid), the tilts are the same plane's; 2 is refused.
TEST(SensorsToPose, ZAtTheSensorsCentroidIsTheMeanOfTheThreeHeights) {
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  SensorsToPoseConfig mean_cfg = cfg;
  mean_cfg.lds_z_point = 1;
  SensorsToPoseState& centre = FreshState(cfg);
  static SensorsToPoseState at_mean{};
  CHECK(ApplySensorsToPoseConfig(mean_cfg, &at_mean) == SensorsToPoseError::kOk);
  const double gain = 20e-6 * 10.0 / 32768.0;  // m per code
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> code(-30000, 30000);
  double xc = 0.0, yc = 0.0;
  for (int i = 0; i < 3; ++i) {
    xc += cfg.displacement_sensor_x_m[i] / 3.0;
    yc += cfg.displacement_sensor_y_m[i] / 3.0;
  }
  for (int n = 0; n < 2000; ++n) {
    io::SensorSample s = ZeroSample();
    double sum = 0.0;
    for (int i = 0; i < 3; ++i) {
      s.displacement_adc[i] = static_cast<std::int16_t>(code(rng));
      sum += cfg.displacement_zero_height_m + s.displacement_adc[i] * gain;
    }
    const PoseMeasurement c = SensorsToPoseStep(s, &centre);
    const PoseMeasurement m = SensorsToPoseStep(s, &at_mean);
    DOUBLES_EQUAL(sum / 3.0, static_cast<double>(m.pose[maglev::kernel::Axis::kZ]) * 1e-12, 2e-12);
    CHECK_EQUAL(c.pose[maglev::kernel::Axis::kThetaX], m.pose[maglev::kernel::Axis::kThetaX]);
    CHECK_EQUAL(c.pose[maglev::kernel::Axis::kThetaY], m.pose[maglev::kernel::Axis::kThetaY]);
    // The same plane: the centre's z moved to the centroid.
    const double tx = static_cast<double>(c.pose[maglev::kernel::Axis::kThetaX]) * 1e-12;
    const double ty = static_cast<double>(c.pose[maglev::kernel::Axis::kThetaY]) * 1e-12;
    DOUBLES_EQUAL(static_cast<double>(c.pose[maglev::kernel::Axis::kZ]) * 1e-12 + yc * tx - xc * ty,
                  static_cast<double>(m.pose[maglev::kernel::Axis::kZ]) * 1e-12, 3e-12);
  }
  SensorsToPoseState other{};
  mean_cfg.lds_z_point = 2;
  CHECK(ApplySensorsToPoseConfig(mean_cfg, &other) == SensorsToPoseError::kBadZPoint);
  LONGS_EQUAL(0, other.lsb_den);
}

TEST(SensorsToPose, ValidityFlags) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  io::SensorSample s = ZeroSample();
  CHECK_EQUAL(kPoseValidAll, SensorsToPoseStep(s, &st).valid_axes);
  s.status_flags = io::kBeamLoss1;
  PoseMeasurement pm = SensorsToPoseStep(s, &st);
  CHECK_EQUAL(kPoseValidOutOfPlane, pm.valid_axes);
  CHECK_EQUAL(2, pm.beam_loss);
  s.status_flags = io::kDisplacementOutOfRange2;
  pm = SensorsToPoseStep(s, &st);
  CHECK_EQUAL(kPoseValidInPlane, pm.valid_axes);
  CHECK_EQUAL(4, pm.displacement_bad);
  s.status_flags = 0;
  s.displacement_adc[0] = 32767;  // at the rail
  pm = SensorsToPoseStep(s, &st);
  CHECK_EQUAL(kPoseValidInPlane, pm.valid_axes);
  CHECK_EQUAL(1, pm.displacement_bad);
  s.displacement_adc[0] = -32768;
  CHECK_EQUAL(kPoseValidInPlane, SensorsToPoseStep(s, &st).valid_axes);
  s.displacement_adc[0] = 32766;
  CHECK_EQUAL(kPoseValidAll, SensorsToPoseStep(s, &st).valid_axes);
  s.status_flags = io::kAdcFault;
  CHECK_EQUAL(kPoseValidInPlane, SensorsToPoseStep(s, &st).valid_axes);
  s.status_flags = io::kStaleFrame;
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).valid_axes);
  // A counter jump latches in-plane invalid until re-seeded.
  s.status_flags = 0;
  s.interferometer_counts[2] = 0x40000000u;
  pm = SensorsToPoseStep(s, &st);
  CHECK_EQUAL(kPoseValidOutOfPlane, pm.valid_axes);
  CHECK_EQUAL(4, pm.beam_jump);
  s.interferometer_counts[2] = 0;
  CHECK_EQUAL(kPoseValidOutOfPlane, SensorsToPoseStep(s, &st).valid_axes);
  ReseedInterferometers(&st);
  CHECK_EQUAL(kPoseValidAll, SensorsToPoseStep(s, &st).valid_axes);
  // Degenerate configurations are refused.
  SensorsToPoseConfig bad = DefaultSensorsToPoseConfig();
  bad.beam[0].axis = BeamAxis::kY;
  bad.beam[0].perpendicular_m = 0.02;  // three Y beams: x unobservable
  SensorsToPoseState other{};
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kSingularBeamLayout);
  bad = DefaultSensorsToPoseConfig();
  bad.displacement_sensor_x_m[2] = 0.0615 * 3;  // collinear with the first two? make them collinear:
  bad.displacement_sensor_y_m[2] = 0.0615;
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kSingularDisplacementLayout);
}

namespace {
// eq (1) at the Hall height: B ~ sum_k (-1)^k eps_k sin(n_k theta) with n = 1, 5, 9, 13.
double HallField(double th, const double (&e)[kHallHarmonics], bool cosine) {
  double b = cosine ? std::cos(th) : std::sin(th);
  for (int k = 0; k < kHallHarmonics; ++k) {
    const double n = HallHarmonicOrder(k);
    const double sign = (k % 2 == 0) ? -1.0 : 1.0;
    b += sign * e[k] * (cosine ? std::cos(n * th) : std::sin(n * th));
  }
  return b;
}
// phi = atan2(A, B) of that field: theta + arg w(theta).
double HallPhi(double th, const double (&e)[kHallHarmonics]) {
  return std::atan2(HallField(th, e, false), HallField(th, e, true));
}
}  // namespace

// A laser displacement reading is bad at an ADC rail, code >= rail or
// code <= -rail - 1 (one unsigned compare in the tick), or with its
// out-of-range status bit: every int16 code on sensor 1, at four rails, with
// and without the status bits of the other two sensors.
TEST(SensorsToPose, ADisplacementReadingIsBadExactlyAtItsRailsOrWithItsStatusBit) {
  for (const std::int16_t rail : {std::int16_t{1}, std::int16_t{1000}, std::int16_t{32766}, std::int16_t{32767}}) {
    SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
    cfg.adc_rail_code = rail;
    SensorsToPoseState& st = FreshState(cfg);
    io::SensorSample s = ZeroSample();
    long mismatches = 0;
    for (std::int32_t code = -32768; code <= 32767; ++code) {
      s.displacement_adc[1] = static_cast<std::int16_t>(code);
      s.status_flags = (code & 1) != 0 ? static_cast<std::uint16_t>(io::kDisplacementOutOfRange0 | io::kDisplacementOutOfRange2) : 0u;
      const PoseMeasurement pm = SensorsToPoseStep(s, &st);
      const bool railed = code >= rail || code <= -rail - 1;
      const unsigned expected = (railed ? 2u : 0u) | ((code & 1) != 0 ? 5u : 0u);
      if (pm.displacement_bad != expected) ++mismatches;
    }
    LONGS_EQUAL(0, mismatches);
  }
}

TEST(SensorsToPose, HallPhaseOverAFullPitchWithTheArraysHarmonics) {
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  SensorsToPoseState& st = FreshState(cfg);
  const double(&eps)[kHallHarmonics] = cfg.hall_harmonic_ratio;
  // The seed's 1.6 mm: the 9th is 2.9 % of the fundamental, the 13th 0.9 %.
  DOUBLES_EQUAL(0.1144, eps[0], 1e-4);
  DOUBLES_EQUAL(0.0288, eps[1], 1e-4);
  DOUBLES_EQUAL(0.0090, eps[2], 1e-4);
  SensorsToPoseConfig fifth_cfg = cfg;  // the solve before: the 5th alone
  fifth_cfg.hall_harmonic_ratio[1] = fifth_cfg.hall_harmonic_ratio[2] = 0.0;
  static SensorsToPoseState st_fifth;
  CHECK(ApplySensorsToPoseConfig(fifth_cfg, &st_fifth) == SensorsToPoseError::kOk);
  SensorsToPoseConfig raw_cfg = cfg;
  for (double& e : raw_cfg.hall_harmonic_ratio) e = 0.0;  // plain atan2
  static SensorsToPoseState st_raw;
  CHECK(ApplySensorsToPoseConfig(raw_cfg, &st_raw) == SensorsToPoseError::kOk);
  const double amp = 20000.0;
  double worst = 0.0, worst_fifth = 0.0, worst_raw = 0.0;
  const auto err = [](std::uint32_t turn, double truth) {
    double e = turn / 4294967296.0 * 2 * stage::kPi - truth;
    e -= 2 * stage::kPi * std::floor(e / (2 * stage::kPi) + 0.5);
    return std::fabs(e);
  };
  for (int n = 0; n < 4096; ++n) {
    const double th = 2 * stage::kPi * n / 4096.0;
    const double thy = th + 1.0;  // y at another phase
    io::SensorSample s = ZeroSample();
    // Sensor B a quarter pitch on: sin(n (theta + pi/2)) = cos(n theta) for n = 4k + 1.
    s.hall_adc[0] = static_cast<std::int16_t>(std::lround(amp * HallField(th, eps, false)));
    s.hall_adc[1] = static_cast<std::int16_t>(std::lround(amp * HallField(thy, eps, false)));
    s.hall_adc[2] = static_cast<std::int16_t>(std::lround(amp * HallField(th, eps, true)));
    s.hall_adc[3] = static_cast<std::int16_t>(std::lround(amp * HallField(thy, eps, true)));
    const HallPhase hp = HallToPhase(s, st);
    CHECK(hp.plausible);
    worst = std::fmax(worst, std::fmax(err(hp.phase_x_turn, th), err(hp.phase_y_turn, thy)));
    worst_fifth = std::fmax(worst_fifth, err(HallToPhase(s, st_fifth).phase_x_turn, th));
    worst_raw = std::fmax(worst_raw, err(HallToPhase(s, st_raw).phase_x_turn, th));
  }
  const double um_per_rad = stage::kPitch_m / (2 * stage::kPi) * 1e6;
  std::printf("\n  Hall: c5/c1 %.4f, c9/c1 %.4f, c13/c1 %.4f; phase error %.3g rad (%.3g um); 5th alone %.3g rad "
              "(%.3g um); plain atan2 %.3g rad (%.3g um)",
              eps[0], eps[1], eps[2], worst, worst * um_per_rad, worst_fifth, worst_fifth * um_per_rad, worst_raw,
              worst_raw * um_per_rad);
  // Bound: ADC quantisation 0.5 code on a 20000-code vector -> 2.5e-5 rad per
  // channel, ~5e-5 rad with the harmonics' gain; the iteration's residual is
  // at the double floor.
  CHECK(worst < 1.0e-4);
  // What the 9th and 13th left when only the 5th was removed: ~0.03 rad,
  // 0.25 mm of position (the defect this replaced).
  CHECK(worst_fifth > 0.02);
  CHECK(worst_raw > 0.1);
  // Implausible: unplugged sensor (zeros) and a railed channel.
  io::SensorSample z = ZeroSample();
  CHECK_FALSE(HallToPhase(z, st).plausible);
  z.hall_adc[0] = 32767;
  z.hall_adc[2] = 100;
  CHECK_FALSE(HallToPhase(z, st).plausible);
}

// The solver alone, on exact phases: one fixed-point pass + 6 Newton steps
// reach the double floor over the whole valid range (least slope >= 0.2): the
// three harmonics of arrays pitch/4 (the seed's), pitch/8 and pitch/2 thick at
// Hall heights down to the bound, and the 5th alone up to 0.165.
TEST(SensorsToPose, HallSolveConvergesOverTheValidHarmonicRange) {
  struct Case {
    double e[kHallHarmonics];
  };
  Case cases[64]{};
  int count = 0;
  for (double e5 : {0.0, 0.05, 0.114, 0.15, 0.165}) cases[count++] = Case{{e5, 0.0, 0.0}};
  for (double thickness : {stage::kPitch_m / 8, stage::kMagnetThickness_m, stage::kPitch_m / 2}) {
    for (double h_mm = 0.30; h_mm < 6.0; h_mm *= 1.15) {
      Case c{};
      HallHarmonicRatios(h_mm * 1e-3, thickness, stage::kPitch_m, c.e);
      if (HallPhaseSlopeMin(c.e) >= kHallPhaseSlopeMin) cases[count++] = c;
    }
  }
  CHECK(count > 40);
  for (int i = 0; i < count; ++i) {
    const Case& c = cases[i];
    const double slope = HallPhaseSlopeMin(c.e);
    CHECK(slope >= kHallPhaseSlopeMin);
    double worst = 0.0, worst_after_4 = 0.0;
    for (int n = 0; n < 20000; ++n) {
      const double truth = -stage::kPi + 2 * stage::kPi * (n + 0.5) / 20000.0;
      HallSolve h{};
      for (int k = 0; k < kHallHarmonics; ++k) h.eps[k] = c.e[k];
      for (int a = 0; a < 2; ++a) {
        const double t = truth + 0.3 * a;
        // phi = t + arg w(t), wrapped near t (atan2 of the field).
        double phi = HallPhi(t, c.e);
        phi += 2 * stage::kPi * std::floor((t - phi) / (2 * stage::kPi) + 0.5);
        h.phi[a] = phi;
        h.theta[a] = h.phi[a];
      }
      for (int k = 0; k < 4; ++k) HallSolveStep(&h);
      worst_after_4 = std::fmax(worst_after_4, std::fabs(h.theta[0] - truth));
      while (h.steps < kHallSolveSteps) HallSolveStep(&h);
      HallSolveStep(&h);  // a step beyond the last is a no-op
      LONGS_EQUAL(kHallSolveSteps, h.steps);
      worst = std::fmax(worst, std::fmax(std::fabs(h.theta[0] - truth), std::fabs(h.theta[1] - truth - 0.3)));
    }
    std::printf("\n  Hall solve eps %.3f %.3f %.3f (least slope %.3f): |error| after 4 steps %.2g rad, after %d %.2g rad",
                c.e[0], c.e[1], c.e[2], slope, worst_after_4, kHallSolveSteps, worst);
    CHECK(worst < 2e-14);
  }
  // Below the bound: refused at configuration (a Hall 0.25 mm above this array).
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  HallHarmonicRatios(0.25e-3, stage::kMagnetThickness_m, stage::kPitch_m, cfg.hall_harmonic_ratio);
  CHECK(HallPhaseSlopeMin(cfg.hall_harmonic_ratio) < kHallPhaseSlopeMin);
  SensorsToPoseState other{};
  CHECK(ApplySensorsToPoseConfig(cfg, &other) == SensorsToPoseError::kBadHallConfig);
  cfg = DefaultSensorsToPoseConfig();
  cfg.hall_harmonic_ratio[0] = 0.17;
  cfg.hall_harmonic_ratio[1] = cfg.hall_harmonic_ratio[2] = 0.0;
  CHECK(ApplySensorsToPoseConfig(cfg, &other) == SensorsToPoseError::kBadHallConfig);
  cfg.hall_harmonic_ratio[0] = 0.165;
  CHECK(ApplySensorsToPoseConfig(cfg, &other) == SensorsToPoseError::kOk);
}

TEST(SensorsToPose, HomingMakesXyMagnetFrame) {
  SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  const double(&eps)[kHallHarmonics] = cfg.hall_harmonic_ratio;
  const double g = 2 * stage::kPi / stage::kPitch_m;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(-0.1, 0.1);
  for (int n = 0; n < 200; ++n) {
    SensorsToPoseState& st = FreshState(cfg);
    const double x_true = pos(rng), y_true = pos(rng);
    io::SensorSample s = ZeroSample();
    const double ax = g * (x_true + cfg.hall_a_x_m), ay = g * (y_true + cfg.hall_a_y_m);
    s.hall_adc[0] = static_cast<std::int16_t>(std::lround(20000 * HallField(ax, eps, false)));
    s.hall_adc[1] = static_cast<std::int16_t>(std::lround(20000 * HallField(ay, eps, false)));
    s.hall_adc[2] = static_cast<std::int16_t>(std::lround(20000 * HallField(ax, eps, true)));
    s.hall_adc[3] = static_cast<std::int16_t>(std::lround(20000 * HallField(ay, eps, true)));
    // The interferometer zero is wherever the platen was at power-up.
    const PoseMeasurement pm0 = SensorsToPoseStep(s, &st);
    CHECK_EQUAL(0, pm0.pose_unhomed[maglev::kernel::Axis::kX]);
    const HomingOffsets off = ComputeHomingOffsets(HallToPhase(s, st), pm0.pose_unhomed, st);
    CHECK(off.x_pm >= -st.pitch_pm / 2 && off.x_pm < st.pitch_pm / 2);
    SetHomingOffsets(off, &st);
    const PoseMeasurement pm = SensorsToPoseStep(s, &st);
    // x now equals x_true modulo the pitch, within the Hall error (< 1 um).
    const auto mod_err = [&](std::int64_t got_pm, double truth) {
      double e = static_cast<double>(got_pm) * 1e-12 - truth;
      e -= stage::kPitch_m * std::floor(e / stage::kPitch_m + 0.5);
      return std::fabs(e);
    };
    CHECK(mod_err(pm.pose[maglev::kernel::Axis::kX], x_true) < 1e-6);
    CHECK(mod_err(pm.pose[maglev::kernel::Axis::kY], y_true) < 1e-6);
  }
}

TEST(SensorsToPose, PoseErrorsSaturate) {
  Pose64 ref{};
  ref[Axis::kX] = 1000000;
  ref[Axis::kY] = -2500000;
  ref[Axis::kZ] = 30000000;
  ref[Axis::kThetaX] = 100000;
  ref[Axis::kThetaY] = -100000;
  ref[Axis::kThetaZ] = 1000000;
  Pose64 meas{};
  float e[6];
  PoseErrors<float>(ref, meas, e);
  DOUBLES_EQUAL(1.0, static_cast<double>(e[0]), 1e-7);   // x 1 um
  DOUBLES_EQUAL(-2.5, static_cast<double>(e[1]), 1e-7);  // y
  DOUBLES_EQUAL(1.0, static_cast<double>(e[2]), 1e-7);   // theta_z 1 urad
  DOUBLES_EQUAL(30.0, static_cast<double>(e[3]), 1e-6);  // z
  DOUBLES_EQUAL(0.1, static_cast<double>(e[4]), 1e-7);
  DOUBLES_EQUAL(-0.1, static_cast<double>(e[5]), 1e-7);
  maglev::numeric::Q7_24 q[6];
  ref[maglev::kernel::Axis::kX] = INT64_MAX;
  meas[maglev::kernel::Axis::kX] = -5;
  ref[maglev::kernel::Axis::kY] = -1000000000000;  // -1 m
  PoseErrors<maglev::numeric::Q7_24>(ref, meas, q);
  CHECK(q[0] == maglev::numeric::Q7_24::max());
  CHECK(q[1] == maglev::numeric::Q7_24::min());
  DOUBLES_EQUAL(30.0, q[3].to_double(), 1e-7);
}

// --- acceleration plausibility: a count step no actuator can produce --------
namespace {

// Beam 0 (x) moving at a constant 25 mm/s (10 um = 16 181 counts per tick at
// 2.5 kHz), beam 1 still plus `offset_beam1`, beam 2 still: tick n.
io::SensorSample MovingSample(int n, std::int32_t offset_beam1 = 0) {
  io::SensorSample s = ZeroSample();
  s.interferometer_counts[0] = static_cast<std::uint32_t>(16181 * n);
  s.interferometer_counts[1] = static_cast<std::uint32_t>(5000 + offset_beam1);
  s.interferometer_counts[2] = 5000u;
  return s;
}

// Beam b's extended count as the integer it is (the state holds it in a
// double, exact below 2^53): a fractional or out-of-range value fails here.
std::int64_t Count(const SensorsToPoseState& st, int b) {
  const double c = st.counts[b];
  CHECK(c == std::floor(c) && std::fabs(c) < 9007199254740992.0);
  return static_cast<std::int64_t>(c);
}

std::int64_t Beam1Pm(const SensorsToPoseState& st) { return CountsToPicometres(Count(st, 1), st); }

}  // namespace

TEST(SensorsToPose, AJumpNoActuatorCanProduceIsReplacedByThePreviousStepAndFlagged) {
  const SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  SensorsToPoseState& st = FreshState(cfg);
  // 80 m/s^2 at 2.5 kHz: a step change of ceil(80 / 2500^2 / lsb) counts.
  LONGS_EQUAL(static_cast<long>(std::ceil(80.0 / (2500.0 * 2500.0) / kLsb_m)), st.max_counts_step_change);
  LONGS_EQUAL(20707, st.max_counts_step_change);
  int n = 0;
  for (; n < 10; ++n) {
    const PoseMeasurement pm = SensorsToPoseStep(MovingSample(n), &st);
    LONGS_EQUAL(0, pm.beam_glitch);  // constant speed: no change of step at all
  }
  const std::int64_t x_before = Count(st, 0);
  const std::int64_t y1_before = Beam1Pm(st);
  // Run 5693 of the campaign: -35 943 counts (22 um) on beam 1 in one tick,
  // kept from then on, while the stage moves in x.
  PoseMeasurement pm = SensorsToPoseStep(MovingSample(n++, -35943), &st);
  LONGS_EQUAL(2, pm.beam_glitch);
  LONGS_EQUAL(-35943, pm.glitch_counts[1]);
  LONGS_EQUAL(0, pm.glitch_counts[0]);
  CHECK_EQUAL(kPoseValidAll, pm.valid_axes);  // repaired: the pose stays usable
  LONGS_EQUAL(0, pm.beam_jump);
  LONGS_EQUAL(y1_before, Beam1Pm(st));          // beam 1 took its previous step (zero)
  LONGS_EQUAL(x_before + 16181, Count(st, 0));  // beam 0 moved on untouched
  // The jump stays in the raw counter: taken as an offset, the pose does not move.
  for (int k = 0; k < 20; ++k, ++n) {
    pm = SensorsToPoseStep(MovingSample(n, -35943), &st);
    LONGS_EQUAL(0, pm.beam_glitch);
    LONGS_EQUAL(y1_before, Beam1Pm(st));
  }
  // Real motion after the glitch is measured as before (+100 counts).
  pm = SensorsToPoseStep(MovingSample(n++, -35943 + 100), &st);
  LONGS_EQUAL(0, pm.beam_glitch);
  LONGS_EQUAL(y1_before + CountsToPicometres(100, st), Beam1Pm(st));
}

TEST(SensorsToPose, AOneTickSpikeIsRepairedBothWaysAndRealAccelerationIsMotion) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  int n = 0;
  for (; n < 5; ++n) (void)SensorsToPoseStep(MovingSample(n), &st);
  const std::int64_t y1 = Count(st, 1);
  // Out on one tick, back on the next: both steps are glitches, the count never moves.
  PoseMeasurement pm = SensorsToPoseStep(MovingSample(n++, 50000), &st);
  LONGS_EQUAL(2, pm.beam_glitch);
  LONGS_EQUAL(y1, Count(st, 1));
  pm = SensorsToPoseStep(MovingSample(n++, 0), &st);
  LONGS_EQUAL(2, pm.beam_glitch);
  LONGS_EQUAL(-50000, pm.glitch_counts[1]);
  LONGS_EQUAL(y1, Count(st, 1));
  pm = SensorsToPoseStep(MovingSample(n++, 0), &st);
  LONGS_EQUAL(0, pm.beam_glitch);
  // From rest, a step change just inside the bound (79.99 m/s^2) is motion.
  pm = SensorsToPoseStep(MovingSample(n++, 20707), &st);
  LONGS_EQUAL(0, pm.beam_glitch);
  LONGS_EQUAL(y1 + 20707, Count(st, 1));
  // Stopping dead again is motion too: at speed, one tick's worth of steps
  // more or less is allowed (a sample a tick early or late over a link).
  pm = SensorsToPoseStep(MovingSample(n++, 20707), &st);
  LONGS_EQUAL(0, pm.beam_glitch);
  pm = SensorsToPoseStep(MovingSample(n++, 20707), &st);
  LONGS_EQUAL(0, pm.beam_glitch);
  // At rest, one count beyond the bound is a glitch: the predicted step (0) is counted.
  pm = SensorsToPoseStep(MovingSample(n++, 20707 + 20708), &st);
  LONGS_EQUAL(2, pm.beam_glitch);
  LONGS_EQUAL(20708, pm.glitch_counts[1]);
  LONGS_EQUAL(y1 + 20707, Count(st, 1));
}

TEST(SensorsToPose, AStaleSampleIsNoStepAndTheNextFreshStepCoversTheTicksMissed) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  // Beam 0 at 60 mm/s (the campaign's moves): 24 um = 38 835 counts per tick.
  const std::int64_t v = 38835;
  io::SensorSample s = ZeroSample();
  int n = 0;
  auto at = [&](int k) {
    io::SensorSample x = s;
    x.interferometer_counts[0] = static_cast<std::uint32_t>(v * k);
    return x;
  };
  for (; n < 5; ++n) LONGS_EQUAL(0, SensorsToPoseStep(at(n), &st).beam_glitch);
  // Two ticks with nothing new (the previous sample repeated, flagged), then
  // the newest sample: three ticks of motion in one step. Not a glitch.
  io::SensorSample rep = at(n - 1);
  rep.status_flags = io::kStaleFrame;
  LONGS_EQUAL(0, SensorsToPoseStep(rep, &st).beam_glitch);
  LONGS_EQUAL(0, SensorsToPoseStep(rep, &st).beam_glitch);
  n += 2;
  LONGS_EQUAL(0, SensorsToPoseStep(at(n++), &st).beam_glitch);
  LONGS_EQUAL(v * (n - 1), Count(st, 0));
  LONGS_EQUAL(v, st.last_step[0]);
  LONGS_EQUAL(0, SensorsToPoseStep(at(n++), &st).beam_glitch);
  // A jump on beam 0 while it moves this fast: beyond 80 m/s^2 plus one
  // tick's worth of steps, repaired like at rest.
  io::SensorSample j = at(n++);
  j.interferometer_counts[0] += 60000;
  const PoseMeasurement pm = SensorsToPoseStep(j, &st);
  LONGS_EQUAL(1, pm.beam_glitch);
  LONGS_EQUAL(v * (n - 1), Count(st, 0));
}

// The counter rule written once in its general form (any gap of n ticks),
// as the tick's n = 1 fast path must agree with it: a reference model of
// the three counters run beside SensorsToPoseStep over random motion with
// glitches, spikes, speed violations, wraps and stale runs; counts, steps,
// raw, flags and refused changes compared at every tick.
TEST(SensorsToPose, TheCounterRuleOnEveryTickEqualsItsGeneralForm) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  const auto max_step = static_cast<std::uint32_t>(st.max_counts_per_tick);
  const auto max_change = static_cast<std::uint32_t>(st.max_counts_step_change);
  struct Ref {
    std::uint32_t last_raw = 0;
    std::int64_t counts = 0;
    std::int32_t last_step = 0;
  } ref[3];
  int steps_seen = 0, stale_gap = 0;
  bool seeded = false;
  auto mag = [](std::int64_t v) { return static_cast<std::uint64_t>(v < 0 ? -v : v); };
  std::mt19937_64 rng(7);
  std::uint32_t raw[3] = {0xFFFF0000u, 12345u, 0x7FFFFFF0u};  // near both wraps
  std::int64_t speed[3] = {0, 0, 0};
  io::SensorSample prev = ZeroSample();
  int glitches = 0, stale_ticks = 0, refused = 0, after_gap = 0;
  for (int tick = 0; tick < 200000; ++tick) {
    const unsigned kind = static_cast<unsigned>(rng() % 100);
    io::SensorSample smp = ZeroSample();
    const bool stale = tick > 2 && kind < 8;  // the transport repeats the previous sample
    if (stale) {
      smp = prev;
      smp.status_flags = io::kStaleFrame;
      ++stale_ticks;
    } else {
      for (int b = 0; b < 3; ++b) {
        // Motion within the acceleration bound, now and then a spike, a
        // jump or a step beyond the speed bound.
        speed[b] += static_cast<std::int64_t>(rng() % (2 * max_change + 1)) - max_change;
        if (mag(speed[b]) > max_step / 2) speed[b] /= 2;
        std::int64_t d = speed[b];
        const unsigned r = static_cast<unsigned>(rng() % 1000);
        if (r < 10) d += static_cast<std::int64_t>(rng() % 400000) - 200000;  // glitch-sized
        if (r == 10 && rng() % 10 == 0) d += (rng() & 1u) ? 2000000000ll : -2000000000ll;  // beyond the speed bound
        raw[b] += static_cast<std::uint32_t>(d);
        smp.interferometer_counts[b] = raw[b];
      }
    }
    prev = smp;
    const PoseMeasurement pm = SensorsToPoseStep(smp, &st);
    // The reference, general in n.
    const bool seed = !seeded;
    if (seed) {
      steps_seen = 0;
      stale_gap = 0;
      for (int b = 0; b < 3; ++b) ref[b] = Ref{smp.interferometer_counts[b], 0, 0};
    }
    const std::int64_t n = stale_gap + 1;
    const bool armed = max_change > 0 && steps_seen >= 2 && !stale;
    after_gap += (n > 1 && !stale) ? 1 : 0;
    for (int b = 0; b < 3; ++b) {
      Ref& R = ref[b];
      const auto step = static_cast<std::int32_t>(smp.interferometer_counts[b] - R.last_raw);
      const std::uint64_t speed_mag = mag(R.last_step);
      const bool in_speed = mag(step) <= max_step;
      const std::int64_t expected = n * R.last_step;
      const std::int64_t change = step - expected;
      const bool glitch = armed && in_speed && mag(change) > std::uint64_t{max_change} * static_cast<std::uint64_t>(n * n) + speed_mag;
      const std::uint32_t used = glitch ? R.last_raw + static_cast<std::uint32_t>(expected) : smp.interferometer_counts[b];
      const auto delta = static_cast<std::int32_t>(used - R.last_raw);
      const bool ok = mag(delta) <= max_step;
      const std::int32_t moved = ok ? delta : 0;
      R.counts += moved;
      R.last_raw = glitch ? smp.interferometer_counts[b] : (ok ? used : R.last_raw);
      const auto truncated = static_cast<std::int32_t>(moved / n);  // toward zero
      R.last_step = stale ? R.last_step : truncated;
      glitches += glitch ? 1 : 0;
      refused += ok ? 0 : 1;
      if (R.counts != Count(st, b) || R.last_raw != st.last_raw[b] || R.last_step != st.last_step[b] ||
          glitch != (((static_cast<unsigned>(pm.beam_glitch) >> b) & 1u) != 0u) || (glitch ? change : 0) != pm.glitch_counts[b] ||
          (!ok && ((static_cast<unsigned>(st.jump_latched) >> b) & 1u) == 0u)) {
        std::printf("tick %d beam %d n %lld: counts %lld / %lld, last_raw %lu / %lu, last_step %ld / %ld, glitch %d / %d\n",
                    tick, b, static_cast<long long>(n), static_cast<long long>(R.counts),
                    static_cast<long long>(Count(st, b)), static_cast<unsigned long>(R.last_raw),
                    static_cast<unsigned long>(st.last_raw[b]), static_cast<long>(R.last_step),
                    static_cast<long>(st.last_step[b]), glitch ? 1 : 0, (pm.beam_glitch >> b) & 1);
        FAIL("SensorsToPoseStep's counter rule differs from its general form");
      }
    }
    const bool counted = !stale || seed;
    steps_seen = counted && steps_seen < 2 ? steps_seen + 1 : steps_seen;
    stale_gap = stale && !seed ? (stale_gap < 255 ? stale_gap + 1 : 255) : 0;
    seeded = true;
    // A refused step latches the beam's jump flag until a re-seed: re-seed
    // both (the model and the kernel) now and then, so the run goes on.
    if (tick % 1000 == 999) {
      ReseedInterferometers(&st);
      seeded = false;
    }
  }
  std::printf("[counter rule] 200000 ticks: %d glitches, %d refused steps, %d stale ticks, %d ticks after a gap\n",
              glitches, refused, stale_ticks, after_gap);
  CHECK(glitches > 1000 && refused > 100 && stale_ticks > 10000 && after_gap > 10000);
}

TEST(SensorsToPose, TheAccelerationCheckArmsTwoStepsAfterASeedAndCanBeSwitchedOff) {
  SensorsToPoseState& st = FreshState(DefaultSensorsToPoseConfig());
  // Seed while the counters read far from zero, then a first real step that
  // is large (the stage moving when the counters were re-seeded): not a glitch.
  io::SensorSample s = MovingSample(0, 0);
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).beam_glitch);  // seed
  s.interferometer_counts[1] += 60000;
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).beam_glitch);  // first step: nothing to compare with
  s.interferometer_counts[1] += 60000;
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).beam_glitch);  // same step again
  s.interferometer_counts[1] += 60000 + 90000;
  CHECK_EQUAL(2, SensorsToPoseStep(s, &st).beam_glitch);  // armed: 90 000 > 20 707 + 60 000
  ReseedInterferometers(&st);
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).beam_glitch);
  s.interferometer_counts[0] += 90000;
  CHECK_EQUAL(0, SensorsToPoseStep(s, &st).beam_glitch);
  // Off (0): the same jump is read as motion, as before the check existed.
  SensorsToPoseConfig off = DefaultSensorsToPoseConfig();
  off.max_acceleration_m_per_s2 = 0.0;
  SensorsToPoseState& so = FreshState(off);
  LONGS_EQUAL(0, so.max_counts_step_change);
  int n = 0;
  for (; n < 5; ++n) (void)SensorsToPoseStep(MovingSample(n), &so);
  const std::int64_t y1 = Count(so, 1);
  CHECK_EQUAL(0, SensorsToPoseStep(MovingSample(n, -35943), &so).beam_glitch);
  LONGS_EQUAL(y1 - 35943, Count(so, 1));
  // Bounds that are not numbers, negative, finer than a count or beyond the
  // speed bound are refused, and the state is left as it was.
  SensorsToPoseState other{};
  SensorsToPoseConfig bad = DefaultSensorsToPoseConfig();
  bad.max_acceleration_m_per_s2 = -1.0;
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadPlausibilityBound);
  bad.max_acceleration_m_per_s2 = std::nan("");
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadPlausibilityBound);
  bad.max_acceleration_m_per_s2 = 1e-3;  // 0.0003 counts per tick^2
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadPlausibilityBound);
  bad.max_acceleration_m_per_s2 = 1e8;  // beyond the 2 m/s speed bound per tick
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadPlausibilityBound);
  LONGS_EQUAL(0, other.lsb_den);
}

// --- laser displacement sensors' target steps (issue 15) ---------------------
namespace {

// The heights of sensor 0 (code) with the others at code 0; homed with x
// offset home_x_m, so sensor 0's spot is at (61.5 mm + home_x_m, 61.5 mm).
io::SensorSample LdsSample(std::int16_t code0) {
  io::SensorSample s = ZeroSample();
  s.displacement_adc[0] = code0;
  return s;
}
SensorsToPoseState& HomedAt(const SensorsToPoseConfig& cfg, double home_x_m) {
  SensorsToPoseState& st = FreshState(cfg);
  SetHomingOffsets(HomingOffsets{static_cast<std::int64_t>(std::llround(home_x_m * 1e12)), 0}, &st);
  return st;
}
constexpr std::int16_t kCodes50um = 8192;  // 20 um/V * 10 V / 32768 = 6.1 nm per code
constexpr std::int16_t kCodesHalfUm = 82;  // 0.5 um: below the 1 um threshold

}  // namespace

TEST(SensorsToPose, ATargetStepAtABlockEdgeIsTakenAsAnOffsetOncePerEdgeVisit) {
  const SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  DOUBLES_EQUAL(stage::kPitch_m / 4.0, cfg.lds_target_cell_m, 1e-15);
  // Sensor 0's spot 0.3 mm short of the x edge at 5 cells (63.5 mm).
  SensorsToPoseState& st = HomedAt(cfg, 1.7e-3);
  const std::int64_t z0 = SensorsToPoseStep(LdsSample(0), &st).pose[maglev::kernel::Axis::kZ];
  LONGS_EQUAL(z0, SensorsToPoseStep(LdsSample(0), &st).pose[maglev::kernel::Axis::kZ]);
  // The spot crosses onto a block 50 um lower (the reading rises): repaired,
  // the pose does not move, and the step is reported.
  PoseMeasurement pm = SensorsToPoseStep(LdsSample(kCodes50um), &st);
  LONGS_EQUAL(1, pm.lds_target_step);
  DOUBLES_EQUAL(kCodes50um * st.lds_gain_pm, st.lds_held_pm[0], 1e-3);
  DOUBLES_EQUAL(-kCodes50um * st.lds_gain_pm, st.lds_offset_pm[0], 1e-3);
  CHECK(std::llabs(z0 - pm.pose[maglev::kernel::Axis::kZ]) <= 1);
  LONGS_EQUAL(1, st.lds_steps_repaired);
  // The platen's own motion after it is measured as usual (0.5 um at sensor 0).
  pm = SensorsToPoseStep(LdsSample(kCodes50um + kCodesHalfUm), &st);
  LONGS_EQUAL(0, pm.lds_target_step);
  DOUBLES_EQUAL(kCodesHalfUm * st.lds_gain_pm * st.inv_plane[0][0],
                static_cast<double>(pm.pose[maglev::kernel::Axis::kZ] - z0), 1.0);
  // A second jump the same way at the same edge is the platen moving (a fall,
  // a touchdown): not repaired, the loops and the supervisor see it.
  pm = SensorsToPoseStep(LdsSample(2 * kCodes50um + kCodesHalfUm), &st);
  LONGS_EQUAL(0, pm.lds_target_step);
  CHECK(pm.pose[maglev::kernel::Axis::kZ] - z0 > 16000000);
  // A jump that undoes the held step (the spot back over the edge, or
  // dithering on it) is repaired, however often.
  const std::int64_t z_moved = pm.pose[maglev::kernel::Axis::kZ];
  for (int k = 0; k < 4; ++k) {
    pm = SensorsToPoseStep(LdsSample(k % 2 == 0 ? kCodes50um + kCodesHalfUm : 2 * kCodes50um + kCodesHalfUm), &st);
    LONGS_EQUAL(1, pm.lds_target_step);
    CHECK(std::llabs(z_moved - pm.pose[maglev::kernel::Axis::kZ]) <= 1);
  }
  LONGS_EQUAL(5, st.lds_steps_repaired);
}

TEST(SensorsToPose, TargetJumpsAwayFromAnEdgeBelowTheThresholdUnhomedOrWithTheRepairOffAreMotion) {
  const SensorsToPoseConfig cfg = DefaultSensorsToPoseConfig();
  const auto jump_repaired = [](SensorsToPoseState& st, std::int16_t codes) {
    (void)SensorsToPoseStep(LdsSample(0), &st);
    (void)SensorsToPoseStep(LdsSample(0), &st);
    return SensorsToPoseStep(LdsSample(codes), &st).lds_target_step;
  };
  // At an edge (y: 61.5 mm is 2 mm from 63.5 mm; x 0.5 mm past 63.5 mm): repaired.
  LONGS_EQUAL(1, jump_repaired(HomedAt(cfg, 2.5e-3), kCodes50um));
  // 2 mm from both edges (x 61.5 mm, y 61.5 mm): a fault, not the target.
  LONGS_EQUAL(0, jump_repaired(HomedAt(cfg, 0.0), kCodes50um));
  // Below the 1 um threshold: left to the loops.
  LONGS_EQUAL(0, jump_repaired(HomedAt(cfg, 2.5e-3), kCodesHalfUm));
  // Before homing the spot is not known in the magnet frame.
  LONGS_EQUAL(0, jump_repaired(FreshState(cfg), kCodes50um));
  // Off: no cell (a stage without an array), or the switch (register
  // lds.target_repair) at 0 with the stage's cell kept; back on at 1.
  SensorsToPoseConfig off = cfg;
  off.lds_target_cell_m = 0.0;
  LONGS_EQUAL(0, jump_repaired(HomedAt(off, 2.5e-3), kCodes50um));
  off = cfg;
  off.lds_target_repair = 0;
  LONGS_EQUAL(0, jump_repaired(HomedAt(off, 2.5e-3), kCodes50um));
  off.lds_target_repair = 1;
  LONGS_EQUAL(1, jump_repaired(HomedAt(off, 2.5e-3), kCodes50um));
  // A railed reading breaks the track: its jump back is not compared with it.
  SensorsToPoseState& st = HomedAt(cfg, 2.5e-3);
  (void)SensorsToPoseStep(LdsSample(0), &st);
  (void)SensorsToPoseStep(LdsSample(32767), &st);
  LONGS_EQUAL(0, SensorsToPoseStep(LdsSample(kCodes50um), &st).lds_target_step);
  // Out-of-range settings are refused and leave the state as it was.
  SensorsToPoseState other{};
  SensorsToPoseConfig bad = cfg;
  bad.lds_target_cell_m = -1e-3;
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  bad = cfg;
  bad.lds_target_window_um = static_cast<float>(cfg.lds_target_cell_m / 2 * 1e6);
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  bad = cfg;
  bad.lds_target_step_min_um = std::nanf("");
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  bad = cfg;
  bad.lds_target_step_min_um = 0.05f;  // below 0.1 um
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  bad.lds_target_repair = 0;  // refused with the repair off too
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  bad = cfg;
  bad.lds_target_repair = 2;
  CHECK(ApplySensorsToPoseConfig(bad, &other) == SensorsToPoseError::kBadTargetStepRepair);
  LONGS_EQUAL(0, other.lsb_den);
}
