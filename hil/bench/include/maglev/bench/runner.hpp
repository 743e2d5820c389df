// The HIL bench runner: one scenario, plant + controller node over CAN.
// Parts: timeline.hpp (typed actions), metrics_registry.hpp (metric kinds),
// overrides.hpp ([plant]/[controller] keys, validate), the in-process
// executor (runner.cpp) and the two-process one (two_process.cpp), both on
// hil/lockstep's PlantEndpoint and hil/controller_node's node.
//
// Lockstep tick N (default, --can virtual):
//   plant endpoint: SensorSample s = plant.sample(); sensor frame N (+ current
//                   monitor every 5th tick) -> bus
//   controller node: receives/decodes frame N, Controller::step, actuator frame N
//   plant endpoint: receives actuator frame N (E2E + counter must answer N),
//                   plant.apply() (ZOH), plant.advance_tick() (RK4 sub-steps)
// Everything runs on one thread: deterministic, same seed -> same CSV.
// --mode realtime paces the ticks with a timerfd (PeriodicTimer) instead.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "maglev/bench/axes.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/plant/as_built.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

enum class Mode : std::uint8_t { kLockstep = 0, kRealtime = 1 };

struct RunOptions {
  std::optional<hil::KernelKind> kernel;  // overrides the scenario's `kernel`
  std::string can = "virtual";            // "virtual" or a SocketCAN interface
  Mode mode = Mode::kLockstep;
  std::optional<std::uint64_t> seed;      // overrides the scenario's `seed`
  std::optional<std::string> profile;     // overrides the scenario's `profile` (NAME or FILE)
  PlantOptions plant_options;             // --plant, --error-seed, --floor, --floor-isolator-hz
  // --servo-rate HZ: overrides the scenario's [controller] servo_rate_Hz and the
  // profile's rate (2500, 5000, 10000 or 20000; issue 16).
  std::optional<double> servo_rate_Hz;
  bool verbose = true;                    // print command results while running
  // Fault injection and judging (maglev-hil campaign); nullptr: none. Only
  // the in-process run with --can virtual takes hooks.
  class RunHooks* hooks = nullptr;
  // Non-empty: run() writes every frame on the bus to this file as a candump
  // log (candump_log.hpp), stamped with the tick's simulated time.
  std::string can_log;
  // --calibrate: a coupling correction loaded into the kernel's configuration
  // before the run (as from the persisted configuration at boot); nullopt: none.
  std::optional<kernel::CouplingCorrection> coupling;
};

// The recorded time series: one row per servo tick (SI units). Every
// per-axis array is indexed by the kernel's Axis (axes.hpp: index(a)).
struct Trace {
  std::vector<double> t_s;
  std::vector<double> pose[kAxes];       // measured by the kernel (m, rad)
  std::vector<double> reference[kAxes];  // kernel references (m, rad)
  std::vector<double> current_cmd_A[8];
  std::vector<double> current_A[8];      // actual coil currents (plant)
  std::vector<double> effort_A[kAxes];   // kernel efforts
  std::vector<double> disturbance_A[kAxes];  // injected bench excitation
  std::vector<int> state;                // kernel::SequencerState
  std::size_t size() const { return t_s.size(); }
};

struct CommandLog {
  double t_s;
  std::string text;
  std::string result;
  bool accepted;
};

struct RunResult {
  std::string name;
  std::string title;
  std::string kernel;
  std::string profile;
  std::uint64_t seed = 0;
  Trace trace;
  std::map<std::string, double> metrics;  // flat, SI units in the names
  std::map<std::string, double> paper;    // the scenario's [paper] values
  bool noise_fitted = false;  // Overrides::noise_fitted: rest noise matches the paper by construction
  std::vector<CommandLog> commands;
  std::vector<std::string> warnings;
  double wall_s = 0.0;
  double real_time_factor = 0.0;
  // The run loop's CPU time (this thread's; 0 when not measured): on a shared
  // machine simulated s / cpu_s is the factor the loop reaches on a core of
  // its own (printed on the summary line, not in metrics.json).
  double cpu_s = 0.0;
  double bus_load_percent = 0.0;
  std::uint64_t ticks = 0;
  std::string final_state;
  std::string fault;
  bool completed = false;  // ran to duration_s without a link/controller failure
  // The kernel's coupling correction at the end (what a calibration stored).
  kernel::CouplingCorrection coupling{};
};

// Runs one scenario. Errors in the scenario come back in *errors (nothing ran).
std::optional<RunResult> run(const scenario::Scenario& sc, const RunOptions& opt,
                             std::vector<ScenarioError>* errors);

// ---- two-process mode (docs/BENCH.md) ----------------------------------------
struct PlantProcessOptions {
  // The controller process's record (its --out DIR + "/controller_record.bin"):
  // the kernel-side trace columns. Read after the shutdown command is acked.
  std::string controller_record;
  double record_wait_s = 30.0;
  double controller_wait_s = 60.0;  // for the controller's start-up heartbeat
  std::uint32_t lockstep_timeout_us = 200000;  // wait for actuator frame N
};
// The plant side alone over a CAN interface: the scenario's plant, its
// timeline sent as host_command frames, lockstep. Results as for run().
std::optional<RunResult> run_plant_process(const scenario::Scenario& sc, const RunOptions& opt,
                                           const PlantProcessOptions& po, std::vector<ScenarioError>* errors);

struct ControllerProcessOptions {
  std::string can;
  hil::KernelKind kernel = hil::KernelKind::kFloat32;
  kernel::KernelConfig config = kernel::default_kernel_config();
  double duration_s = 0.0;  // 0: until a shutdown host command or SIGTERM/SIGINT
  std::string out_dir;      // writes out_dir/controller_record.bin when it stops
  bool levitate = false;    // levitate on the first tick (without a plant timeline)
};
// The controller node alone over a CAN interface, executing host commands.
int run_controller_process(const ControllerProcessOptions& o);

// The [controller] overrides and kernel kind of a scenario (for the controller
// process, which gets its configuration from the scenario file, not over CAN).
bool controller_config_of(const scenario::Scenario& sc, kernel::KernelConfig* config, hil::KernelKind* kind,
                          std::vector<ScenarioError>* errors);

}  // namespace maglev::bench
