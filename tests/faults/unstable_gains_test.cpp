// Gains the loop check finds unstable are refused by the kernel (issue 17):
// z kp = 1e7, kd = 1e4 were accepted while levitated, saturated the coils and
// let z sag while the status said Ready. Every path that sets gains (Modbus
// live tuning, scenario files, profiles) goes through apply_config.
#include "maglev/axis_loops/loop_check.hpp"
#include "maglev/controller/controller.hpp"

// CppUTest last: its new/delete macros must not meet the STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev::kernel;

TEST_GROUP(UnstableGains){};

TEST(UnstableGains, TheKernelRefusesThemAndKeepsItsConfiguration) {
  static Controller<float> c;  // static: large, and the kernel never allocates
  const KernelConfig good = default_kernel_config();
  CHECK_TRUE(c.apply_config(good) == ConfigError::kOk);
  KernelConfig bad = good;
  bad.axis[axis_index(Axis::kZ)].pid.kp = 1e7f;
  bad.axis[axis_index(Axis::kZ)].pid.kd = 1e4f;
  CHECK_TRUE(c.apply_config(bad) == ConfigError::kUnstableLoop);
  LONGS_EQUAL(axis_index(Axis::kZ), c.status().config_axis);
  CHECK_TRUE(c.config().axis[axis_index(Axis::kZ)].pid.kp == good.axis[axis_index(Axis::kZ)].pid.kp);
  STRCMP_EQUAL("UnstableLoop", to_string(ConfigError::kUnstableLoop));
  // The default gains pass with margin; the check agrees with the bench's
  // measured x loop (50.6 Hz, 28.3 deg).
  const InternalModelConfig& px = good.axis[axis_index(Axis::kX)].imr;
  const LoopMargins mx = Pid2DofLoopMargins(
      good.axis[axis_index(Axis::kX)].pid,
      LoopPlant{static_cast<double>(px.plant_gain), static_cast<double>(px.plant_damping_per_s),
                static_cast<double>(px.plant_stiffness_per_s2)},
      static_cast<double>(good.servo_rate_Hz));
  CHECK_TRUE(LoopIsAcceptable(mx));
  DOUBLES_EQUAL(50.6, mx.crossover_Hz, 1.0);
  DOUBLES_EQUAL(28.3, mx.phase_margin_deg, 2.0);
  // A too-slow integrator-only loop: no crossover margin left.
  bad = good;
  bad.axis[axis_index(Axis::kX)].pid.kp = 10.0f;
  bad.axis[axis_index(Axis::kX)].pid.kd = 0.0f;
  bad.axis[axis_index(Axis::kX)].pid.ki = 5e7f;
  CHECK_TRUE(c.apply_config(bad) == ConfigError::kUnstableLoop);
  LONGS_EQUAL(axis_index(Axis::kX), c.status().config_axis);
}
