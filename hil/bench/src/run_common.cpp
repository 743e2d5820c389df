#include "internal/run_common.hpp"

#include <ctime>

#include "maglev/can_port/open_can_port.hpp"

namespace maglev::bench::internal {

bool resolve_overrides(const scenario::Scenario& sc, const RunOptions& opt, Overrides* ov,
                       std::vector<ScenarioError>* errors) {
  std::vector<ScenarioError> errs = validate(sc);
  *ov = Overrides{};
  // The stage first (kernel configuration and plant from its profile), then
  // the scenario's own [plant]/[controller] keys on top.
  // The servo rate goes in with the profile: the kernel configuration is made
  // (and checked) at it, the plant steps at it. The command line wins.
  const std::optional<double> rate = opt.servo_rate_Hz ? opt.servo_rate_Hz : servo_rate_of(sc);
  if (errs.empty()) apply_profile(opt.profile ? *opt.profile : profile_of(sc), ov, &errs, rate);
  ov->command_line = opt.plant_options;
  if (errs.empty()) apply_overrides(sc, ov, &errs);
  if (!errs.empty()) {
    if (errors != nullptr) *errors = errs;
    return false;
  }
  if (opt.kernel) ov->kernel = *opt.kernel;
  if (opt.seed) ov->seed = *opt.seed;
  return true;
}

RunResult new_result(const scenario::Scenario& sc, const Overrides& ov) {
  RunResult R;
  R.name = sc.name();
  R.title = sc.scenario.count("title") ? sc.scenario.at("title") : R.name;
  R.kernel = hil::to_string(ov.kernel);
  R.profile = ov.profile_name;
  R.seed = ov.seed;
  R.paper = sc.paper;
  R.noise_fitted = ov.noise_fitted;
  // Which plant ran, and (as-built) every error drawn: reproducible from
  // error_seed. The default model adds nothing (its metrics.json is the
  // regression oracle's).
  if (ov.plant_model != hil::PlantModel::kDefault) {
    R.metrics["plant_model"] = static_cast<double>(static_cast<int>(ov.plant_model));
    R.metrics["plant_current_noise_density_A_per_rtHz"] = ov.plant.amplifier.current_noise_density_A_per_rtHz *
                                                          ov.plant.amplifier.current_noise_scale;
    R.metrics["plant_interferometer_noise_m"] = ov.plant.interferometer.noise_m;
    R.metrics["plant_displacement_noise_m"] = ov.plant.displacement.noise_m;
  }
  for (const auto& [name, value] : ov.drawn_errors) R.metrics["plant_error_" + name] = value;
  // The floor, when there is one (every run without keeps its metrics.json).
  if (ov.plant.floor.active()) {
    R.metrics["plant_floor_band_velocity_m_per_s"] = ov.plant.floor.band_velocity_m_per_s;
    R.metrics["plant_floor_isolator_hz"] = ov.plant.floor.isolator_hz;
    R.metrics["plant_floor_isolator_damping"] = ov.plant.floor.isolator_damping;
  }
  // Off only on a plant whose sensors read without noise (overrides.cpp).
  if (ov.controller.supervisor.max_identical_samples == 0) R.metrics["frozen_sample_check"] = 0.0;
  return R;
}

Link open_link(const std::string& name, bool need_controller) {
  Link l;
  if (name == "virtual") {
    // Not the process-wide named registry: runs in one process never hear
    // each other and nothing outlives the run.
    // One thread (bench::run's lockstep loop) uses both ports: no locks.
    l.bus = std::make_shared<can::VirtualBus>("maglev-hil", can::VirtualBus::Threading::kOneThread);
    l.plant_port = l.bus->open_endpoint();
    if (need_controller) l.ctrl_port = l.bus->open_endpoint();
  } else {
    l.plant_port = can::open_can_port(name, &l.error);
    if (l.plant_port && need_controller) l.ctrl_port = can::open_can_port(name, &l.error);
  }
  return l;
}

std::uint64_t CanLogTap::tick_time_us(std::uint64_t n) const {
  // Every offered rate's period is a whole number of microseconds (400, 200,
  // 100, 50 us), so no rounding enters the log.
  return n * period_us;
}

void CanLogTap::drain(std::uint64_t n) {
  if (!port) return;
  can::CanFrame f{};
  while (port->receive(f, 0) == can::PortStatus::kOk) log.write(tick_time_us(n), f);
}

bool open_can_log(const Link& link, const std::string& can_name, const std::string& path, CanLogTap* tap,
                  std::string* error) {
  if (link.bus) {
    // Deep enough for far more than one tick's frames: drained every tick.
    tap->port = link.bus->open_endpoint();
  } else {
    tap->port = can::open_can_port(can_name, error);
  }
  if (!tap->port) return false;
  if (!tap->log.open(path, can_name, error)) {
    tap->port.reset();
    return false;
  }
  return true;
}

double thread_cpu_s() {
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) return 0.0;
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double set_run_timing(RunResult* R, double wall_s, const can::BusLoadMeter& meter, double dt) {
  R->wall_s = wall_s;
  R->ticks = R->trace.size();
  const double sim_s = static_cast<double>(R->ticks) * dt;
  R->real_time_factor = R->wall_s > 0 ? sim_s / R->wall_s : 0.0;
  R->bus_load_percent = sim_s > 0 ? 1e-4 * meter.load_ppm(static_cast<std::uint64_t>(sim_s * 1e9)) : 0.0;
  return sim_s;
}

void mark_refused_actions(const std::vector<CommandLog>& commands, std::vector<TimelineAction>* actions) {
  for (std::size_t i = 0; i < commands.size() && i < actions->size(); ++i) (*actions)[i].refused = !commands[i].accepted;
}

void add_run_metrics(RunResult* R, const can::BusLoadMeter& meter, double sim_s, const LinkTotals& l) {
  auto& M = R->metrics;
  M["real_time_factor"] = R->real_time_factor;
  M["wall_time_per_tick_us"] = R->ticks > 0 ? 1e6 * R->wall_s / static_cast<double>(R->ticks) : 0.0;
  M["bus_load_percent"] = R->bus_load_percent;
  M["bus_frames"] = static_cast<double>(meter.frames());
  M["ticks"] = static_cast<double>(R->ticks);
  M["simulated_time_s"] = sim_s;
  M["missed_actuator_frames"] = static_cast<double>(l.missed_actuator_frames);
  M["controller_rx_rejected_frames"] = static_cast<double>(l.controller_rx_rejected);
  M["plant_rx_rejected_frames"] = static_cast<double>(l.plant_rx_rejected);
  M["final_sequencer_state"] = l.final_sequencer_state;
  M["fault_code"] = l.fault_code;
  M["completed"] = R->completed ? 1.0 : 0.0;
}

void add_realtime_metrics(const can::PeriodicTimer& timer, std::map<std::string, double>* M) {
  const can::JitterHistogram& j = timer.jitter();
  (*M)["realtime_deadline_misses"] = static_cast<double>(timer.deadline_misses());
  (*M)["realtime_max_lateness_us"] = static_cast<double>(j.max_ns) * 1e-3;
  (*M)["realtime_mean_lateness_us"] = j.samples > 0 ? j.sum_ns * 1e-3 / static_cast<double>(j.samples) : 0.0;
  for (std::size_t b = 0; b < j.counts.size(); ++b) {
    const std::string name = b < can::JitterHistogram::kEdges_us.size()
                                 ? "realtime_lateness_le_" + std::to_string(can::JitterHistogram::kEdges_us[b]) + "us_ticks"
                                 : "realtime_lateness_gt_" + std::to_string(can::JitterHistogram::kEdges_us.back()) + "us_ticks";
    (*M)[name] = static_cast<double>(j.counts[b]);
  }
}

void resize_rows(Trace* tr, std::size_t n) {
  tr->t_s.resize(n);
  for (int i = 0; i < kAxes; ++i) {
    tr->pose[i].resize(n);
    tr->reference[i].resize(n);
    tr->effort_A[i].resize(n);
    tr->disturbance_A[i].resize(n);
  }
  for (int j = 0; j < 8; ++j) {
    tr->current_cmd_A[j].resize(n);
    tr->current_A[j].resize(n);
  }
  tr->state.resize(n);
}

void height_sensor_centroid_m(const kernel::KernelConfig& config, double out[2]) {
  out[0] = out[1] = 0.0;
  // Relative to the point where the kernel measures z: with lds_z_point = 1
  // its z already is the sensors' mean.
  if (config.measurement.lds_z_point == 1) return;
  kernel::HeightSensorCentroid(config.measurement, &out[0], &out[1]);
}

void platen_centre_m(const hil::Plant& plant, double out[2]) {
  const hil::PlantState& truth = plant.truth();
  const auto& ab = plant.config().as_built;
  for (int a = 0; a < 2; ++a) out[a] = truth.position_m[a] - (ab.active ? ab.com_offset_m[a] : 0.0);
}

void add_homing_metrics(const double pose_xy_m[2], const double centre_xy_m[2], std::map<std::string, double>* M) {
  (*M)["homing_error_x_m"] = pose_xy_m[0] - centre_xy_m[0];
  (*M)["homing_error_y_m"] = pose_xy_m[1] - centre_xy_m[1];
}

}  // namespace maglev::bench::internal
