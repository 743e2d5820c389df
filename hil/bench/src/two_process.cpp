// The two-process executor: the plant process (plant + plant endpoint +
// the timeline as host_command frames) and the controller process (the
// controller node executing them), over any CAN interface.
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>

#include "internal/run_common.hpp"
#include "maglev/bench/metrics_registry.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/can_link/link_budget.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/lockstep/actuator_watchdog.hpp"
#include "maglev/lockstep/plant_endpoint.hpp"

namespace maglev::bench {

// ------------------------------------------------------- two-process mode
// The plant process runs the plant endpoint of run() tick for tick and sends
// the timeline as host_command frames; the controller process runs
// ControllerNode over CanServoIo. Command N goes out before sensor frame N,
// the controller drains it before it steps on that frame (one socket, FIFO),
// so it is applied at the same tick as run() applies it in process, and its
// arguments are IEEE binary64 on the wire: the same MotionCommand bits.
// The kernel-side trace columns come from the controller's own per-tick
// record (written at shutdown, like the board's Recorder dump), the plant
// columns from the plant: trace.csv equals run()'s byte for byte.
namespace {

constexpr std::uint32_t kRecordMagic = 0x4D4C5231;  // "MLR1"
constexpr int kRecordDoubles = 3 * kAxes + 8;  // pose, reference, effort (kernel Axis order), coil current cmd

struct RecordHeader {
  std::uint32_t magic = kRecordMagic;
  std::uint32_t rx_rejected = 0;
  std::uint64_t rows = 0;
  std::uint32_t final_state = 0;
  std::uint32_t fault = 0;
  std::uint32_t host_commands = 0;
  std::uint32_t tx_frames = 0;
};

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void on_stop_signal(int) { g_stop_signal = 1; }

bool write_record(const std::string& path, const RecordHeader& h, const std::vector<double>& rows,
                  const std::vector<std::int32_t>& states) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (f == nullptr) return false;
  bool ok = std::fwrite(&h, sizeof h, 1, f) == 1;
  ok = ok && (rows.empty() || std::fwrite(rows.data(), sizeof(double), rows.size(), f) == rows.size());
  ok = ok && (states.empty() || std::fwrite(states.data(), sizeof(std::int32_t), states.size(), f) == states.size());
  ok = std::fclose(f) == 0 && ok;
  return ok && std::rename(tmp.c_str(), path.c_str()) == 0;  // atomic: the plant never sees half a file
}

bool read_record(const std::string& path, RecordHeader* h, std::vector<double>* rows, std::vector<std::int32_t>* states) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return false;
  bool ok = std::fread(h, sizeof *h, 1, f) == 1 && h->magic == kRecordMagic;
  if (ok) {
    rows->resize(h->rows * kRecordDoubles);
    states->resize(h->rows);
    ok = (rows->empty() || std::fread(rows->data(), sizeof(double), rows->size(), f) == rows->size()) &&
         (states->empty() || std::fread(states->data(), sizeof(std::int32_t), states->size(), f) == states->size());
  }
  std::fclose(f);
  return ok;
}

}  // namespace

namespace {
// The two-process bench runs over a real (or virtual) CAN FD bus: a servo rate
// whose periodic frames would take more than can::kLinkUsableFraction of it is
// refused (docs/CAN.md "Bus budget"), not run late.
bool link_carries(double servo_rate_Hz, std::string* why) {
  const double max_Hz = can::max_servo_rate_Hz();
  if (servo_rate_Hz <= max_Hz) return true;
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "servo rate %.0f Hz: the CAN FD link (1 Mbit/s nominal, 5 Mbit/s data) carries the servo frames "
                "of at most %.0f Hz at %.0f %% bus load (docs/CAN.md \"Bus budget\"); run %.0f Hz in process "
                "(maglev-hil run --servo-rate)",
                servo_rate_Hz, std::floor(max_Hz), 100.0 * can::kLinkUsableFraction, servo_rate_Hz);
  *why = buf;
  return false;
}
}  // namespace

