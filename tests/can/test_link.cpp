// Virtual bus, lockstep determinism, watchdog bounds, fault injection, bus
// load, transport selection by name.
#include <chrono>
#include <cstdio>
#include <thread>

#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_link/watchdog.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/lockstep/plant_endpoint.hpp"
#include "maglev/can_port/open_can_port.hpp"
#include "maglev/can_port/periodic_timer.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>
#include <CppUTest/MemoryLeakWarningPlugin.h>

using namespace maglev;
using namespace maglev::can;

namespace {
// A toy "plant" and "controller" pair: enough to make the exchanged values
// depend on every previous tick, so any reordering or loss changes the hash.
io::SensorSample plant_output(std::uint32_t tick, const io::ActuatorCommand& last) {
  io::SensorSample s{};
  for (int i = 0; i < 3; ++i) s.interferometer_counts[i] = tick * 1000u + static_cast<std::uint32_t>(last.dac_code[i]);
  for (int i = 0; i < 3; ++i) s.displacement_adc[i] = static_cast<std::int16_t>(last.dac_code[i + 3] / 2);
  for (int i = 0; i < 4; ++i) s.hall_adc[i] = static_cast<std::int16_t>(tick + static_cast<std::uint32_t>(i));
  for (int i = 0; i < 8; ++i) s.coil_current_adc[i] = static_cast<std::int16_t>(last.dac_code[i] / 3);
  return s;
}
io::ActuatorCommand controller_step(const io::SensorSample& s) {
  io::ActuatorCommand a{};
  for (int j = 0; j < 8; ++j) {
    a.dac_code[j] = static_cast<std::int16_t>((s.interferometer_counts[j % 3] * 7u + static_cast<std::uint32_t>(s.coil_current_adc[j])) & 0x3FFF);
  }
  a.amplifier_enable = true;
  return a;
}

struct LockstepResult {
  std::uint64_t hash = 1469598103934665603ull;
  std::uint32_t ok_ticks = 0;
  RxStats plant_rx;
  RxStats controller_rx;
};

// The bench's two endpoints (hil/lockstep's PlantEndpoint, the controller
// node's CanServoIo = the firmware app's CAN I/O) with toy dynamics.
LockstepResult run_lockstep(const std::string& bus_name, std::uint32_t ticks) {
  auto bus = VirtualBus::get(bus_name);
  auto plant_port = bus->open_endpoint();
  auto ctrl_port = bus->open_endpoint();
  LockstepResult r;
  std::thread controller([&] {
    hil::CanServoIo cio(*ctrl_port);
    io::SensorSample s{};
    for (std::uint32_t i = 0; i < ticks; ++i) {
      if (!cio.port().wait(2'000'000) || !cio.sensors().read(s)) break;
      cio.actuators().write(controller_step(s));
    }
    r.controller_rx = cio.rx_stats();
  });
  lockstep::PlantEndpoint plant(*plant_port, nullptr, lockstep::PlantEndpoint::Config{false, false});
  io::ActuatorCommand cmd = io::kSafeActuatorCommand;
  for (std::uint32_t tick = 0; tick < ticks; ++tick) {
    const std::uint8_t counter = plant.send_tick(tick, tick * 400e-6, plant_output(tick, cmd));
    if (!plant.await_actuator(counter, 2'000'000, &cmd)) break;
    ++r.ok_ticks;
    for (auto c : cmd.dac_code) r.hash = (r.hash ^ static_cast<std::uint16_t>(c)) * 1099511628211ull;
  }
  controller.join();
  r.plant_rx = plant.receiver().stats();
  return r;
}
}  // namespace

TEST_GROUP(VirtualBus) {
  // The named-bus registry and std::thread keep process-lifetime
  // allocations that CppUTest's per-test leak check would flag.
  void setup() override { MemoryLeakWarningPlugin::saveAndDisableNewDeleteOverloads(); }
  void teardown() override { MemoryLeakWarningPlugin::restoreNewDeleteOverloads(); }
};

