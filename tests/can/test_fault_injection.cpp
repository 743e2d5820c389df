// CAN fault injection on the closed loop (label can): the plant
// (hil::Plant), the controller node (hil::ControllerNode over CanServoIo) and
// the in-process virtual bus with its fault hook, lockstep, one thread.
// Sensor and actuator frames are dropped, corrupted, delayed and duplicated
// while the stage levitates. Asserted: each fault is detected (per-reason
// counters, stale ticks, watchdog trips within their bound, the kernel's
// safe reaction), the plant's actuator watchdog zeroes the current, and the
// plant's TRUTH never leaves the stage's limits.
#include <cmath>
#include <cstdio>
#include <memory>

#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/can_link/watchdog.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;

namespace {

constexpr std::uint32_t kPeriodUs = 400;
constexpr double kZMax_m = 40e-6 + 5e-6;   // 40 um window + margin (overshoot on a fault)
constexpr double kZMin_m = -1e-6;          // rest is z = 0 (contact)
constexpr double kTiltMax_rad = 300e-6;    // supervisor envelope
constexpr double kPeakCurrent_A = 4.0 + 0.5;

struct Fault {
  std::uint32_t id = 0;         // frame ID hit
  std::uint64_t first_tick = 0, last_tick = 0;  // inclusive
  can::FaultAction action{};
};

// Plant endpoint + controller node in lockstep over one virtual bus.
struct Loop {
  std::shared_ptr<can::VirtualBus> bus = std::make_shared<can::VirtualBus>("fault-injection");
  std::unique_ptr<can::VirtualCanPort> plant_port = bus->open_endpoint();
  std::unique_ptr<can::VirtualCanPort> ctrl_port = bus->open_endpoint();
  hil::Plant plant{hil::PlantConfig::Default(), 5};
  hil::CanServoIo cio{*ctrl_port};
  hil::ControllerNode node{hil::KernelKind::kFloat32, cio};
  can::LinkReceiver prx;
  can::ActuatorFrameWatchdog plant_watchdog;
  io::ActuatorCommand held = io::kSafeActuatorCommand;
  std::uint64_t tick = 0;
  std::uint8_t cm_counter = 0;
  std::vector<Fault> faults;
  // Measured
  std::uint32_t plant_missed = 0;
  std::uint64_t plant_trip_tick = ~0ull;
  std::uint64_t zero_current_tick = ~0ull;
  double z_min = 1.0, z_max = -1.0, tilt_max = 0.0, i_max = 0.0;

  Loop() {
    bus->set_fault_hook([this](const can::CanFrame& f, std::uint64_t) {
      for (const auto& x : faults) {
        if (f.id == x.id && tick >= x.first_tick && tick <= x.last_tick) return x.action;
      }
      return can::FaultAction{};
    });
    plant_watchdog.arm(0);
  }

  void step() {
    const io::SensorSample s = plant.sample();
    can::CanFrame f{};
    if (tick % can::kCurrentMonitorPeriodTicks == 0) {
      can::CurrentMonitorFrame cm{};
      for (int j = 0; j < io::kCoils; ++j) cm.coil_current_adc[j] = s.coil_current_adc[j];
      can::encode_current_monitor(cm, cm_counter++, f);
      plant_port->send(f);
    }
    const auto counter = static_cast<std::uint8_t>(tick & 0xFFu);
    can::encode_sensor(s, counter, f);
    plant_port->send(f);
    node.run_once(0, true);  // lockstep: a missing sensor frame is a stale tick
    const auto now = static_cast<std::uint32_t>(tick * kPeriodUs);
    bool got = false;
    while (plant_port->pending() > 0) {
      can::CanFrame in{};
      if (plant_port->receive(in, 0) != can::PortStatus::kOk) break;
      if (prx.accept(in) != can::RxStatus::kOk) continue;
      if (prx.last_message() == &can::message(can::MessageKind::kActuator) && can::frame_counter(in) == counter) {
        can::decode_actuator(in, held);
        got = true;
      }
    }
    if (got) {
      plant_watchdog.feed(now);
    } else {
      ++plant_missed;  // the amplifier holds its last input (ZOH) until its enable times out
    }
    if (plant_watchdog.check(now)) {
      if (plant_trip_tick == ~0ull) plant_trip_tick = tick;
      held = io::kSafeActuatorCommand;
    }
    if (!held.amplifier_enable && zero_current_tick == ~0ull && tick > 10) zero_current_tick = tick;
    plant.apply(held);
    plant.advance_tick();
    const auto& t = plant.truth();
    z_min = std::min(z_min, t.position_m[2]);
    z_max = std::max(z_max, t.position_m[2]);
    tilt_max = std::max({tilt_max, std::fabs(t.angles_rad[0]), std::fabs(t.angles_rad[1])});
    for (double i : t.coil_current_A) i_max = std::max(i_max, std::fabs(i));
    ++tick;
  }