std::optional<RunResult> run_plant_process(const scenario::Scenario& sc, const RunOptions& opt,
                                           const PlantProcessOptions& po, std::vector<ScenarioError>* errors) {
  auto fail = [&](const std::string& m) -> std::optional<RunResult> {
    if (errors != nullptr) errors->push_back({m});
    return std::nullopt;
  };
  Overrides ov;
  if (!internal::resolve_overrides(sc, opt, &ov, errors)) return std::nullopt;
  std::vector<TimelineAction> actions;
  std::vector<std::string> unused;
  (void)parse_timeline(sc, &actions, &unused);  // validate() vetted every line
  for (const auto& a : actions) {
    if (a.kind == TimelineAction::Kind::kBenchExcite) {
      return fail(sc.source + ":" + std::to_string(a.line) +
                  ": 'excite' is a bench disturbance computed from the controller's pose every tick: in-process only");
    }
  }
  const double rate_Hz = static_cast<double>(ov.controller.servo_rate_Hz);
  if (std::string why; !link_carries(rate_Hz, &why)) return fail(why);
  internal::Link link = internal::open_link(opt.can, false);
  if (!link.plant_port) return fail("cannot open CAN '" + opt.can + "': " + link.error);

  RunResult R = internal::new_result(sc, ov);
  hil::Plant plant(ov.plant, ov.seed);
  can::BusLoadMeter meter;  // every frame on the bus: sent here + received from the controller
  lockstep::PlantEndpoint endpoint(*link.plant_port, &meter, lockstep::PlantEndpoint::Config{true});
  const double dt = 1.0 / rate_Hz;
  can::PeriodicTimer timer(static_cast<std::uint64_t>(std::llround(1e9 * dt)));
  const bool paced = opt.mode == Mode::kRealtime && timer.ok() && timer.start();
  const auto n_ticks = static_cast<std::uint64_t>(std::llround(sc.duration_s() / dt));
  Trace& tr = R.trace;
  std::vector<double> current_A[8];
  std::vector<double> centre_x_m, centre_y_m;  // the platen's centre after each tick (homing metrics)
  lockstep::ActuatorWatchdog watchdog;  // the amplifier board's command watchdog
  std::uint64_t missed = 0;
  std::uint8_t cmd_counter = 0;
  std::uint16_t seq = 0;
  std::map<std::uint16_t, std::size_t> pending;  // command seq -> R.commands index
  std::size_t next_action = 0;
  double levitate_t = -1.0;
  bool shutdown_acked = false;
  bool controller_up = false;

  endpoint.set_other_frame_handler([&](const can::Message& m, const can::CanFrame& in) {
    if (&m == &can::message(can::MessageKind::kHeartbeatController)) controller_up = true;
    if (&m != &can::message(can::MessageKind::kHostCommandAck)) return;
    can::HostCommandAckFrame ack{};
    can::decode_host_command_ack(in, ack);
    if (ack.code == can::HostCommandCode::kShutdown) shutdown_acked = true;
    const auto it = pending.find(ack.seq);
    if (it == pending.end()) return;
    CommandLog& log = R.commands[it->second];
    const auto r = static_cast<kernel::CommandResult>(ack.result);
    log.result = ack.result == can::kHostResultNotExecuted ? "not executed" : hil::to_string(r);
    log.accepted = r == kernel::CommandResult::kAccepted;
    if (opt.verbose) std::printf("  t=%7.3f s  %-40s -> %s\n", log.t_s, log.text.c_str(), log.result.c_str());
    pending.erase(it);
  });
  auto send_command = [&](can::HostCommandFrame h) {
    h.seq = ++seq;
    can::CanFrame f{};
    can::encode_host_command(h, cmd_counter++, f);
    (void)endpoint.send(f);
    return h.seq;
  };

  // The controller announces itself (heartbeat, node_state init) once its
  // socket is open: tick 0 is not sent into the void.
  {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(po.controller_wait_s);
    while (!controller_up && std::chrono::steady_clock::now() < until) (void)endpoint.poll(10000);
    if (!controller_up) {
      return fail("no controller on CAN '" + opt.can + "' (no heartbeat_controller within " +
                  std::to_string(po.controller_wait_s) + " s): start 'maglev-hil controller' first");
    }
  }
  const auto wall0 = std::chrono::steady_clock::now();
  for (std::uint64_t n = 0; n < n_ticks; ++n) {
    const double t = static_cast<double>(n) * dt;
    while (next_action < actions.size() && actions[next_action].t_s <= t + 0.5 * dt) {
      const TimelineAction& a = actions[next_action++];
      const std::uint16_t s = send_command(a.command);
      if (a.is(can::HostCommandCode::kLevitate) && levitate_t < 0) levitate_t = t;
      pending[s] = R.commands.size();
      R.commands.push_back(CommandLog{t, a.text, "no answer", false});
    }
    if (paced) timer.wait();
    const io::SensorSample s = plant.sample();
    const hil::PlantState truth_before = plant.truth();
    const std::uint8_t counter = endpoint.send_tick(n, t, s);
    io::ActuatorCommand received{};
    const bool got = endpoint.await_actuator(counter, paced ? 1000u : po.lockstep_timeout_us, &received);
    if (!got) ++missed;
    plant.apply(watchdog.update(got, received));  // hold <= 10 ms, then amplifiers off
    plant.advance_tick();
    double centre[2];
    internal::platen_centre_m(plant, centre);  // as the in-process runner reads it, after the tick
    centre_x_m.push_back(centre[0]);
    centre_y_m.push_back(centre[1]);
    tr.t_s.push_back(t);
    for (int j = 0; j < 8; ++j) current_A[j].push_back(truth_before.coil_current_A[j]);
  }
  const auto wall1 = std::chrono::steady_clock::now();

  // Stop the controller and collect its record.
  (void)send_command(can::make_host_command(can::HostCommandCode::kShutdown, 0));
  {
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (!shutdown_acked && std::chrono::steady_clock::now() < until) (void)endpoint.poll(10000);
  }
  RecordHeader rh{};
  std::vector<double> rows;
  std::vector<std::int32_t> states;
  bool have_record = false;
  if (!po.controller_record.empty()) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(po.record_wait_s);
    while (!(have_record = read_record(po.controller_record, &rh, &rows, &states)) &&
           std::chrono::steady_clock::now() < until) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  if (!have_record) {
    R.warnings.push_back("no controller record at '" + po.controller_record +
                         "': kernel-side trace columns are zero (give the controller --out)");
  } else if (rh.rows != tr.size()) {
    R.warnings.push_back("controller record has " + std::to_string(rh.rows) + " ticks, the plant ran " +
                         std::to_string(tr.size()));
  }
  double ready_t = -1.0;
  double homed_pose_m[2] = {0.0, 0.0}, homed_centre_m[2] = {0.0, 0.0};
  bool homed_seen = false;
  for (std::size_t n = 0; n < tr.size(); ++n) {
    const bool have = have_record && n < rh.rows;
    const double* row = have ? &rows[n * kRecordDoubles] : nullptr;
    for (int i = 0; i < kAxes; ++i) {
      tr.pose[i].push_back(have ? row[i] : 0.0);
      tr.reference[i].push_back(have ? row[kAxes + i] : 0.0);
      tr.effort_A[i].push_back(have ? row[2 * kAxes + i] : 0.0);
      tr.disturbance_A[i].push_back(0.0);
    }
    for (int j = 0; j < 8; ++j) {
      tr.current_cmd_A[j].push_back(have ? row[3 * kAxes + j] : 0.0);
      tr.current_A[j].push_back(current_A[j][n]);
    }
    const int st = have ? states[n] : 0;
    tr.state.push_back(st);
    if (!homed_seen && have && st == static_cast<int>(kernel::SequencerState::kInPlaneLock)) {
      homed_seen = true;
      homed_pose_m[0] = row[0];  // the record's pose columns: x, y first (Axis order)
      homed_pose_m[1] = row[1];
      homed_centre_m[0] = centre_x_m[n];
      homed_centre_m[1] = centre_y_m[n];
    }
    if (ready_t < 0 && st == static_cast<int>(kernel::SequencerState::kReady)) ready_t = tr.t_s[n];
  }
  const double sim_s = internal::set_run_timing(&R, std::chrono::duration<double>(wall1 - wall0).count(), meter, dt);
  const auto final_state = static_cast<kernel::SequencerState>(have_record ? rh.final_state : 0u);
  R.final_state = have_record ? hil::to_string(final_state) : "unknown";
  R.fault = std::to_string(have_record ? rh.fault : 0u);
  R.completed = have_record && rh.rows == tr.size() && missed == 0;
  auto& M = R.metrics;
  internal::add_run_metrics(&R, meter, sim_s,
                            internal::LinkTotals{missed, rh.rx_rejected, endpoint.receiver().stats().rejected_total(),
                                                 static_cast<double>(rh.final_state), static_cast<double>(rh.fault)});
  M["host_commands_acked"] = static_cast<double>(R.commands.size() - pending.size());
  if (homed_seen) internal::add_homing_metrics(homed_pose_m, homed_centre_m, &M);
  if (paced) internal::add_realtime_metrics(timer, &M);
  internal::mark_refused_actions(R.commands, &actions);
  MetricInputs mi{actions, tr, {}, levitate_t, ready_t, sc.duration_s(), rate_Hz};
  internal::height_sensor_centroid_m(ov.controller, mi.height_sensor_centroid_m);
  compute_metrics(sc, mi, &M, &R.warnings);
  if (!pending.empty()) R.warnings.push_back(std::to_string(pending.size()) + " host command(s) never acknowledged");
  return R;
}

