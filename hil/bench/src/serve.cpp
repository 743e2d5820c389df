// maglev-hil serve --modbus-tcp HOST:PORT [--kernel float32|q7.24] [--flash FILE]
//                  [--scenario NAME|FILE] [--seed N] [--duration S] [--scenarios DIR]
//                  [--plant MODEL] [--error-seed N] [--floor CLASS] [--floor-isolator-hz HZ]
//
// The simulated stage running in REAL TIME, operated over Modbus TCP like the
// real controller. One thread, one loop, per servo period (the flash's servo.rate: 400 us at 2.5 kHz):
//
//   plant endpoint   Plant::sample() -> sensor frame N (+ current_monitor every
//                    5th tick, heartbeat_plant every 250th) on the virtual CAN bus
//   controller       app::ServoLoop<kernel::Controller<Scalar>>::on_tick() with
//                    app::CanSensorSource / app::CanActuatorSink: the firmware's
//                    own servo application and CAN I/O (firmware/app)
//   plant endpoint   actuator frame N (E2E + counter) -> Plant::apply(), advance
//   Modbus           BenchServer::poll(0): requests already waiting go through
//                    the firmware's RegisterServer + ControllerDevice<Scalar>
//                    (the same objects the board's RTU server drives) -- BETWEEN
//                    ticks, so no lock is needed and a request sees a whole tick
//   sleep            clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME) to the next
//                    absolute deadline t0 + (N+1) * period
//
// A tick whose work (servo + plant + Modbus) ends after its deadline counts as
// a deadline miss; the loop then runs the next tick at once (catching up, so
// simulated time keeps pace with wall time). Behind by more than kResyncTicks
// periods, it re-anchors the schedule (counted as a resync) instead of
// bursting.
//
// Status line to stderr once per second; stops on SIGINT/SIGTERM or --duration.
#include "maglev/bench/serve.hpp"

#include <sched.h>
#include <sys/mman.h>
#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "maglev/app/can_io.hpp"
#include "maglev/lockstep/actuator_watchdog.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/bench/units.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/plant/plant_profile.hpp"
#include "maglev/stage_profile/stage_database.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/modbus_tcp/bench_server.hpp"
#include "maglev/lab_tools/lab_registers.hpp"
#include "maglev/lab_tools/lab_tick.hpp"
#include "maglev/scenario/scenario.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

#ifndef MAGLEV_SCENARIO_DIR
#define MAGLEV_SCENARIO_DIR "hil/scenarios"
#endif