  void levitate() {
    kernel::MotionCommand c;
    c.type = kernel::MotionType::kLevitate;
    CHECK_TRUE(node.command(c) == kernel::CommandResult::kAccepted);
    while (node.status().state != kernel::SequencerState::kReady && tick < 5 * 2500) step();
    CHECK_TRUE(node.status().state == kernel::SequencerState::kReady);
    for (int i = 0; i < 500; ++i) step();  // settle
  }
  void run_for(std::uint64_t ticks) {
    for (std::uint64_t i = 0; i < ticks; ++i) step();
  }
  void check_limits() const {
    std::printf("    truth: z %.2f..%.2f um, |tilt| <= %.1f urad, |i| <= %.3f A\n", z_min * 1e6, z_max * 1e6,
                tilt_max * 1e6, i_max);
    CHECK_TRUE(z_min >= kZMin_m);
    CHECK_TRUE(z_max <= kZMax_m);
    CHECK_TRUE(tilt_max <= kTiltMax_rad);
    CHECK_TRUE(i_max <= kPeakCurrent_A);
  }
};

can::FaultAction act(can::FaultAction::Kind k, std::uint32_t delay = 1, std::uint16_t bit = 77) {
  can::FaultAction a;
  a.kind = k;
  a.delay_frames = delay;
  a.corrupt_bit = bit;
  return a;
}

constexpr std::uint32_t kSensorId = 0x030, kActuatorId = 0x020;

}  // namespace

TEST_GROUP(FaultInjection){};

TEST(FaultInjection, SingleCorruptedAndDuplicatedFramesAreRejectedAndTolerated) {
  Loop L;
  L.levitate();
  const std::uint64_t t0 = L.tick + 10;
  L.faults = {{kSensorId, t0, t0, act(can::FaultAction::kCorrupt)},
              {kActuatorId, t0 + 50, t0 + 50, act(can::FaultAction::kCorrupt, 1, 100)},
              {kSensorId, t0 + 100, t0 + 100, act(can::FaultAction::kDuplicate)}};
  L.run_for(400);
  const auto& rx = L.cio.rx_stats();
  std::printf("\n    controller: bad_crc %u repeated %u stale ticks %u (first at +%u), link lost %u; plant: bad_crc %u "
              "missed %u\n",
              rx.count(can::RxStatus::kBadCrc), rx.count(can::RxStatus::kRepeated), L.node.link_stats().stale_ticks,
              L.node.link_stats().first_stale_tick - static_cast<std::uint32_t>(t0), L.node.link_stats().link_lost_ticks,
              L.prx.stats().count(can::RxStatus::kBadCrc), L.plant_missed);
  LONGS_EQUAL(1u, rx.count(can::RxStatus::kBadCrc));     // the corrupted sensor frame, never applied
  LONGS_EQUAL(1u, rx.count(can::RxStatus::kRepeated));   // the duplicate
  LONGS_EQUAL(1u, L.node.link_stats().stale_ticks);      // detected in the very tick
  LONGS_EQUAL(static_cast<std::uint32_t>(t0), L.node.link_stats().first_stale_tick);
  LONGS_EQUAL(0u, L.node.link_stats().link_lost_ticks);  // one frame does not trip the 1.2 ms watchdog
  // The plant: the corrupted actuator frame + the one the stale tick never sent.
  LONGS_EQUAL(1u, L.prx.stats().count(can::RxStatus::kBadCrc));
  LONGS_EQUAL(2u, L.plant_missed);
  LONGS_EQUAL(0u, L.plant_watchdog.timeouts());
  CHECK_TRUE(L.node.status().state == kernel::SequencerState::kReady);  // tolerated: still levitating
  L.check_limits();
}

TEST(FaultInjection, DelayedSensorFrameIsSupersededNotApplied) {
  Loop L;
  L.levitate();
  const std::uint64_t t0 = L.tick + 10;
  // Sensor frame t0 arrives after 1 later frame (behind sensor t0+1 or its current monitor).
  L.faults = {{kSensorId, t0, t0, act(can::FaultAction::kDelay, 1)}};
  L.run_for(400);
  const auto& rx = L.cio.rx_stats();
  std::printf("\n    delayed sensor frame: stale ticks %u, out_of_order %u, superseded %u, plant missed %u\n",
              L.node.link_stats().stale_ticks, rx.count(can::RxStatus::kOutOfOrder), L.cio.superseded(),
              L.plant_missed);
  LONGS_EQUAL(1u, L.node.link_stats().stale_ticks);  // tick t0 ran stale
  // The late frame t0 was either rejected as out of order or superseded by t0+1.
  CHECK_TRUE(rx.count(can::RxStatus::kOutOfOrder) + L.cio.superseded() == 1u);
  CHECK_TRUE(L.plant_missed <= 2u);
  CHECK_TRUE(L.node.status().state == kernel::SequencerState::kReady);
  L.check_limits();
}