TEST(VirtualBus, EveryOtherEndpointReceivesInOrderNotItself) {
  auto bus = VirtualBus::get("three");
  auto a = bus->open_endpoint();
  auto b = bus->open_endpoint();
  auto c = bus->open_endpoint();
  CanFrame f{};
  for (int i = 0; i < 5; ++i) {
    encode_sync(SyncFrame{static_cast<std::uint32_t>(i), 0}, static_cast<std::uint8_t>(i), f);
    CHECK(PortStatus::kOk == a->send(f));
  }
  LONGS_EQUAL(0, a->pending());
  LONGS_EQUAL(5, b->pending());
  LONGS_EQUAL(5, c->pending());
  for (int i = 0; i < 5; ++i) {
    CanFrame in{};
    CHECK(PortStatus::kOk == b->receive(in, 0));
    LONGS_EQUAL(i, frame_counter(in));
  }
  CanFrame in{};
  CHECK(PortStatus::kTimeout == b->receive(in, 1000));
  LONGS_EQUAL(1, b->counters().rx_timeouts);
  LONGS_EQUAL(5, a->counters().tx_frames);
  // Invalid FD length is refused at send.
  f.len = 13;
  CHECK(PortStatus::kBadFrame == a->send(f));
}

// Threading::kOneThread (bench::run's private bus) takes no lock: it must
// deliver exactly what a shared bus delivers, fault hook included, and a
// receive with a timeout on an empty queue returns at once (no other thread
// could send meanwhile) instead of sleeping.
TEST(VirtualBus, OneThreadBusDeliversAsTheSharedOneAndNeverWaits) {
  std::vector<std::vector<std::uint8_t>> got[2];
  for (int mode = 0; mode < 2; ++mode) {
    auto bus = std::make_shared<VirtualBus>(
        "one-thread-" + std::to_string(mode),
        mode == 0 ? VirtualBus::Threading::kShared : VirtualBus::Threading::kOneThread);
    bus->set_fault_hook([](const CanFrame&, std::uint64_t seq) {
      FaultAction a;
      if (seq % 5 == 1) a.kind = FaultAction::kDrop;
      if (seq % 5 == 2) a.kind = FaultAction::kDuplicate;
      if (seq % 5 == 3) {
        a.kind = FaultAction::kDelay;
        a.delay_frames = 2;
      }
      if (seq % 5 == 4) {
        a.kind = FaultAction::kCorrupt;
        a.corrupt_bit = static_cast<std::uint16_t>(seq);
      }
      return a;
    });
    auto tx = bus->open_endpoint();
    auto rx = bus->open_endpoint();
    CanFrame f{};
    for (int i = 0; i < 40; ++i) {
      encode_sync(SyncFrame{static_cast<std::uint32_t>(i), 7}, static_cast<std::uint8_t>(i), f);
      CHECK(PortStatus::kOk == tx->send(f));
    }
    LONGS_EQUAL(40, static_cast<long>(bus->frames_sent()));
    CanFrame in{};
    while (rx->receive(in, 0) == PortStatus::kOk) got[mode].emplace_back(in.data, in.data + in.len);
    const auto t0 = std::chrono::steady_clock::now();
    const PortStatus last = rx->receive(in, mode == 0 ? 1000u : 5'000'000u);  // 5 s if it waited
    const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    CHECK(PortStatus::kTimeout == last);
    if (mode == 1) CHECK_TRUE(waited_s < 1.0);
  }
  CHECK_TRUE(!got[0].empty());
  CHECK_TRUE(got[0] == got[1]);
}