namespace maglev::bench {
namespace {

namespace fs = std::filesystem;

volatile std::sig_atomic_t g_stop = 0;

// The lab tools' memory: static, as on the board (there: .axi_bss / .bss).
float g_recorder_pool[lab::kBoardPoolWords];
float g_wave_table[lab::kWaveTableLen];
void on_signal(int) { g_stop = 1; }

constexpr std::int64_t kNsPerS = 1'000'000'000;
// Behind by more than this many periods (40 ms): re-anchor, do not burst.
constexpr std::int64_t kResyncTicks = 100;

struct ServeOptions {
  std::string host = "127.0.0.1";
  int port = -1;
  hil::KernelKind kernel = hil::KernelKind::kFloat32;
  std::string flash = "maglev-stage-flash.bin";
  std::string scenario;
  std::string scenarios = MAGLEV_SCENARIO_DIR;
  std::uint64_t seed = 1;
  bool seed_given = false;
  double duration_s = 0.0;  // 0: until SIGINT/SIGTERM
  int rt_priority = 0;      // >0: SCHED_FIFO at this priority + mlockall (a real bench PC)
  PlantOptions plant;       // --plant, --error-seed, --floor, --floor-isolator-hz (as `run`)
};

void usage() {
  std::fputs(
      "usage: maglev-hil serve --modbus-tcp HOST:PORT [--kernel float32|q7.24] [--flash FILE]\n"
      "                        [--scenario NAME|FILE] [--seed N] [--duration S] [--scenarios DIR]\n"
      "                        [--rt-priority N]\n",
      stderr);
  std::fputs(kPlantOptionsUsage, stderr);
  std::fputs(
      "  runs the simulated stage in real time (at the flash's servo.rate) and serves the register map\n"
      "  over Modbus TCP (docs/REGISTERS.md) until SIGINT/SIGTERM or --duration; PORT 0 = any free port.\n"
      "  The plant is the flash's stage (stage.profile) with the scenario's [plant] keys and the plant\n"
      "  options on top, read as `maglev-hil run` reads them (model, noise, error set, floor).\n"
      "  --scenario: the scenario's [plant] keys and seed (its timeline and [controller] keys are not\n"
      "  used: the controller's configuration is the flash's).\n"
      "  --rt-priority N: SCHED_FIFO priority N (1..99) and mlockall, fewer deadline misses.\n",
      stderr);
}

std::int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNsPerS + ts.tv_nsec;
}

std::int64_t thread_cpu_ns() {
  timespec ts{};
  (void)clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void sleep_until_ns(std::int64_t t) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t / kNsPerS);
  ts.tv_nsec = static_cast<long>(t % kNsPerS);
  // EINTR (a signal): return, the loop checks g_stop.
  (void)clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

bool parse(int argc, char** argv, ServeOptions* o) {
  std::string err;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "maglev-hil serve: %s needs a value\n", a.c_str());
      return false;
    }
    const std::string v = argv[++i];
    if (a == "--modbus-tcp") {
      const auto colon = v.rfind(':');
      if (colon == std::string::npos) {
        std::fprintf(stderr, "maglev-hil serve: --modbus-tcp HOST:PORT, got '%s'\n", v.c_str());
        return false;
      }
      o->host = v.substr(0, colon);
      char* end = nullptr;
      const long port = std::strtol(v.c_str() + colon + 1, &end, 10);
      if (end == v.c_str() + colon + 1 || *end != '\0' || port < 0 || port > 65535) {
        std::fprintf(stderr, "maglev-hil serve: bad port in '%s'\n", v.c_str());
        return false;
      }
      o->port = static_cast<int>(port);
    } else if (a == "--kernel") {
      if (!hil::parse_kernel_kind(v, &o->kernel)) {
        std::fprintf(stderr, "maglev-hil serve: --kernel float32|q7.24, got '%s'\n", v.c_str());
        return false;
      }
    } else if (a == "--flash") {
      o->flash = v;
    } else if (a == "--scenario") {
      o->scenario = v;
    } else if (a == "--scenarios") {
      o->scenarios = v;
    } else if (a == "--seed") {
      o->seed = static_cast<std::uint64_t>(std::strtoull(v.c_str(), nullptr, 10));
      o->seed_given = true;
    } else if (a == "--duration") {
      // A number of seconds, 0 = until a signal; NaN, inf, negative or
      // trailing text are refused (a NaN once ran forever).
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(d) || d < 0.0 || d > 1e7) {
        std::fprintf(stderr, "maglev-hil serve: --duration needs seconds >= 0, got '%s'\n", v.c_str());
        return false;
      }
      o->duration_s = d;
    } else if (const PlantOptionParse p = parse_plant_option(a, v, &o->plant, &err); p != PlantOptionParse::kNotPlantOption) {
      if (p == PlantOptionParse::kBad) {
        std::fprintf(stderr, "maglev-hil serve: %s\n", err.c_str());
        return false;
      }
    } else if (a == "--rt-priority") {
      o->rt_priority = std::atoi(v.c_str());
    } else {
      std::fprintf(stderr, "maglev-hil serve: unknown option '%s'\n", a.c_str());
      return false;
    }
  }
  if (o->port < 0) {
    std::fprintf(stderr, "maglev-hil serve: --modbus-tcp HOST:PORT is required\n");
    return false;
  }
  return true;
}

