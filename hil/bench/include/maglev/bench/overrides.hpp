// A scenario's [scenario], [plant] and [controller] keys on top of the
// defaults, and the whole-scenario validation (timeline, metrics, keys).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "maglev/controller/controller.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/plant/as_built.hpp"
#include "maglev/plant/plant_config.hpp"
#include "maglev/scenario/scenario.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::bench {

struct ScenarioError {
  std::string message;  // "file:line: what" (like the parser's errors)
};

// The stage every scenario runs on unless it (or --profile) names another.
inline constexpr const char* kDefaultProfile = "nk2017-cross";
// Where `--profile NAME` looks (hil/profiles of the source tree).
std::string profile_dir();

struct Overrides {
  std::string profile_name = kDefaultProfile;
  stage_profile::StageProfile profile{};
  hil::PlantConfig plant = hil::PlantConfig::Default();
  kernel::KernelConfig controller = kernel::default_kernel_config();
  std::uint64_t seed = 1;
  hil::KernelKind kernel = hil::KernelKind::kFloat32;
  // [plant] model (docs/PLANT.md "Plant models and error sets"); the command
  // line's --plant / --error-seed win over the scenario's keys.
  hil::PlantModel plant_model = hil::PlantModel::kDefault;
  // The plant's force-producing current noise is the density identified from
  // paper 000's 3 nm (docs/BENCH.md, "Noise model"): the default model, or
  // `noise = fitted`, and no density of the scenario's own. A rest-noise
  // figure then matches the paper by construction; the report says so.
  bool noise_fitted = false;
  std::optional<hil::PlantModel> plant_model_override;
  std::optional<std::uint64_t> error_seed_override;
  std::optional<std::string> floor_override;  // --floor CLASS: overrides [plant] floor
  std::optional<double> floor_isolator_override;  // --floor-isolator-hz HZ: overrides [plant] floor_isolator_hz
  hil::ErrorSet error_set;
  hil::DrawnErrors drawn_errors;  // as-built: what was drawn (metrics.json plant_error_*)
};

// Loads the profile NAME|FILE and builds the kernel configuration and the
// plant from it (both from the one record). false: *errs says why, field by
// field for a malformed profile.
// servo_rate_Hz: the servo rate the stage runs at instead of its profile's
// (one of io::stage::kSupportedServoRates_Hz): the kernel configuration is
// made and checked at that rate (the kernel discretizes every loop, filter and
// timing from its continuous definition) and the plant steps at it.
bool apply_profile(const std::string& name_or_path, Overrides* o, std::vector<ScenarioError>* errs,
                   std::optional<double> servo_rate_Hz = std::nullopt);
// The scenario's `[controller] servo_rate_Hz`, if it has one (a number; not
// checked here: apply_overrides reports a bad one).
std::optional<double> servo_rate_of(const scenario::Scenario& sc);
// "2500, 5000, 10000 or 20000 Hz": io::stage::kSupportedServoRates_Hz for messages.
std::string offered_servo_rates();
// The profile a scenario names ([scenario] profile), else the default.
std::string profile_of(const scenario::Scenario& sc);

// `[controller] preset = paper`: paper 000's published PIDs (27), (28), (32),
// (33) as printed, without our shaping (setpoint weights, acceleration
// feed-forward, output filters). docs/BENCH.md, "Controller presets".
void apply_paper_controller(kernel::KernelConfig* c);

// Applies the scenario's keys to *o; false: *errs says why (field by field).
bool apply_overrides(const scenario::Scenario& sc, Overrides* o, std::vector<ScenarioError>* errs);

// Validates the timeline/metrics/overrides of a parsed scenario (verbs,
// argument counts, units, ranges). Empty = fine.
std::vector<ScenarioError> validate(const scenario::Scenario& sc);

}  // namespace maglev::bench