TEST(VirtualBus, OpenCanPortByName) {
  std::string err;
  auto p1 = open_can_port("virtual:named", &err);
  auto p2 = open_can_port("virtual:named", &err);
  CHECK_TRUE(p1 != nullptr);
  CHECK_TRUE(p2 != nullptr);
  STRCMP_EQUAL("virtual:named", p1->name());
  CanFrame f{};
  encode_sync(SyncFrame{1, 2}, 0, f);
  CHECK(PortStatus::kOk == p1->send(f));
  CanFrame in{};
  CHECK(PortStatus::kOk == p2->receive(in, 0));
  LONGS_EQUAL(0x010, in.id);
  auto d = open_can_port("virtual", &err);
  STRCMP_EQUAL("virtual:default", d->name());
  // A SocketCAN name that cannot open reports why instead of crashing.
  auto bad = open_can_port("nosuchcan7", &err);
  CHECK_TRUE(bad == nullptr);
  CHECK_FALSE(err.empty());
}

TEST_GROUP(Lockstep) {
  // The named-bus registry and std::thread keep process-lifetime
  // allocations that CppUTest's per-test leak check would flag.
  void setup() override { MemoryLeakWarningPlugin::saveAndDisableNewDeleteOverloads(); }
  void teardown() override { MemoryLeakWarningPlugin::restoreNewDeleteOverloads(); }
};

TEST(Lockstep, DeterministicAcrossRunsAndNoRejections) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto r1 = run_lockstep("ls1", 5000);
  const auto t1 = std::chrono::steady_clock::now();
  const auto r2 = run_lockstep("ls2", 5000);
  LONGS_EQUAL(5000, r1.ok_ticks);
  LONGS_EQUAL(5000, r2.ok_ticks);
  CHECK_TRUE(r1.hash == r2.hash);
  LONGS_EQUAL(0, r1.plant_rx.rejected_total());
  LONGS_EQUAL(0, r1.controller_rx.rejected_total());
  LONGS_EQUAL(0, r1.plant_rx.lost);
  LONGS_EQUAL(5000, r1.plant_rx.accepted);
  // sensor frames + a current monitor frame every 5th tick + a plant heartbeat every 250th
  LONGS_EQUAL(5000 + 1000 + 20, r1.controller_rx.accepted);
  const double s = std::chrono::duration<double>(t1 - t0).count();
  std::printf("\n[measured] virtual-bus lockstep (2 threads): %.0f ticks/s\n", 5000.0 / s);
}

TEST_GROUP(Watchdog){};

TEST(Watchdog, TripsAfterThreePeriodsNotBefore) {
  SensorFrameWatchdog wd;  // 1200 us
  LONGS_EQUAL(1200, wd.timeout_us());
  wd.arm(1000);
  CHECK_FALSE(wd.check(2200));  // exactly 1.2 ms silent: still fine
  CHECK_TRUE(wd.check(2201));
  LONGS_EQUAL(1, wd.timeouts());
  CHECK_TRUE(wd.check(5000));  // stays expired, counted once
  LONGS_EQUAL(1, wd.timeouts());
  // Frames every 400 us with two lost in a row (800 us gaps -> 1200 us gap).
  wd.feed(6000);
  CHECK_FALSE(wd.expired());
  CHECK_FALSE(wd.check(6400 + 800));
  wd.feed(7200);
  CHECK_FALSE(wd.check(7200 + 1200));
  CHECK_TRUE(wd.check(7200 + 1201));
  LONGS_EQUAL(2, wd.timeouts());
}

TEST(Watchdog, WrapsWithTheMicrosecondClock) {
  ActuatorFrameWatchdog wd(FrameWatchdog::Config{1200});
  wd.feed(0xFFFFFF00u);
  CHECK_FALSE(wd.check(0xFFFFFF00u + 1000u));  // wraps past 2^32
  CHECK_TRUE(wd.check(0xFFFFFF00u + 1300u));
}

TEST(Watchdog, UnarmedNeverTrips) {
  FrameWatchdog wd;
  CHECK_FALSE(wd.check(100000));
}

TEST_GROUP(FaultInjection) {
  // The named-bus registry and std::thread keep process-lifetime
  // allocations that CppUTest's per-test leak check would flag.
  void setup() override { MemoryLeakWarningPlugin::saveAndDisableNewDeleteOverloads(); }
  void teardown() override { MemoryLeakWarningPlugin::restoreNewDeleteOverloads(); }
};

