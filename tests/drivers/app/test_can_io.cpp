// firmware/app CanSensorSource / CanActuatorSink over drivers/virtual_can:
// round trip with the counter echo, rejection of corrupted / repeated frames
// (stale sample, no answer), frame-watchdog expiry (safe outputs), and the
// real kernel's safe reaction to stale frames within the stated bound.
#include <cstdint>
#include <memory>

#include "maglev/app/can_io.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;

namespace {

// Echoes the first interferometer count into every DAC code so the round
// trip proves the actuator frame answers THIS sample.
struct EchoKernel {
  int calls = 0;
  std::uint16_t last_flags = 0;
  io::ActuatorCommand step(const io::SensorSample& s, bool) {
    ++calls;
    last_flags = s.status_flags;
    io::ActuatorCommand c{};
    for (int j = 0; j < io::kCoils; ++j) c.dac_code[j] = static_cast<std::int16_t>(s.interferometer_counts[0] + static_cast<std::uint32_t>(j));
    c.amplifier_enable = true;
    return c;
  }
};

io::SensorSample plant_sample(std::uint32_t k) {
  io::SensorSample s{};
  s.interferometer_counts[0] = 100 + k;
  s.interferometer_counts[1] = 200 + k;
  s.interferometer_counts[2] = 300 + k;
  s.displacement_adc[0] = -1234;
  s.displacement_adc[1] = 55;
  s.displacement_adc[2] = 4321;
  s.hall_adc[0] = 10;
  s.hall_adc[3] = -10;
  s.status_flags = 0;
  return s;
}

struct Rig {
  std::shared_ptr<can::VirtualBus> bus = std::make_shared<can::VirtualBus>("app-can-io");
  std::unique_ptr<can::VirtualCanPort> plant = bus->open_endpoint();
  std::unique_ptr<can::VirtualCanPort> controller = bus->open_endpoint();
  app::CanSensorSource sensors{*controller, app::CanSensorConfig{}};
  app::CanActuatorSink actuators{*controller, sensors};
  can::LinkReceiver plant_rx;

  void send_sensor(std::uint32_t k, std::uint8_t counter) {
    can::CanFrame f{};
    can::encode_sensor(plant_sample(k), counter, f);
    CHECK(plant->send(f) == can::PortStatus::kOk);
  }
  // Next actuator frame at the plant: false if none.
  bool plant_actuator(io::ActuatorCommand& c, std::uint8_t& counter) {
    can::CanFrame f{};
    if (plant->receive(f, 0) != can::PortStatus::kOk) return false;
    CHECK(plant_rx.accept(f, &can::message(can::MessageKind::kActuator)) == can::RxStatus::kOk);
    can::decode_actuator(f, c);
    counter = can::frame_counter(f);
    return true;
  }
};

}  // namespace

TEST_GROUP(CanIo) {};

TEST(CanIo, RoundTripEchoesTheSensorCounterAndCarriesTheSample) {
  Rig rig;
  EchoKernel kernel;
  app::ServoLoop<EchoKernel> loop(rig.sensors, rig.actuators, kernel, app::ServoConfig{}, app::ServoHooks{});
  for (std::uint32_t k = 0; k < 300; ++k) {  // counter wraps at 256
    const auto counter = static_cast<std::uint8_t>(k & 0xFFu);
    rig.send_sensor(k, counter);
    loop.on_tick();
    LONGS_EQUAL(0, kernel.last_flags);
    io::ActuatorCommand c{};
    std::uint8_t answered = 0;
    CHECK_TRUE(rig.plant_actuator(c, answered));
    LONGS_EQUAL(counter, answered);
    LONGS_EQUAL(static_cast<std::int16_t>(100 + k), c.dac_code[0]);
    LONGS_EQUAL(static_cast<std::int16_t>(107 + k), c.dac_code[7]);
    CHECK_TRUE(c.amplifier_enable);
  }
  LONGS_EQUAL(300, rig.sensors.stats().fresh);
  LONGS_EQUAL(0, rig.sensors.stats().stale);
  LONGS_EQUAL(300, rig.actuators.stats().sent);
  LONGS_EQUAL(300, rig.plant_rx.stats().accepted);
  LONGS_EQUAL(0, loop.state().sensor_faults);
}

