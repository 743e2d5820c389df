// The in-process executor: plant, plant endpoint, controller node and the
// bench's own disturbance on one thread, lockstep (or paced in real time).
#include "maglev/bench/runner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "internal/run_common.hpp"
#include "maglev/motion_commands/to_motion_command.hpp"
#include "maglev/bench/metrics_registry.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/bench/run_hooks.hpp"
#include "maglev/lockstep/actuator_watchdog.hpp"
#include "maglev/lockstep/plant_endpoint.hpp"
#include "maglev/plant/plant.hpp"

namespace maglev::bench {

namespace {

// The bench multisine as coil currents added to the controller's DAC codes,
// through the kernel's own allocation at the controller's measured pose. The
// sum stays inside the stage's peak coil current (the disturbance once drove
// 5.0 A through a 4 A coil): the bench never commands what the controller may not.
class DisturbanceInjector {
 public:
  explicit DisturbanceInjector(const kernel::KernelConfig& config) {
    kernel::ForceAllocationConfig ac = config.allocation;
    ac.payload_kg = static_cast<double>(config.payload_mass_kg);
    kernel::ApplyForceAllocationConfig<float>(ac, &alloc_);
    limit_codes_ = config.allocation.peak_current_A * alloc_.dac_codes_per_A;
  }
  void add(Axis axis, double effort, const kernel::ControllerStatus& st, io::ActuatorCommand* applied) const {
    if (effort == 0.0 || !applied->amplifier_enable) return;
    float e[kAxes] = {};
    e[index(axis)] = static_cast<float>(effort);
    kernel::AllocationOutput<float> out{};
    kernel::AllocateCurrents<float>(e, st.pose[maglev::kernel::Axis::kX], st.pose[maglev::kernel::Axis::kY], alloc_, &out);
    for (int j = 0; j < 8; ++j) {
      const double code = static_cast<double>(applied->dac_code[j]) +
                          static_cast<double>(out.current_A[j]) * alloc_.dac_codes_per_A;
      applied->dac_code[j] = static_cast<std::int16_t>(std::lround(std::clamp(code, -limit_codes_, limit_codes_)));
    }
  }