TEST(FaultInjection, DropCorruptDelayDuplicateAreEachDetectedAndCounted) {
  auto bus = VirtualBus::get("faults");
  auto tx = bus->open_endpoint();
  auto rx_port = bus->open_endpoint();
  // Per bus sequence number: 10 dropped, 20 corrupted, 30 delayed by 2
  // frames, 40 duplicated, 50..52 dropped (a 4-counter jump).
  bus->set_fault_hook([](const CanFrame&, std::uint64_t seq) {
    FaultAction a;
    if (seq == 10 || (seq >= 50 && seq <= 52)) a.kind = FaultAction::kDrop;
    if (seq == 20) {
      a.kind = FaultAction::kCorrupt;
      a.corrupt_bit = 100;
    }
    if (seq == 30) {
      a.kind = FaultAction::kDelay;
      a.delay_frames = 2;
    }
    if (seq == 40) a.kind = FaultAction::kDuplicate;
    return a;
  });
  LinkReceiver rx;
  SensorFrameWatchdog wd;
  io::SensorSample applied{};
  std::uint32_t applied_count = 0;
  CanFrame f{};
  for (std::uint32_t i = 0; i < 60; ++i) {
    io::SensorSample s{};
    s.interferometer_counts[0] = i;
    encode_sensor(s, static_cast<std::uint8_t>(i), f);
    tx->send(f);
  }
  wd.arm(0);
  std::uint32_t now_us = 0;
  CanFrame in{};
  while (rx_port->receive(in, 0) == PortStatus::kOk) {
    now_us += 400;
    if (rx.accept(in, &message(MessageKind::kSensor)) == RxStatus::kOk) {
      decode_sensor(in, applied);
      ++applied_count;
      wd.feed(now_us);
    }
    wd.check(now_us);
  }
  const auto& st = rx.stats();
  LONGS_EQUAL(1, st.count(RxStatus::kBadCrc));        // corrupted frame 20
  LONGS_EQUAL(1, st.count(RxStatus::kOutOfOrder));    // frame 30 arriving after 31, 32
  LONGS_EQUAL(1, st.count(RxStatus::kRepeated));      // duplicate of 40
  LONGS_EQUAL(1, st.count(RxStatus::kSequenceJump));  // 49 -> 53
  // lost: 10 (1), 20 (1, the corrupted one), 30 (1, jump 29 -> 31)
  LONGS_EQUAL(3, st.lost);
  // 60 sent, 4 dropped on the wire, 1 duplicated: 57 received; rejected 4.
  LONGS_EQUAL(57 - 4, st.accepted);
  LONGS_EQUAL(applied_count, st.accepted);
  LONGS_EQUAL(59, applied.interferometer_counts[0]);  // last good frame applied
  LONGS_EQUAL(0, wd.timeouts());  // no gap of 3 periods in arrival order

  // Now the sender goes silent: the watchdog trips after 1.2 ms.
  CHECK_FALSE(wd.check(now_us + 1200));
  CHECK_TRUE(wd.check(now_us + 1201));
}

