// A scenario's [scenario], [plant] and [controller] keys on top of the
// defaults, and the whole-scenario validation (timeline, metrics, keys).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "maglev/controller/controller.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/hil/plant_config.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

struct ScenarioError {
  std::string message;  // "file:line: what" (like the parser's errors)
};

struct Overrides {
  hil::PlantConfig plant = hil::PlantConfig::Default();
  kernel::KernelConfig controller = kernel::default_kernel_config();
  std::uint64_t seed = 1;
  hil::KernelKind kernel = hil::KernelKind::kFloat32;
};

// Applies the scenario's keys to *o; false: *errs says why (field by field).
bool apply_overrides(const scenario::Scenario& sc, Overrides* o, std::vector<ScenarioError>* errs);

// Validates the timeline/metrics/overrides of a parsed scenario (verbs,
// argument counts, units, ranges). Empty = fine.
std::vector<ScenarioError> validate(const scenario::Scenario& sc);

}  // namespace maglev::bench
