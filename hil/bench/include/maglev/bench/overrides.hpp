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

// The command line's plant options, which win over the scenario's [plant]
// keys: `run` and `serve` read them with one parser (parse_plant_option).
struct PlantOptions {
  std::optional<hil::PlantModel> model;       // --plant: the scenario's [plant] model
  std::optional<std::uint64_t> error_seed;    // --error-seed: [plant] error_seed (as-built)
  std::optional<std::string> floor;           // --floor CLASS: [plant] floor (docs/PLANT.md section 12)
  std::optional<double> floor_isolator_hz;    // --floor-isolator-hz HZ: [plant] floor_isolator_hz
};
// Their usage lines (one per option, for both commands' --help).
extern const char* const kPlantOptionsUsage;
enum class PlantOptionParse : std::uint8_t {
  kNotPlantOption = 0,  // `option` is none of them
  kTaken = 1,           // read into *p
  kBad = 2,             // one of them with a bad value: *err says why
};
// Reads `option value` into *p if the option is one of PlantOptions'. The
// floor's class and the isolator's range are checked with the scenario
// (apply_overrides), where the scenario's own keys are.
PlantOptionParse parse_plant_option(const std::string& option, const std::string& value, PlantOptions* p,
                                    std::string* err);

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
  PlantOptions command_line;  // --plant, --error-seed, --floor, --floor-isolator-hz
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

// The plant a stage runs on in `serve` as in `run`: the stage's own plant
// (*base, from its profile), then the scenario's [plant] keys (sc may be
// null: none) and the command line's plant options, read by
// apply_overrides. `controller` is the kernel configuration the stage runs
// (its travel bounds initial_x_m / initial_y_m, its rate the plant's step).
// false: *errs says why, key by key.
struct StagePlant {
  hil::PlantConfig plant;
  hil::PlantModel model = hil::PlantModel::kDefault;
  hil::ErrorSet error_set;
  hil::DrawnErrors drawn_errors;
  std::uint64_t seed = 1;  // the scenario's [scenario] seed, else 1
};
bool plant_for_stage(const hil::PlantConfig& base, const kernel::KernelConfig& controller,
                     const scenario::Scenario* sc, const PlantOptions& options, StagePlant* out,
                     std::vector<ScenarioError>* errs);

// Validates the timeline/metrics/overrides of a parsed scenario (verbs,
// argument counts, units, ranges). Empty = fine.
std::vector<ScenarioError> validate(const scenario::Scenario& sc);

}  // namespace maglev::bench