 private:
  kernel::ForceAllocationState<float> alloc_{};
  double limit_codes_ = 0.0;
};

}  // namespace

std::optional<RunResult> run(const scenario::Scenario& sc, const RunOptions& opt, std::vector<ScenarioError>* errors) {
  Overrides ov;
  if (!internal::resolve_overrides(sc, opt, &ov, errors)) return std::nullopt;
  std::vector<TimelineAction> actions;
  std::vector<std::string> unused;
  (void)parse_timeline(sc, &actions, &unused);  // validate() vetted every line

  RunResult R = internal::new_result(sc, ov);
  internal::Link link = internal::open_link(opt.can, true);
  if (!link.plant_port || !link.ctrl_port) {
    if (errors != nullptr) errors->push_back({"cannot open CAN '" + opt.can + "': " + link.error});
    return std::nullopt;
  }
  const std::uint32_t rx_timeout_us = opt.can == "virtual" ? 0u : 100000u;
  RunHooks* const hooks = opt.hooks;
  if (hooks != nullptr) {
    if (!link.bus) {
      if (errors != nullptr) errors->push_back({"fault hooks need --can virtual"});
      return std::nullopt;
    }
    link.bus->set_fault_hook([hooks](const can::CanFrame& f, std::uint64_t seq) { return hooks->on_frame(f, seq); });
    hooks->attach(*link.bus);
  }
  // The configured servo rate (profile, [controller] servo_rate_Hz or
  // --servo-rate; the kernel refused anything but the offered rates).
  const double rate_Hz = static_cast<double>(ov.controller.servo_rate_Hz);
  internal::CanLogTap tap;
  tap.period_us = static_cast<std::uint64_t>(std::llround(1e6 / rate_Hz));
  if (!opt.can_log.empty()) {
    std::string err;
    if (!internal::open_can_log(link, opt.can, opt.can_log, &tap, &err)) {
      if (errors != nullptr) errors->push_back({"--can-log: " + err});
      return std::nullopt;
    }
  }

  can::BusLoadMeter meter;
  hil::Plant plant(ov.plant, ov.seed);
  lockstep::PlantEndpoint endpoint(*link.plant_port, &meter);
  hil::CanServoIo cio(*link.ctrl_port, &meter, rate_Hz);
  hil::ControllerNode node(ov.kernel, cio);
  kernel::KernelConfig boot_config = ov.controller;
  if (opt.coupling) boot_config.coupling = *opt.coupling;
  const kernel::ConfigError ce = node.apply_config(boot_config);
  if (ce != kernel::ConfigError::kOk) {
    if (errors != nullptr) {
      errors->push_back({sc.source + ": [controller] overrides refused by the kernel (ConfigError " +
                         std::to_string(static_cast<int>(ce)) + ")"});
    }
    return std::nullopt;
  }
  const DisturbanceInjector injector(ov.controller);

  const double dt = 1.0 / rate_Hz;
  const auto n_ticks = static_cast<std::uint64_t>(std::llround(sc.duration_s() / dt));
  Trace& tr = R.trace;
  internal::resize_rows(&tr, n_ticks);
  std::uint64_t rows = 0;

  std::unique_ptr<can::PeriodicTimer> timer;
  if (opt.mode == Mode::kRealtime) {
    timer = std::make_unique<can::PeriodicTimer>(static_cast<std::uint64_t>(1e9 * dt));
    if (!timer->ok() || !timer->start()) {
      if (errors != nullptr) errors->push_back({"realtime mode: timerfd unavailable"});
      return std::nullopt;
    }
  }

  std::vector<Multisine> excitations;
  std::size_t next_action = 0;
  double levitate_t = -1.0, ready_t = -1.0;
  // The homed in-plane frame against the plant's truth, on the first tick
  // after homing (the commutation's zero: 1 um of x is 0.0071 deg of phase).
  double homed_pose_m[2] = {0.0, 0.0}, homed_centre_m[2] = {0.0, 0.0};
  bool homed_seen = false;
  std::uint64_t missed_actuator = 0;
  bool aborted = false;
  lockstep::ActuatorWatchdog watchdog;  // the amplifier board's command watchdog
  const auto wall0 = std::chrono::steady_clock::now();
  const double cpu0 = internal::thread_cpu_s();

  for (std::uint64_t n = 0; n < n_ticks; ++n) {
    const double t = static_cast<double>(n) * dt;
    // --- timeline: commands reach the controller node before this tick.
    while (next_action < actions.size() && actions[next_action].t_s <= t + 0.5 * dt) {
      const TimelineAction& a = actions[next_action++];
      CommandLog log{t, a.text, "", false};
      if (a.kind == TimelineAction::Kind::kBenchExcite) {
        excitations.push_back(make_multisine(a));
        log.result = "accepted (bench: multisine disturbance effort at the plant input)";
        log.accepted = true;
      } else {
        // The board's and the two-process bench's path: host command ->
        // motion_commands::to_motion_command (relative moves on the present reference).
        kernel::MotionCommand c{};
        (void)motion_commands::to_motion_command(a.command, node.status().reference, &c);
        const kernel::CommandResult r = node.command(c);
        if (a.is(can::HostCommandCode::kLevitate) && levitate_t < 0) levitate_t = t;
        log.result = hil::to_string(r);
        log.accepted = r == kernel::CommandResult::kAccepted;
      }
      if (opt.verbose) std::printf("  t=%7.3f s  %-40s -> %s\n", t, log.text.c_str(), log.result.c_str());
      R.commands.push_back(log);
    }
    const Multisine* excite = excitations.empty() ? nullptr : &excitations.back();
    if (timer) timer->wait();

    // --- plant endpoint: sensors -> CAN. Coil currents at the sample instant.
    if (hooks != nullptr) hooks->before_tick(n, t, plant);
    io::SensorSample s = plant.sample();
    if (hooks != nullptr) hooks->on_sensor_sample(n, t, &s);
    double current_before_A[8];
    for (int j = 0; j < 8; ++j) current_before_A[j] = plant.amplifiers().current_A(j);
    const std::uint8_t counter = endpoint.send_tick(n, t, s);

    if (hooks != nullptr && hooks->config_write_due(n, t)) {
      kernel::KernelConfig next = node.config();
      hooks->make_config_write(&next);
      const kernel::ConfigError result = node.apply_config(next);
      hooks->config_result(result, node.config());
    }

    // --- controller node: one tick.
    // With fault hooks a lost sensor frame is a stale tick for the kernel
    // (its link-loss handling), not the end of the run.
    if (!node.run_once(rx_timeout_us, hooks != nullptr)) {
      R.warnings.push_back("controller node got no sensor frame at tick " + std::to_string(n));
      aborted = true;
      break;
    }

    // --- plant endpoint: the actuator frame answering tick n (else the
    // actuator watchdog: the last command held <= 10 ms, then amplifiers off).
    io::ActuatorCommand received{};
    const bool got = endpoint.await_actuator(counter, rx_timeout_us, &received);
    if (!got) ++missed_actuator;
    io::ActuatorCommand applied = watchdog.update(got, received);
    const Axis ex_axis = excite != nullptr ? excite->axis : Axis::kX;
    const double d_ex = excite != nullptr ? excite->value(t) : 0.0;
    injector.add(ex_axis, d_ex, node.status(), &applied);
    if (hooks != nullptr) hooks->on_actuator(n, t, &applied);
    plant.apply(applied);
    plant.advance_tick();
    if (hooks != nullptr) hooks->after_tick(n, t, plant, node.status());
    tap.drain(n);  // this tick's frames, in bus order

    // --- record this tick (pose measured at t, currents at t).
    const auto& st = node.status();
    tr.t_s[n] = t;
    for (Axis a : kernel::kAllAxes) {
      tr.pose[index(a)][n] = pose_si(st.pose, a);
      tr.reference[index(a)][n] = pose_si(st.reference, a);
      tr.effort_A[index(a)][n] = static_cast<double>(st.effort_A[index(a)]);
      tr.disturbance_A[index(a)][n] = a == ex_axis ? d_ex : 0.0;
    }
    for (int j = 0; j < 8; ++j) {
      tr.current_cmd_A[j][n] = static_cast<double>(st.coil_current_A[j]);
      tr.current_A[j][n] = current_before_A[j];
    }
    tr.state[n] = static_cast<int>(st.state);
    rows = n + 1;
    if (ready_t < 0 && st.state == kernel::SequencerState::kReady) ready_t = t;
    if (!homed_seen && st.state == kernel::SequencerState::kInPlaneLock) {
      homed_seen = true;
      homed_pose_m[0] = pose_si(st.pose, Axis::kX);
      homed_pose_m[1] = pose_si(st.pose, Axis::kY);
      internal::platen_centre_m(plant, homed_centre_m);
    }
  }
  const auto wall1 = std::chrono::steady_clock::now();
  R.cpu_s = internal::thread_cpu_s() - cpu0;
  internal::resize_rows(&tr, rows);  // an aborted run keeps the rows it recorded
  if (tap.port) {
    std::string err;
    if (!tap.log.close(&err)) {
      R.warnings.push_back(err);
      aborted = true;  // a run asked for its log and did not get it
    }
  }
  const double sim_s = internal::set_run_timing(&R, std::chrono::duration<double>(wall1 - wall0).count(), meter, dt);
  R.final_state = hil::to_string(node.status().state);
  R.fault = std::to_string(static_cast<int>(node.status().fault));
  R.completed = !aborted;
  internal::add_run_metrics(&R, meter, sim_s,
                            internal::LinkTotals{missed_actuator, cio.rx_stats().rejected_total(),
                                                 endpoint.receiver().stats().rejected_total(),
                                                 static_cast<double>(static_cast<int>(node.status().state)),
                                                 static_cast<double>(static_cast<int>(node.status().fault))});
  if (timer) internal::add_realtime_metrics(*timer, &R.metrics);
  // Coupling calibration (issue 15): only when one ran or a correction was
  // loaded, so other runs' metrics.json keep their keys.
  // Only off the default rate, so the default runs' metrics.json keep their keys.
  if (rate_Hz != io::stage::kServoRate_Hz) {
    R.metrics["servo_rate_Hz"] = rate_Hz;
    R.metrics["plant_substeps_per_tick"] = static_cast<double>(ov.plant.integration.substeps_per_tick);
  }
  if (homed_seen) internal::add_homing_metrics(homed_pose_m, homed_centre_m, &R.metrics);
  R.coupling = node.config().coupling;
  const kernel::ControllerStatus& fin = node.status();
  if (opt.coupling) R.metrics["coupling_correction_loaded"] = opt.coupling->enabled;
  // LDS target steps repaired (issue 15): only when there were any, so the
  // runs on a flat target keep their keys.
  if (fin.lds_target_steps != 0) R.metrics["lds_target_steps_repaired"] = static_cast<double>(fin.lds_target_steps);
  if (fin.calibration_result != kernel::CouplingCalibrationResult::kNone) {
    R.metrics["calibration_result"] = static_cast<double>(static_cast<int>(fin.calibration_result));
    R.metrics["calibration_coupling_before"] = static_cast<double>(fin.calibration_coupling_before);
    R.metrics["calibration_coupling_after"] = static_cast<double>(fin.calibration_coupling_after);
    R.metrics["calibration_inconsistency"] = static_cast<double>(fin.calibration_inconsistency);
    // The correction the kernel holds at the end (row-major, Axis order):
    // what a user checks before saving it.
    for (int i = 0; i < kernel::kCouplingMatrixSize; ++i) {
      R.metrics["coupling_correction_" + std::to_string(i / kernel::kAxisCount) + std::to_string(i % kernel::kAxisCount)] =
          static_cast<double>(R.coupling.matrix[i]);
    }
  }
  internal::mark_refused_actions(R.commands, &actions);
  MetricInputs mi{actions, tr, excitations, levitate_t, ready_t, sc.duration_s(), rate_Hz};
  internal::height_sensor_centroid_m(ov.controller, mi.height_sensor_centroid_m);
  compute_metrics(sc, mi, &R.metrics, &R.warnings);
  return R;
}

}  // namespace maglev::bench