TEST(FaultInjection, SensorFramesLostControllerTripsAndLandsSafely) {
  Loop L;
  L.levitate();
  const std::uint64_t t0 = L.tick + 10;
  L.faults = {{kSensorId, t0, t0 + 19, act(can::FaultAction::kDrop)}};  // 20 ticks = 8 ms silent
  L.run_for(2 * 2500);
  const auto& ls = L.node.link_stats();
  const auto& st = L.node.status();
  const std::uint32_t stale_latency = ls.first_stale_tick - static_cast<std::uint32_t>(t0);
  const std::uint32_t wd_latency = ls.first_link_lost_tick - static_cast<std::uint32_t>(t0);
  std::printf("\n    sensor frames dropped 20 ticks: stale after %u ticks, kernel fault %d (first at +%u ticks), "
              "controller watchdog after %u ticks (%u us), plant watchdog after %llu ticks; final state %d, z %.2f um\n",
              stale_latency, static_cast<int>(st.first_fault.code), st.first_fault.tick - static_cast<std::uint32_t>(t0),
              wd_latency, wd_latency * kPeriodUs, static_cast<unsigned long long>(L.plant_trip_tick - t0),
              static_cast<int>(st.state), L.plant.truth().position_m[2] * 1e6);
  LONGS_EQUAL(0u, stale_latency);  // the first missing frame is seen in its own tick
  // The kernel's supervisor latches kStaleFrames on the 3rd consecutive stale sample.
  CHECK_TRUE(st.first_fault.code == kernel::FaultCode::kStaleFrames);
  CHECK_TRUE(st.first_fault.tick - static_cast<std::uint32_t>(t0) <= 3u);
  // The frame watchdog: no accepted frame for > 1.2 ms -> expired on the 4th silent tick (1.6 ms).
  CHECK_TRUE(wd_latency * kPeriodUs <= 1200u + kPeriodUs);
  CHECK_TRUE(ls.link_lost_ticks >= 1u);
  // The plant saw no actuator frame either (stale ticks answer nothing): its
  // amplifier-enable watchdog zeroed the current within the same bound.
  CHECK_TRUE(L.plant_trip_tick - t0 <= 4u);
  // Safe reaction latched: landing or currents off, never back to Ready by itself.
  CHECK_TRUE(st.state == kernel::SequencerState::kFault || st.state == kernel::SequencerState::kLanding ||
             st.state == kernel::SequencerState::kIdle);
  CHECK_TRUE(st.reaction != kernel::FaultReaction::kNone);
  CHECK_TRUE(L.plant.truth().position_m[2] < 5e-6);  // on (or near) rest two seconds later
  L.check_limits();
}

TEST(FaultInjection, ActuatorFramesLostPlantZeroesCurrentAndControllerReacts) {
  Loop L;
  L.levitate();
  const std::uint64_t t0 = L.tick + 10;
  L.faults = {{kActuatorId, t0, t0 + 24, act(can::FaultAction::kDrop)}};  // 25 ticks = 10 ms
  L.run_for(2 * 2500);
  const auto& st = L.node.status();
  std::printf("\n    actuator frames dropped 25 ticks: plant missed %u, plant watchdog after %llu ticks "
              "(bound 1.2 ms = 3 ticks), controller fault %d reaction %d at +%d ticks; z %.2f um\n",
              L.plant_missed, static_cast<unsigned long long>(L.plant_trip_tick - t0), static_cast<int>(st.first_fault.code),
              static_cast<int>(st.reaction), static_cast<int>(st.first_fault.tick) - static_cast<int>(t0),
              L.plant.truth().position_m[2] * 1e6);
  CHECK_TRUE(L.plant_missed >= 25u);
  CHECK_TRUE(L.plant_trip_tick - t0 <= 4u);  // > 1200 us without a frame: zero current
  CHECK_TRUE(L.plant_watchdog.timeouts() >= 1u);
  // 10 ms without current: the platen drops; the controller notices through
  // its sensors (envelope / following error) and latches a safe reaction.
  CHECK_TRUE(st.first_fault.code != kernel::FaultCode::kNone);
  CHECK_TRUE(st.reaction != kernel::FaultReaction::kNone);
  L.check_limits();
}
