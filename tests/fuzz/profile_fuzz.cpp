// libFuzzer target: the stage profile parser (hil/profile parse_profile) on
// arbitrary text, and what the firmware does with a profile it accepts.
// Profiles are written by hand for each lab's stage.
// Checked, beyond "no crash, no sanitizer report":
//   * every error names the file ("fuzz.profile:LINE: field: reason") with a
//     line inside the file;
//   * an accepted profile keeps the format's promises: a NUL-terminated
//     non-empty name and title, counts within their arrays, a start-up that
//     ends with 'ready', finite numbers, an increasing gain schedule, travel
//     MIN < MAX on every active axis;
//   * an accepted profile goes through the boot-time check
//     (CheckStageProfile) and, when the check passes, MakeKernelConfig
//     succeeds and the kernel applies the result: "runs" from the checker
//     means the kernel takes it.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "maglev/controller/controller.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

namespace {

namespace sp = maglev::stage_profile;
namespace kernel = maglev::kernel;

bool finite(double v) { return std::isfinite(v); }

void check_accepted(const sp::StageProfile& p) {
  if (p.name[0] == '\0' || std::memchr(p.name, '\0', sizeof p.name) == nullptr) __builtin_trap();
  if (std::memchr(p.title, '\0', sizeof p.title) == nullptr) __builtin_trap();
  if (p.actuator_count > sp::kMaxActuators || p.sensor_count > sp::kMaxSensors) __builtin_trap();
  if (!(p.servo_rate_Hz >= 100.0 && p.servo_rate_Hz <= 20000.0) || !(p.body.mass_kg > 0.0)) __builtin_trap();
  // Start-up: steps, then 'ready', then kEnd to the end of the array.
  int ready_at = -1;
  for (int i = 0; i < sp::kMaxStartupSteps; ++i) {
    if (p.startup[i] == sp::StartupStep::kReady) {
      ready_at = i;
      break;
    }
    if (p.startup[i] == sp::StartupStep::kEnd) __builtin_trap();
  }
  if (ready_at < 0) __builtin_trap();
  for (int i = ready_at + 1; i < sp::kMaxStartupSteps; ++i) {
    if (p.startup[i] != sp::StartupStep::kEnd) __builtin_trap();
  }
  for (const sp::Axis& a : p.axis) {
    const sp::AxisController& c = a.controller;
    if (!finite(a.travel_min) || !finite(a.travel_max) || !finite(c.kp) || !finite(c.ki) || !finite(c.kd)) {
      __builtin_trap();
    }
    if (a.mode == sp::AxisMode::kActive && !(a.travel_min < a.travel_max)) __builtin_trap();
    if (c.filter_count > sp::kMaxFilters || c.schedule_points > sp::kMaxSchedulePoints) __builtin_trap();
    if (c.schedule_points == 1) __builtin_trap();  // a schedule has 2..8 points or none
    for (int i = 1; i < c.schedule_points; ++i) {
      if (!(c.schedule[i].at > c.schedule[i - 1].at)) __builtin_trap();
    }
    for (int f = 0; f < c.filter_count; ++f) {
      const sp::Filter& fl = c.filters[f];
      if (!finite(fl.frequency_Hz) || !(fl.q > 0.0) || !finite(fl.q) || fl.depth_dB < 0.0 || fl.pole_Hz < 0.0) {
        __builtin_trap();
      }
    }
  }
  if (p.limits.peak_current_A > p.limits.hardware_current_A) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  const maglev::profile::ProfileParse r = maglev::profile::parse_profile(text, "fuzz.profile");
  if (!r.ok()) {
    int lines = 0;
    for (char c : text) lines += c == '\n' ? 1 : 0;
    for (const auto& e : r.errors) {
      // "fuzz.profile:LINE: ..." with LINE inside the file.
      if (e.rfind("fuzz.profile:", 0) != 0) __builtin_trap();
      const long line = std::strtol(e.c_str() + 13, nullptr, 10);
      if (line < 0 || line > lines + 1) __builtin_trap();
    }
    return 0;
  }
  check_accepted(r.profile);
  const sp::ProfileCheck check = sp::CheckStageProfile(r.profile);
  if (static_cast<int>(check.error) >= static_cast<int>(sp::ProfileError::kCount)) __builtin_trap();
  kernel::KernelConfig kc = kernel::default_kernel_config();
  const sp::ProfileCheck made = sp::MakeKernelConfig(r.profile, &kc);
  if (made.error != check.error) __builtin_trap();
  if (check.error != sp::ProfileError::kOk) return 0;
  // A controller at rest (never stepped) takes any configuration the kernel
  // considers valid; one per input so no state leaks between inputs.
  const auto controller = std::make_unique<kernel::Controller<float>>();
  if (controller->apply_config(kc) != kernel::ConfigError::kOk) __builtin_trap();
  return 0;
}