TEST(CanIo, SampleFieldsSurviveTheLinkAndCurrentMonitorFillsCoilCurrents) {
  Rig rig;
  can::CurrentMonitorFrame cm{};
  for (int j = 0; j < io::kCoils; ++j) cm.coil_current_adc[j] = static_cast<std::int16_t>(-500 * (j + 1));
  can::CanFrame f{};
  can::encode_current_monitor(cm, 7, f);
  CHECK(rig.plant->send(f) == can::PortStatus::kOk);
  rig.send_sensor(9, 1);
  io::SensorSample s{};
  CHECK_TRUE(rig.sensors.read(s));
  const io::SensorSample want = plant_sample(9);
  LONGS_EQUAL(want.interferometer_counts[2], s.interferometer_counts[2]);
  LONGS_EQUAL(-1234, s.displacement_adc[0]);
  LONGS_EQUAL(4321, s.displacement_adc[2]);
  LONGS_EQUAL(-10, s.hall_adc[3]);
  LONGS_EQUAL(-500, s.coil_current_adc[0]);
  LONGS_EQUAL(-4000, s.coil_current_adc[7]);
  LONGS_EQUAL(0, s.status_flags);
  LONGS_EQUAL(1, rig.sensors.stats().current_monitor);
}

TEST(CanIo, CorruptedFrameIsRejectedStaleAndUnanswered) {
  Rig rig;
  EchoKernel kernel;
  app::ServoLoop<EchoKernel> loop(rig.sensors, rig.actuators, kernel, app::ServoConfig{}, app::ServoHooks{});
  rig.send_sensor(0, 0);
  loop.on_tick();
  // Flip one payload bit of the next frame on the wire: the CRC must catch it.
  rig.bus->set_fault_hook([](const can::CanFrame& fr, std::uint64_t) {
    can::FaultAction a;
    if (fr.id == can::message(can::MessageKind::kSensor).can_id) {
      a.kind = can::FaultAction::kCorrupt;
      a.corrupt_bit = 8 * 5 + 3;  // inside interferometer_count_0
    }
    return a;
  });
  rig.send_sensor(1, 1);
  loop.on_tick();
  LONGS_EQUAL(1, static_cast<long>(rig.sensors.receiver().stats().count(can::RxStatus::kBadCrc)));
  LONGS_EQUAL(io::kStaleFrame, kernel.last_flags);  // previous sample, flagged; not the corrupted one
  CHECK_FALSE(rig.sensors.fresh());
  LONGS_EQUAL(0, loop.state().sensor_faults);       // one lost frame: still inside the watchdog bound
  LONGS_EQUAL(1, rig.actuators.stats().sent);       // only tick 0 was answered
  LONGS_EQUAL(1, rig.actuators.stats().unanswered);
  rig.bus->set_fault_hook(nullptr);
  rig.send_sensor(2, 2);  // counter jump of 2 is within max_delta_counter = 3: accepted
  loop.on_tick();
  LONGS_EQUAL(0, kernel.last_flags);
  LONGS_EQUAL(2, rig.actuators.stats().sent);
}

TEST(CanIo, RepeatedCounterIsRejectedAndNewestOfSeveralWins) {
  Rig rig;
  io::SensorSample s{};
  rig.send_sensor(0, 10);
  CHECK_TRUE(rig.sensors.read(s));
  rig.send_sensor(1, 10);  // replayed counter
  CHECK_TRUE(rig.sensors.read(s));
  LONGS_EQUAL(1, static_cast<long>(rig.sensors.receiver().stats().count(can::RxStatus::kRepeated)));
  LONGS_EQUAL(io::kStaleFrame, s.status_flags);
  LONGS_EQUAL(100, s.interferometer_counts[0]);  // still sample 0, not the replay's payload
  // Two frames queued before one tick: the newest is used, the older counted.
  rig.send_sensor(2, 11);
  rig.send_sensor(3, 12);
  CHECK_TRUE(rig.sensors.read(s));
  LONGS_EQUAL(103, s.interferometer_counts[0]);
  LONGS_EQUAL(12, rig.sensors.answer_counter());
  LONGS_EQUAL(1, rig.sensors.stats().superseded);
}