struct ServeCounters {
  std::uint64_t ticks = 0;
  std::uint64_t deadline_misses = 0;
  std::uint64_t resyncs = 0;
  std::uint64_t missed_actuator = 0;
  std::uint64_t modbus_requests = 0;
  std::int64_t max_work_ns = 0;
  std::int64_t sum_work_ns = 0;
  std::int64_t max_late_ns = 0;
  // The thread CPU time of one Modbus poll (what the network can add to a
  // tick's work; wall time also holds preemption by other processes).
  std::int64_t max_modbus_cpu_ns = 0;
};

template <typename Scalar>
int serve(const ServeOptions& o, const scenario::Scenario* sc) {
  using Kernel = kernel::Controller<Scalar>;
  const auto bus = std::make_shared<can::VirtualBus>("maglev-hil-serve");
  auto plant_port = bus->open_endpoint();
  auto ctrl_port = bus->open_endpoint();

  auto controller = std::make_unique<Kernel>();  // large: not on the stack
  // Boot as on the board: the configuration comes from the flash file.
  auto modbus = std::make_unique<modbus_tcp::BenchServer<Scalar>>(*controller, o.host, o.port, o.flash);
  if (!modbus->ok()) {
    std::fprintf(stderr, "maglev-hil serve: cannot serve Modbus TCP on %s:%d (flash %s): %s\n", o.host.c_str(),
                 o.port, o.flash.c_str(), modbus->error().c_str());
    return 1;
  }
  // The bench's plant is the stage the flash selects (stage.profile), as the
  // board's stage is the one wired to it. A selection the firmware refused
  // (status.profile_error) leaves the default stage's plant: the kernel
  // holds it landed with fault 18 anyway.
  // The plant of database stage `index` (index 0: the default stage's), as
  // `run` builds it: the stage's plant, then the scenario's [plant] keys and
  // the plant options (plant_for_stage: model, noise, error set, floor), at
  // the servo rate; false: *why says why.
  const auto plant_of = [sc, &controller](std::uint16_t index, double rate, const PlantOptions& options,
                                          StagePlant* out, std::string* why, const char** name) {
    static stage_profile::StageProfile profile;  // ~4 kB
    hil::PlantConfig base = hil::PlantConfig::Default();
    *name = "the default stage";
    if (index != 0) {
      if (stage_profile::LoadStageProfile(index, &profile) != stage_profile::ProfileError::kOk) {
        *why = "not in the profile database";
        return false;
      }
      if (!hil::PlantConfigForProfile(profile, hil::PlantConfig::Default(), &base, why)) return false;
      *name = profile.name;
    }
    std::vector<ScenarioError> errs;
    if (!plant_for_stage(base, controller->config(), sc, options, out, &errs)) {
      why->clear();
      for (const ScenarioError& e : errs) *why += (why->empty() ? "" : "\n") + e.message;
      return false;
    }
    hil::ApplyServoRate(rate, &out->plant);
    return true;
  };
  // Which plant, and (as-built) every error drawn: the run's metrics.json
  // plant_error_* on one line, so that a session can be reproduced.
  const auto report_plant = [](const StagePlant& p, std::uint64_t noise_seed) {
    std::printf("maglev-hil serve: plant %s, noise seed %llu", hil::to_string(p.model),
                static_cast<unsigned long long>(noise_seed));
    if (p.model == hil::PlantModel::kAsBuilt) {
      std::printf(", error seed %llu:", static_cast<unsigned long long>(p.error_set.error_seed));
      for (const auto& [name, value] : p.drawn_errors) std::printf(" %s=%.6g", name.c_str(), value);
    }
    std::printf("\n");
    std::fflush(stdout);
  };
  const auto selected_stage = [&modbus, &controller]() -> int {
    // The stage the kernel runs: the register's value once the binding took
    // it; a refused selection (status.profile_error) runs no stage at all.
    if (controller->stage_profile_error() != 0) return 0;
    return static_cast<int>(modbus->registers().config().get(modbus::RegId::stage_profile));
  };
  // The servo rate the flash's configuration selects (servo.rate): the
  // plant steps at it and the loop is paced at it. A later servo.rate write
  // (landed) re-designs the kernel; the bench then re-steps its plant and
  // re-paces its loop at the new rate, as the board re-times its tick timer
  // (firmware/board/stm32h743/src/main.cpp).
  double rate_Hz = static_cast<double>(controller->config().servo_rate_Hz);
  int plant_stage = selected_stage();
  PlantOptions plant_options = o.plant;  // what the running plant was built with (a stage swap may fall back)
  StagePlant stage_plant;
  {
    std::string why;
    const char* name = "";
    if (!plant_of(static_cast<std::uint16_t>(plant_stage), rate_Hz, o.plant, &stage_plant, &why, &name)) {
      std::fprintf(stderr, "maglev-hil serve: the bench cannot build the plant of stage.profile %d: %s\n", plant_stage,
                   why.c_str());
      return 2;
    }
    if (plant_stage != 0) {
      std::printf("maglev-hil serve: stage.profile %d (%s) from the flash: plant and kernel built from it\n",
                  plant_stage, name);
    }
  }
  // A plant whose sensors read without noise repeats every bit of a sample
  // once the loops settle, and the kernel's frozen-sample check (a real
  // stage's sensors never do that) lands it: levitating `--plant ideal`
  // faulted at once (FrozenSample, 20). `run` turns the check off for such a
  // plant; here the kernel's configuration is the flash's, which keeps it.
  if (!stage_plant.plant.sensor_noise_enabled) {
    std::fprintf(stderr,
                 "maglev-hil serve: the plant's sensors read without noise (model ideal, or sensor_noise = off): the "
                 "kernel's frozen-sample check (fault 20, FrozenSample) would land the stage once it settles, and "
                 "the flash's configuration keeps it on; use `maglev-hil run` (which turns it off for such a plant) "
                 "or serve --plant nominal\n");
    return 2;
  }
  // The noise seed: --seed, else the scenario's, else 1.
  const std::uint64_t seed = o.seed_given ? o.seed : stage_plant.seed;
  auto plant = std::make_unique<hil::Plant>(stage_plant.plant, seed);
  app::CanSensorConfig sensor_config{};
  sensor_config.period_us = static_cast<std::uint32_t>(std::lround(1e6 / rate_Hz));
  app::CanSensorSource sensors(*ctrl_port, sensor_config);
  app::CanActuatorSink actuators(*ctrl_port, sensors);
  // Lab tools (recorder, wave generator) as on the board: rec.* / wave.*
  // registers, the recorder armed in fault-watch mode from the start.
  lab::Recorder recorder(g_recorder_pool, lab::kBoardPoolWords);
  lab::WaveGenerator wave(g_wave_table, lab::kWaveTableLen);
  (void)recorder.configure(lab::fault_watch_config(controller->config().servo_rate_Hz));
  (void)recorder.arm();
  lab::LabRegisters lab_registers(recorder, wave, controller->config());
  modbus->registers().set_lab_tools(&lab_registers);
  lab::LabTick<Scalar>::bind(controller.get(), &recorder, &wave);
  app::ServoHooks servo_hooks{};
  servo_hooks.before_step = lab::LabTick<Scalar>::before_step;
  servo_hooks.record = lab::LabTick<Scalar>::record;
  app::ServoLoop<Kernel> loop(sensors, actuators, *controller, app::ServoConfig{}, servo_hooks);

  std::printf("maglev-hil serve: Modbus TCP listening on %s:%d (unit 1), kernel %s, flash %s, %.0f Hz real time\n",
              o.host.c_str(), modbus->port(), hil::to_string(o.kernel), o.flash.c_str(), rate_Hz);
  // After the listening line, which clients wait for as the first line of a
  // default stage's serve (tests/faults/hostile_levitated.py).
  report_plant(stage_plant, seed);

  // The loop's pacing at a rate: its tick, ticks per status line, wall period.
  double dt = 0.0;
  std::uint64_t ticks_per_second = 0;
  std::int64_t period_ns = 0;
  const auto pace_at = [&](double rate) {
    rate_Hz = rate;
    dt = 1.0 / rate;
    ticks_per_second = static_cast<std::uint64_t>(std::llround(rate));
    period_ns = static_cast<std::int64_t>(std::llround(1e9 * dt));
  };
  pace_at(rate_Hz);
  std::uint64_t end_tick =
      o.duration_s > 0.0 ? static_cast<std::uint64_t>(std::llround(o.duration_s / dt)) : ~std::uint64_t{0};
  // Simulated time: ticks at the rates they ran at (the rate may change).
  double t_at_retime = 0.0;
  std::uint64_t n_at_retime = 0;
  const auto sim_time = [&](std::uint64_t ticks) { return t_at_retime + static_cast<double>(ticks - n_at_retime) * dt; };
  can::LinkReceiver prx;
  lockstep::ActuatorWatchdog watchdog;  // the amplifier board's command watchdog
  std::uint8_t cm_counter = 0, hb_counter = 0;
  ServeCounters c;
  std::int64_t deadline = now_ns() + period_ns;
  const std::int64_t wall0 = now_ns();

  for (std::uint64_t n = 0; n < end_tick && g_stop == 0; ++n) {
    const std::int64_t start = now_ns();
    const double t = sim_time(n);
    // --- plant endpoint: sensors -> CAN.
    const io::SensorSample s = plant->sample();
    can::CanFrame f{};
    if (n % can::kCurrentMonitorPeriodTicks == 0) {
      can::CurrentMonitorFrame cm{};
      std::copy(std::begin(s.coil_current_adc), std::end(s.coil_current_adc), cm.coil_current_adc);
      can::encode_current_monitor(cm, cm_counter++, f);
      plant_port->send(f);
    }
    const auto counter = static_cast<std::uint8_t>(n & 0xFFu);
    can::encode_sensor(s, counter, f);
    plant_port->send(f);
    if (n % can::kHeartbeatPeriodTicks == 0) {
      can::HeartbeatFrame hb{can::NodeState::kOperational, static_cast<std::uint32_t>(t * 1000.0), 0, 0};
      can::encode_heartbeat(can::MessageKind::kHeartbeatPlant, hb, hb_counter++, f);
      plant_port->send(f);
    }
    // --- controller: the firmware's servo tick.
    loop.on_tick();
    // --- plant endpoint: the actuator frame answering tick n (ZOH).
    bool got = false;
    io::ActuatorCommand received{};
    while (plant_port->pending() > 0) {
      can::CanFrame in{};
      if (plant_port->receive(in, 0u) != can::PortStatus::kOk) break;
      if (prx.accept(in) != can::RxStatus::kOk) continue;
      if (prx.last_message() == &can::message(can::MessageKind::kActuator) && can::frame_counter(in) == counter) {
        can::decode_actuator(in, received);
        got = true;
      }
    }
    if (!got) ++c.missed_actuator;
    plant->apply(watchdog.update(got, received));  // the amplifiers' watchdog: hold <= 10 ms, then off
    plant->advance_tick();
    ++c.ticks;
    // --- Modbus, between ticks: only requests already waiting.
    const std::int64_t poll_cpu0 = thread_cpu_ns();
    const int requests = std::max(0, modbus->poll(0));
    c.modbus_requests += static_cast<std::uint64_t>(requests);
    c.max_modbus_cpu_ns = std::max(c.max_modbus_cpu_ns, thread_cpu_ns() - poll_cpu0);
    modbus->registers().advance_time_us(static_cast<std::uint32_t>(period_ns / 1000));  // engineer relock clock

    const std::int64_t done = now_ns();
    c.max_work_ns = std::max(c.max_work_ns, done - start);
    c.sum_work_ns += done - start;
    if (done > deadline) {
      ++c.deadline_misses;
      c.max_late_ns = std::max(c.max_late_ns, done - deadline);
      if (done - deadline > kResyncTicks * period_ns) {
        ++c.resyncs;
        deadline = done;
      }
    } else {
      sleep_until_ns(deadline);
    }
    deadline += period_ns;

    // A stage selected over Modbus (stage.profile, landed only: the binding
    // refuses it otherwise) is the stage wired to the board from now on: the
    // bench rebuilds its plant from that profile, at rest, as a lab swaps the
    // stage on the bench. The plant stayed the boot stage's before, and the
    // square stage's kernel then faulted on the cross plant (FollowingError,
    // 0.17 s into its levitation). Only a request can change it: looked up
    // after a poll that answered one, not every tick.
    if (const int now_stage = requests > 0 ? selected_stage() : plant_stage; now_stage != plant_stage) {
      std::string why;
      const char* name = "";
      StagePlant next;
      bool built = plant_of(static_cast<std::uint16_t>(now_stage), rate_Hz, o.plant, &next, &why, &name);
      if (built) plant_options = o.plant;
      if (!built) {
        // A stage the kernel took but whose plant the bench cannot build as
        // asked -- the as-built error set is modelled for the cross and square
        // layouts only -- runs on its nominal plant, said loudly, rather than
        // a Modbus write stopping the bench (it did, with --plant as-built
        // and the triangle stage selected).
        PlantOptions nominal = o.plant;
        nominal.model = hil::PlantModel::kNominal;
        nominal.error_seed.reset();
        std::string why_nominal;
        built = plant_of(static_cast<std::uint16_t>(now_stage), rate_Hz, nominal, &next, &why_nominal, &name);
        if (built) {
          plant_options = nominal;
          std::fprintf(stderr, "maglev-hil serve: stage.profile %d: %s; its plant is the nominal model instead\n",
                       now_stage, why.c_str());
        }
      }
      if (!built) {
        std::fprintf(stderr, "maglev-hil serve: stage.profile is now %d, whose plant the bench cannot build (%s): stopping\n",
                     now_stage, why.c_str());
        break;
      }
      // Where the landed platen lies stays where it lies: x, y and theta_z
      // carry over (the interferometers read on; the counters jumped by the
      // 1 mm a session had moved, and the supervisor latched CounterJump);
      // height and tilt are the new stage's rest.
      // The platen's centre -- where its sensors are -- stays where it lies.
      // An as-built plant's body position is its centre of mass,
      // com_offset_m from the centre (body frame): carrying the CoM over
      // moved the platen by the difference of the two plants' offsets (2-5
      // mm from an as-built plant to a nominal one: CounterJump, and the
      // triangle, which lifts only near its centre, then hit its tilt
      // envelope).
      const auto com_offset = [](const hil::PlantConfig& pc) {
        return pc.as_built.active ? Eigen::Vector3d(pc.as_built.com_offset_m[0], pc.as_built.com_offset_m[1], 0.0)
                                  : Eigen::Vector3d::Zero();
      };
      const hil::BodyState was = plant->body_state();
      const Eigen::Vector3d centre = was.position_m - was.attitude * com_offset(plant->config());
      plant = std::make_unique<hil::Plant>(next.plant, seed);
      hil::BodyState rest = plant->body_state();
      const Eigen::Quaterniond& q = was.attitude;
      const double yaw = std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
      rest.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) * rest.attitude;
      const Eigen::Vector3d com = centre + rest.attitude * com_offset(next.plant);
      rest.position_m.x() = com.x();
      rest.position_m.y() = com.y();
      plant->set_body_state(rest);
      watchdog = lockstep::ActuatorWatchdog{};
      plant_stage = now_stage;
      std::printf("maglev-hil serve: stage.profile %d (%s) selected: the bench's plant rebuilt from it, at rest\n",
                  now_stage, name);
      report_plant(next, seed);
      std::fflush(stdout);
      deadline = now_ns() + period_ns;  // the rebuild is not a missed tick
    }
    if (const double now_rate = static_cast<double>(controller->config().servo_rate_Hz); now_rate != rate_Hz) {
      // servo.rate written (the binding takes it landed only): the kernel
      // has re-designed its loops. The plant steps at the new rate from the
      // state it is in (the same stage and plant options; its noise streams
      // restart from the seed), the sensor frames carry the new period, and
      // the loop is paced at it. Until 2026-11-29 the bench stopped here and
      // asked for a save and a restart, which it no longer answered.
      StagePlant next;
      std::string why;
      const char* name = "";
      if (!plant_of(static_cast<std::uint16_t>(plant_stage), now_rate, plant_options,
                    &next, &why, &name)) {
        std::fprintf(stderr, "maglev-hil serve: servo.rate is now %.0f Hz, at which the bench cannot build its plant (%s): "
                     "stopping\n", now_rate, why.c_str());
        break;
      }
      const double t_now = t + dt;
      const hil::BodyState was = plant->body_state();
      plant = std::make_unique<hil::Plant>(next.plant, seed);
      plant->set_body_state(was);
      watchdog = lockstep::ActuatorWatchdog{};
      sensors.set_period_us(static_cast<std::uint32_t>(std::lround(1e6 / now_rate)));
      t_at_retime = t_now;
      n_at_retime = n + 1;
      pace_at(now_rate);
      if (o.duration_s > 0.0) {
        const double left_s = o.duration_s - t_now;
        end_tick = n + 1 + (left_s > 0.0 ? static_cast<std::uint64_t>(std::llround(left_s / dt)) : 0u);
      }
      std::printf("maglev-hil serve: servo.rate %.0f Hz: the bench's plant steps and its loop is paced at it from %.4f s\n",
                  rate_Hz, t_now);
      std::fflush(stdout);
      deadline = now_ns() + period_ns;  // the rebuild is not a missed tick
    }
    if ((n + 1 - n_at_retime) % ticks_per_second == 0) {
      const kernel::ControllerStatus& st = controller->status();
      std::fprintf(stderr,
                   "t=%8.1f s  state=%-9s fault=%u moving=%d  x=%+.9f y=%+.9f z=%+.9f m  "
                   "misses=%llu resyncs=%llu max_tick=%lld us  modbus=%llu\n",
                   t + dt, hil::to_string(st.state), static_cast<unsigned>(st.fault), st.motion_active ? 1 : 0,
                   static_cast<double>(st.pose[maglev::kernel::Axis::kX]) * 1e-12, static_cast<double>(st.pose[maglev::kernel::Axis::kY]) * 1e-12,
                   static_cast<double>(st.pose[maglev::kernel::Axis::kZ]) * 1e-12, static_cast<unsigned long long>(c.deadline_misses),
                   static_cast<unsigned long long>(c.resyncs), static_cast<long long>(c.max_work_ns / 1000),
                   static_cast<unsigned long long>(c.modbus_requests));
    }
  }
  const double wall_s = static_cast<double>(now_ns() - wall0) * 1e-9;
  const double sim_s = sim_time(c.ticks);
  std::fprintf(stderr,
               "maglev-hil serve: stopped after %llu ticks (%.2f s simulated, %.2f s wall, real-time factor %.3f); "
               "deadline misses %llu (max late %lld us, resyncs %llu), tick work mean %.1f us max %lld us, missed "
               "actuator frames %llu, Modbus requests %llu (poll CPU max %lld us), final state %s\n",
               static_cast<unsigned long long>(c.ticks), sim_s, wall_s, wall_s > 0 ? sim_s / wall_s : 0.0,
               static_cast<unsigned long long>(c.deadline_misses), static_cast<long long>(c.max_late_ns / 1000),
               static_cast<unsigned long long>(c.resyncs),
               c.ticks > 0 ? 1e-3 * static_cast<double>(c.sum_work_ns) / static_cast<double>(c.ticks) : 0.0,
               static_cast<long long>(c.max_work_ns / 1000), static_cast<unsigned long long>(c.missed_actuator),
               static_cast<unsigned long long>(c.modbus_requests), static_cast<long long>(c.max_modbus_cpu_ns / 1000),
               hil::to_string(controller->status().state));
  const modbus_tcp::TcpServerStats& ms = modbus->tcp().stats();
  std::fprintf(stderr,
               "maglev-hil serve: Modbus TCP: %llu requests answered, max system calls per poll %llu (bound %llu), "
               "accepted %llu, refused %llu, evicted %llu, idle-closed %llu, slow-closed %llu, bad frames %llu, "
               "other unit %llu\n",
               static_cast<unsigned long long>(ms.requests), static_cast<unsigned long long>(ms.max_poll_syscalls),
               static_cast<unsigned long long>(modbus->tcp().max_syscalls_per_poll()),
               static_cast<unsigned long long>(ms.accepted), static_cast<unsigned long long>(ms.refused),
               static_cast<unsigned long long>(ms.evicted), static_cast<unsigned long long>(ms.idle_closed),
               static_cast<unsigned long long>(ms.slow_closed), static_cast<unsigned long long>(ms.bad_frames),
               static_cast<unsigned long long>(ms.other_unit));
  return 0;
}

}  // namespace