TEST(FaultInjection, LockstepPlantTimesOutWhenActuatorFramesDropped) {
  auto bus = VirtualBus::get("drop_actuator");
  auto plant_port = bus->open_endpoint();
  auto ctrl_port = bus->open_endpoint();
  bus->set_fault_hook([](const CanFrame& f, std::uint64_t) {
    FaultAction a;
    if (f.id == message(MessageKind::kActuator).can_id) a.kind = FaultAction::kDrop;
    return a;
  });
  lockstep::PlantEndpoint plant(*plant_port, nullptr, lockstep::PlantEndpoint::Config{false, false});
  hil::CanServoIo ctrl(*ctrl_port);
  io::ActuatorCommand cmd = io::kSafeActuatorCommand;
  io::SensorSample s{};
  s.status_flags = 0;
  const std::uint8_t counter = plant.send_tick(0, 0.0, s);
  std::thread t([&] {
    io::SensorSample got{};
    if (ctrl.port().wait(1'000'000) && ctrl.sensors().read(got)) ctrl.actuators().write(controller_step(got));
  });
  const bool answered = plant.await_actuator(counter, 20'000, &cmd);
  t.join();
  CHECK_FALSE(answered);
  CHECK_FALSE(cmd.amplifier_enable);  // untouched: still the safe command
  ActuatorFrameWatchdog wd;
  wd.arm(0);
  CHECK_TRUE(wd.check(1201));  // the plant's reaction: zero current
}

TEST_GROUP(BusLoad){};

TEST(BusLoad, ServoPairAt2500HzIs46Point8Percent) {
  BusLoadMeter meter;
  CanFrame s{};
  CanFrame a{};
  encode_sensor(io::SensorSample{}, 0, s);
  encode_actuator(io::kSafeActuatorCommand, 0, a);
  LONGS_EQUAL(34 + 358, can_frame_bits(s).total());
  LONGS_EQUAL(34 + 238, can_frame_bits(a).total());
  for (int tick = 0; tick < 2500; ++tick) {
    meter.on_frame(s);
    meter.on_frame(a);
  }
  // One second of ticks.
  LONGS_EQUAL(468000, meter.load_ppm(1'000'000'000ull));
  UNSIGNED_LONGS_EQUAL(468'000'000ull, meter.busy_ns());  // 187.2 us x 2500
  std::printf("\n[measured] sensor %u bits (%u nominal + %u data) = %.1f us, actuator %u bits = %.1f us, "
              "servo load at 2.5 kHz %.1f %%\n",
              can_frame_bits(s).total(), can_frame_bits(s).nominal_bits, can_frame_bits(s).data_bits,
              static_cast<double>(frame_time_ns(can_frame_bits(s))) / 1000.0, can_frame_bits(a).total(),
              static_cast<double>(frame_time_ns(can_frame_bits(a))) / 1000.0,
              static_cast<double>(meter.load_ppm(1'000'000'000ull)) / 1e4);
}

TEST(BusLoad, ClassicalAndNoBrsFramesCostMore) {
  // Classical 8-byte frame: 47 + 64 bits + worst-case stuffing floor(98/4)=24 = 135 bits.
  LONGS_EQUAL(135, can_frame_bits(8, false, false).total());
  // FD without BRS: everything at the nominal rate.
  const FrameBits nobrs = can_frame_bits(32, true, false);
  LONGS_EQUAL(0, nobrs.data_bits);
  LONGS_EQUAL(392, nobrs.nominal_bits);
  LONGS_EQUAL(392'000, frame_time_ns(nobrs));
}

TEST_GROUP(PeriodicTimer){};

TEST(PeriodicTimer, AbsoluteDeadlinesCountMissesAndJitter) {
  PeriodicTimer timer(400'000);  // 2.5 kHz
  CHECK_TRUE(timer.ok());
  CHECK_TRUE(timer.start());
  const std::int64_t t0 = monotonic_ns();
  for (int i = 0; i < 250; ++i) timer.wait();
  // Stall for 2 ms: about 5 deadlines pass while we are busy.
  std::this_thread::sleep_for(std::chrono::milliseconds(2));
  const std::uint64_t n = timer.wait();
  CHECK_TRUE(n >= 4);
  CHECK_TRUE(timer.deadline_misses() >= 3);
  const double elapsed_ms = static_cast<double>(monotonic_ns() - t0) / 1e6;
  // Absolute deadlines: ticks * period matches the elapsed time (no drift).
  // (tolerance: one late wake-up on a loaded 2-core machine)
  DOUBLES_EQUAL(static_cast<double>(timer.ticks()) * 0.4, elapsed_ms, 3.0);
  LONGS_EQUAL(251, timer.jitter().samples);
  std::printf("\n[measured] timerfd 2.5 kHz, %llu ticks, %llu misses (2 ms stall injected)\n%s",
              static_cast<unsigned long long>(timer.ticks()),
              static_cast<unsigned long long>(timer.deadline_misses()), timer.jitter().to_string().c_str());
}