TEST(CanIo, WatchdogExpiryForcesSafeOutputsAndDeadlineWriteIsNotResent) {
  Rig rig;
  EchoKernel kernel;
  app::ServoLoop<EchoKernel> loop(rig.sensors, rig.actuators, kernel, app::ServoConfig{}, app::ServoHooks{});
  rig.send_sensor(0, 0);
  loop.on_tick();
  io::ActuatorCommand c{};
  std::uint8_t counter = 0;
  CHECK_TRUE(rig.plant_actuator(c, counter));
  // The deadline check writing again in the same tick must not repeat counter 0.
  rig.actuators.write(io::kSafeActuatorCommand);
  LONGS_EQUAL(1, rig.actuators.stats().duplicates);
  CHECK_FALSE(rig.plant_actuator(c, counter));
  // Frames stop. Tick clock 400 us; bound 1200 us after the last frame at t = 0.
  for (int k = 1; k <= 3; ++k) {
    loop.on_tick();
    LONGS_EQUAL(0, loop.state().sensor_faults);  // stale, kernel decides
  }
  CHECK_FALSE(rig.sensors.watchdog().expired());
  loop.on_tick();  // t = 1600 us > 1200 us: link lost
  CHECK_TRUE(rig.sensors.watchdog().expired());
  LONGS_EQUAL(1, loop.state().sensor_faults);
  LONGS_EQUAL(io::kStaleFrame | io::kAdcFault, kernel.last_flags);
  LONGS_EQUAL(1, rig.sensors.stats().link_lost);
  LONGS_EQUAL(4, rig.sensors.stats().stale);
  // Link back: the next good frame (counter jump 5 > 3 resyncs, the one after is accepted).
  rig.send_sensor(5, 5);
  loop.on_tick();
  rig.send_sensor(6, 6);
  loop.on_tick();
  CHECK_FALSE(rig.sensors.watchdog().expired());
  LONGS_EQUAL(0, kernel.last_flags);
}

TEST(CanIo, NoFrameEverIsNotTrusted) {
  Rig rig;
  io::SensorSample s{};
  CHECK_FALSE(rig.sensors.read(s));
  LONGS_EQUAL(io::kStaleFrame, s.status_flags);
}

// The real kernel over the CAN seam: frames stop -> the supervisor latches
// kStaleFrames on the 3rd consecutive stale tick (max_consecutive_stale_frames
// = 2, i.e. 1.2 ms after the last frame) and the outputs are zero current.
TEST(CanIo, RealKernelLatchesStaleFramesWithinThreeTicks) {
  Rig rig;
  static kernel::Controller<float> controller;  // large: keep it off the stack
  app::ServoLoop<kernel::Controller<float>> loop(rig.sensors, rig.actuators, controller, app::ServoConfig{},
                                                 app::ServoHooks{});
  for (std::uint32_t k = 0; k < 20; ++k) {
    rig.send_sensor(0, static_cast<std::uint8_t>(k));
    loop.on_tick();
  }
  CHECK(controller.status().fault == kernel::FaultCode::kNone);
  const std::uint16_t bound = controller.config().supervisor.max_consecutive_stale_frames;
  LONGS_EQUAL(2, bound);
  for (std::uint16_t k = 1; k <= bound; ++k) {
    loop.on_tick();
    CHECK(controller.status().fault == kernel::FaultCode::kNone);  // tolerated
  }
  loop.on_tick();  // stale tick bound + 1
  CHECK(controller.status().fault == kernel::FaultCode::kStaleFrames);
  CHECK(controller.status().reaction != kernel::FaultReaction::kNone);
  // The kernel's own output is zero current with the amplifiers off.
  io::SensorSample s{};
  s.status_flags = io::kStaleFrame;
  const io::ActuatorCommand out = controller.step(s, false);
  CHECK_FALSE(out.amplifier_enable);
  for (int j = 0; j < io::kCoils; ++j) LONGS_EQUAL(0, out.dac_code[j]);
}