int serve_main(int argc, char** argv) {
  ServeOptions o;
  if (!parse(argc, argv, &o)) {
    usage();
    return 2;
  }
  std::optional<scenario::Scenario> sc;
  if (!o.scenario.empty()) {
    std::string path = o.scenario;
    if (!(fs::exists(path) && fs::is_regular_file(path))) path = (fs::path(o.scenarios) / (o.scenario + ".scenario")).string();
    auto r = scenario::load_scenario_file(path);
    if (!r.ok()) {
      for (const auto& e : r.errors) std::fprintf(stderr, "%s\n", e.to_string().c_str());
      return 2;
    }
    sc = std::move(*r.scenario);
    if (!sc->controller.empty() || !sc->timeline.empty()) {
      std::fprintf(stderr,
                   "maglev-hil serve: note: %s: only its [plant] keys and seed are used (the controller's "
                   "configuration is the flash's; nothing of its timeline runs)\n",
                   sc->source.c_str());
    }
  }

  struct sigaction sa{};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: clock_nanosleep returns at once
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  if (o.rt_priority > 0) {
    // Real-time scheduling for the servo thread (needs CAP_SYS_NICE / root);
    // the tick's work is ~10 % of the period, so this cannot starve the host.
    sched_param sp{};
    sp.sched_priority = std::clamp(o.rt_priority, sched_get_priority_min(SCHED_FIFO), sched_get_priority_max(SCHED_FIFO));
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
      std::fprintf(stderr, "maglev-hil serve: SCHED_FIFO %d refused (%s); running with the normal scheduler\n",
                   sp.sched_priority, std::strerror(errno));
    }
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      std::fprintf(stderr, "maglev-hil serve: mlockall failed (%s)\n", std::strerror(errno));
    }
  }

  const scenario::Scenario* scenario = sc ? &*sc : nullptr;
  return o.kernel == hil::KernelKind::kQ7_24 ? serve<numeric::Q7_24>(o, scenario) : serve<float>(o, scenario);
}

}  // namespace maglev::bench