bool controller_config_of(const scenario::Scenario& sc, kernel::KernelConfig* config, hil::KernelKind* kind,
                          std::vector<ScenarioError>* errors) {
  std::vector<ScenarioError> errs;
  Overrides ov;
  if (apply_profile(profile_of(sc), &ov, &errs, servo_rate_of(sc))) apply_overrides(sc, &ov, &errs);
  if (std::string why; errs.empty() && !link_carries(static_cast<double>(ov.controller.servo_rate_Hz), &why)) {
    errs.push_back({sc.source + ": " + why});
  }
  if (!errs.empty()) {
    if (errors != nullptr) *errors = errs;
    return false;
  }
  *config = ov.controller;
  *kind = ov.kernel;
  return true;
}

int run_controller_process(const ControllerProcessOptions& o) {
  internal::Link link = internal::open_link(o.can, false);
  if (!link.plant_port) {
    std::fprintf(stderr, "cannot open CAN '%s': %s\n", o.can.c_str(), link.error.c_str());
    return 1;
  }
  can::BusLoadMeter meter;
  hil::CanServoIo cio(*link.plant_port, &meter, static_cast<double>(o.config.servo_rate_Hz));
  hil::ControllerNode node(o.kernel, cio);
  if (node.apply_config(o.config) != kernel::ConfigError::kOk) {
    std::fprintf(stderr, "controller: configuration refused by the kernel\n");
    return 2;
  }
  g_stop_signal = 0;
  std::signal(SIGTERM, on_stop_signal);
  std::signal(SIGINT, on_stop_signal);
  cio.announce();
  std::vector<double> rows;
  std::vector<std::int32_t> states;
  bool levitate_sent = false;
  const auto t0 = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point first_tick{};
  const char* why = "signal";
  // A row per tick, the ticks that stand in for lost sensor frames included
  // (ControllerNode::run_once): the record stays on the plant's tick.
  if (!o.out_dir.empty()) {
    node.after_tick = [&]() {
      const auto& st = node.status();
      for (Axis a : kernel::kAllAxes) rows.push_back(pose_si(st.pose, a));
      for (Axis a : kernel::kAllAxes) rows.push_back(pose_si(st.reference, a));
      for (Axis a : kernel::kAllAxes) rows.push_back(static_cast<double>(st.effort_A[index(a)]));
      for (int j = 0; j < 8; ++j) rows.push_back(static_cast<double>(st.coil_current_A[j]));
      states.push_back(static_cast<std::int32_t>(st.state));
    };
  }
  for (;;) {
    if (g_stop_signal != 0) break;
    const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (o.duration_s > 0 && el > o.duration_s) {
      why = "duration";
      break;
    }
    // Silence for kSilence_us once ticking: a stale tick (4 of them, ~2 s,
    // and the frame watchdog lands the stage). Longer than the plant's
    // lockstep wait for an actuator frame (200 ms), so that a lost frame is
    // caught up by its successor's counter, never by this timeout.
    constexpr std::uint32_t kSilence_us = 500000;
    const bool ran = node.run_once(kSilence_us, node.ticks() > 0);
    if (cio.stop_requested()) {
      why = "shutdown command";
      break;
    }
    if (!ran) continue;
    if (node.ticks() == 1) first_tick = std::chrono::steady_clock::now();
    if (o.levitate && !levitate_sent) {
      kernel::MotionCommand c;
      c.type = kernel::MotionType::kLevitate;
      std::printf("controller: levitate -> %s\n", hil::to_string(node.command(c)));
      levitate_sent = true;
    }
  }
  const double active_s =
      node.ticks() > 0 ? std::chrono::duration<double>(std::chrono::steady_clock::now() - first_tick).count() : 0.0;
  const auto& st = node.status();
  std::printf("controller: stopped by %s; %llu ticks (%.0f ticks/s), state %s, z = %.3f um, fault %d, "
              "rx rejected %u, host commands %u\n",
              why, static_cast<unsigned long long>(node.ticks()),
              active_s > 0 ? static_cast<double>(node.ticks()) / active_s : 0.0, hil::to_string(st.state),
              static_cast<double>(st.pose[maglev::kernel::Axis::kZ]) * 1e-6, static_cast<int>(st.fault), cio.rx_stats().rejected_total(),
              node.link_stats().host_commands);
  if (!o.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.out_dir, ec);
    RecordHeader h{};
    h.rx_rejected = cio.rx_stats().rejected_total();
    h.rows = states.size();
    h.final_state = static_cast<std::uint32_t>(st.state);
    h.fault = static_cast<std::uint32_t>(st.fault);
    h.host_commands = node.link_stats().host_commands;
    h.tx_frames = static_cast<std::uint32_t>(meter.frames());
    const std::string path = o.out_dir + "/controller_record.bin";
    if (!write_record(path, h, rows, states)) {
      std::fprintf(stderr, "controller: cannot write %s\n", path.c_str());
      return 1;
    }
  }
  return node.ticks() > 0 ? 0 : 1;
}

}  // namespace maglev::bench
