// hil::ControllerNode runs firmware/app's ServoLoop over CanSensorSource /
// CanActuatorSink (label hil). The plant side of the virtual bus is driven by
// hand: frames in, the node's frames out, compared with a reference
// kernel::Controller<float> stepped on the same samples.
#include <cstring>
#include <memory>
#include <vector>

#include "maglev/app/telemetry.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;

namespace {

struct Bench {
  std::shared_ptr<can::VirtualBus> bus = std::make_shared<can::VirtualBus>("node-test");
  std::unique_ptr<can::VirtualCanPort> plant_port = bus->open_endpoint();
  std::unique_ptr<can::VirtualCanPort> ctrl_port = bus->open_endpoint();
  can::BusLoadMeter meter;
  hil::CanServoIo cio{*ctrl_port, &meter};
  hil::ControllerNode node{hil::KernelKind::kFloat32, cio};
  hil::Plant plant{hil::PlantConfig::Default(), 3};
  can::LinkReceiver prx;
  std::uint8_t cmd_counter = 0;

  io::SensorSample send_sensor(std::uint8_t counter) {
    const io::SensorSample s = plant.sample();
    can::CanFrame f{};
    can::encode_sensor(s, counter, f);
    CHECK_TRUE(plant_port->send(f) == can::PortStatus::kOk);
    return s;
  }
  void send_command(can::HostCommandCode code, std::uint16_t seq) {
    can::HostCommandFrame h{};
    h.code = code;
    h.seq = seq;
    can::CanFrame f{};
    can::encode_host_command(h, cmd_counter++, f);
    CHECK_TRUE(plant_port->send(f) == can::PortStatus::kOk);
  }
  // Everything the node sent, accepted by the plant's receiver.
  std::vector<can::CanFrame> drain() {
    std::vector<can::CanFrame> out;
    can::CanFrame f{};
    while (plant_port->pending() > 0 && plant_port->receive(f, 0) == can::PortStatus::kOk) {
      CHECK_TRUE(prx.accept(f) == can::RxStatus::kOk);
      out.push_back(f);
    }
    return out;
  }
};

bool is(const can::CanFrame& f, can::MessageKind k) { return f.id == can::message(k).can_id; }

}  // namespace

TEST_GROUP(ControllerNode){};

TEST(ControllerNode, StepsTheKernelThroughServoLoopAndAnswersTheSensorCounter) {
  Bench b;
  kernel::Controller<float> ref;
  // No sensor frame yet: no tick, even in lockstep (nothing to repeat).
  CHECK_FALSE(b.node.run_once(0, true));
  LONGS_EQUAL(0, b.node.ticks());
  for (std::uint8_t n = 0; n < 5; ++n) {
    const io::SensorSample s = b.send_sensor(static_cast<std::uint8_t>(40 + n));
    CHECK_TRUE(b.node.run_once(0));
    const io::ActuatorCommand want = ref.step(s, false);
    const auto frames = b.drain();
    LONGS_EQUAL(1, frames.size());
    CHECK_TRUE(is(frames[0], can::MessageKind::kActuator));
    LONGS_EQUAL(40 + n, can::frame_counter(frames[0]));  // answers the sensor frame's counter
    io::ActuatorCommand got{};
    can::decode_actuator(frames[0], got);
    CHECK_TRUE(std::memcmp(want.dac_code, got.dac_code, sizeof want.dac_code) == 0);
    CHECK_EQUAL(want.amplifier_enable, got.amplifier_enable);
    b.plant.advance_tick();
  }
  LONGS_EQUAL(5, b.node.ticks());
  LONGS_EQUAL(5, b.node.servo_ticks());                 // app::ServoLoop ran every tick
  LONGS_EQUAL(5, b.cio.sensors().stats().fresh);        // app::CanSensorSource served them
  LONGS_EQUAL(5, b.node.link_stats().fresh_ticks);
  LONGS_EQUAL(ref.status().tick, b.node.status().tick);
}

TEST(ControllerNode, HostCommandIsExecutedBeforeTheStepAckedAndNeverReachesTheApp) {
  Bench b;
  kernel::Controller<float> ref;
  b.send_command(can::HostCommandCode::kLevitate, 7);
  const io::SensorSample s = b.send_sensor(0);
  CHECK_TRUE(b.node.run_once(0));
  kernel::MotionCommand lev;
  lev.type = kernel::MotionType::kLevitate;
  const auto want_result = static_cast<std::uint8_t>(ref.command(lev));
  const auto want_state = static_cast<std::uint8_t>(ref.status().state);
  ref.step(s, false);
  const auto frames = b.drain();
  LONGS_EQUAL(2, frames.size());  // the ack first (before the step), then the actuator frame
  CHECK_TRUE(is(frames[0], can::MessageKind::kHostCommandAck));
  CHECK_TRUE(is(frames[1], can::MessageKind::kActuator));
  can::HostCommandAckFrame ack{};
  can::decode_host_command_ack(frames[0], ack);
  LONGS_EQUAL(7, ack.seq);
  LONGS_EQUAL(want_result, ack.result);
  LONGS_EQUAL(want_state, ack.sequencer_state);
  LONGS_EQUAL(0, ack.tick);
  LONGS_EQUAL(1, b.node.link_stats().host_commands);
  CHECK_TRUE(ref.status().state == b.node.status().state);
  LONGS_EQUAL(0, b.cio.sensors().stats().ignored);  // the app never saw it
  LONGS_EQUAL(2, b.cio.rx_stats().accepted);         // the node's receiver saw both
  // Shutdown: acknowledged as not executed, no tick, stop requested.
  b.send_command(can::HostCommandCode::kShutdown, 8);
  CHECK_FALSE(b.node.run_once(0, true));
  CHECK_TRUE(b.cio.stop_requested());
  const auto f2 = b.drain();
  LONGS_EQUAL(1, f2.size());
  can::decode_host_command_ack(f2[0], ack);
  LONGS_EQUAL(8, ack.seq);
  LONGS_EQUAL(can::kHostResultNotExecuted, ack.result);
  LONGS_EQUAL(1, b.node.ticks());
}

TEST(ControllerNode, MissingFramesRunTheAppsStaleAndLinkLostPath) {
  Bench b;
  b.send_sensor(0);
  CHECK_TRUE(b.node.run_once(0, true));
  b.drain();
  // Not lockstep: a missing frame is no tick.
  CHECK_FALSE(b.node.run_once(0, false));
  // Lockstep: ticks 1..3 stale (1.2 ms: watchdog not yet expired), tick 4 link lost.
  for (int n = 1; n <= 4; ++n) CHECK_TRUE(b.node.run_once(0, true));
  LONGS_EQUAL(0, b.drain().size());  // stale ticks answer nothing
  const auto& ls = b.node.link_stats();
  LONGS_EQUAL(4, ls.stale_ticks);
  LONGS_EQUAL(1, ls.first_stale_tick);
  LONGS_EQUAL(1, ls.link_lost_ticks);
  LONGS_EQUAL(4, ls.first_link_lost_tick);
  LONGS_EQUAL(4, b.cio.sensors().stats().stale);
  LONGS_EQUAL(4, b.cio.actuators().stats().unanswered);
  LONGS_EQUAL(1, b.node.sensor_faults());  // ServoLoop: read() false -> kAdcFault + safe preset
  CHECK_TRUE(b.node.sensor_watchdog().expired());
  LONGS_EQUAL(1, b.node.sensor_watchdog().timeouts());
  CHECK_FALSE(b.node.last_output().amplifier_enable);
  // The supervisor latched the stale frames (3rd consecutive stale sample).
  CHECK_TRUE(b.node.status().first_fault.code == kernel::FaultCode::kStaleFrames);
  // A frame again: fresh, answered.
  b.send_sensor(1);
  CHECK_TRUE(b.node.run_once(0, true));
  LONGS_EQUAL(1, b.drain().size());
}

// Two-process mode ticks on frames, not on a timer: a frame whose counter is
// beyond the next tick's stands for the periods whose frames were lost, and
// those run first as stale ticks (docs/CAN.md "Watchdogs"). It used to skip
// them: the kernel fell a tick behind the plant per lost frame, never saw a
// stale sample, and stayed Ready while the plant cut the amplifiers.
TEST(ControllerNode, ALostSensorFrameIsAStaleTickWhenItsSuccessorArrives) {
  Bench b;
  b.send_sensor(0);
  CHECK_TRUE(b.node.run_once(0));
  b.drain();
  b.send_sensor(2);  // frame 1 lost
  CHECK_TRUE(b.node.run_once(0));
  LONGS_EQUAL(3, b.node.ticks());
  LONGS_EQUAL(1, b.node.link_stats().stale_ticks);
  LONGS_EQUAL(1, b.node.link_stats().first_stale_tick);
  LONGS_EQUAL(2, b.node.link_stats().fresh_ticks);
  const auto frames = b.drain();
  LONGS_EQUAL(1, frames.size());  // the stale tick answers nothing
  CHECK_TRUE(is(frames[0], can::MessageKind::kActuator));
  LONGS_EQUAL(2, can::frame_counter(frames[0]));
  b.send_sensor(3);  // on time again: no catch-up
  CHECK_TRUE(b.node.run_once(0));
  LONGS_EQUAL(4, b.node.ticks());
  LONGS_EQUAL(1, b.node.link_stats().stale_ticks);
}

TEST(ControllerNode, AnOutageSeenOnlyByItsEndStillTripsTheFrameWatchdog) {
  Bench b;
  std::vector<std::size_t> rows;
  b.node.after_tick = [&]() { rows.push_back(b.node.ticks()); };
  b.send_sensor(0);
  CHECK_TRUE(b.node.run_once(0));
  b.drain();
  // Frames 1..5 lost; 6 jumps further than the receiver allows (rejected, it
  // resynchronises on it); 7 is accepted: ticks 1..6 ran unseen.
  b.send_sensor(6);
  CHECK_FALSE(b.node.run_once(0));
  b.send_sensor(7);
  CHECK_TRUE(b.node.run_once(0));
  LONGS_EQUAL(8, b.node.ticks());
  LONGS_EQUAL(8, rows.size());  // after_tick: one row per tick, the stale ones included
  const auto& ls = b.node.link_stats();
  LONGS_EQUAL(6, ls.stale_ticks);
  LONGS_EQUAL(1, ls.first_stale_tick);
  CHECK_TRUE(ls.link_lost_ticks >= 1);
  LONGS_EQUAL(4, ls.first_link_lost_tick);  // > 1.2 ms of silence, as on the board
  CHECK_TRUE(b.node.status().first_fault.code == kernel::FaultCode::kStaleFrames);
  // One actuator frame, answering 7 (the plant's receiver would call it a
  // jump after 0: read raw here; the plant pairs frames by counter).
  std::vector<can::CanFrame> frames;
  for (can::CanFrame f{}; b.plant_port->pending() > 0 && b.plant_port->receive(f, 0) == can::PortStatus::kOk;) {
    frames.push_back(f);
  }
  LONGS_EQUAL(1, frames.size());
  CHECK_TRUE(is(frames[0], can::MessageKind::kActuator));
  LONGS_EQUAL(7, can::frame_counter(frames[0]));
}

TEST(ControllerNode, NewestOfSeveralQueuedSensorFramesWinsAndTelemetryKeepsCatalogTicks) {
  Bench b;
  b.send_sensor(10);
  b.send_sensor(11);
  CHECK_TRUE(b.node.run_once(0));
  LONGS_EQUAL(1, b.cio.superseded());
  auto frames = b.drain();
  LONGS_EQUAL(1, frames.size());
  LONGS_EQUAL(11, can::frame_counter(frames[0]));
  // Ticks 2..250: status on ticks 10, 20, ..., 250 (25 frames), heartbeat on 250.
  int status = 0, heartbeats = 0;
  can::ControllerStatusFrame last{};
  for (int n = 2; n <= 250; ++n) {
    b.send_sensor(static_cast<std::uint8_t>(10 + n));
    CHECK_TRUE(b.node.run_once(0));
    for (const auto& f : b.drain()) {
      if (is(f, can::MessageKind::kControllerStatus)) {
        ++status;
        CHECK_TRUE(n % 10 == 0);
        can::decode_controller_status(f, last);
      }
      if (is(f, can::MessageKind::kHeartbeatController)) {
        ++heartbeats;
        LONGS_EQUAL(250, n);
      }
    }
  }
  LONGS_EQUAL(25, status);
  LONGS_EQUAL(1, heartbeats);
  // The payload is the firmware's telemetry binding.
  const can::ControllerStatusFrame want = app::to_status_frame(b.node.status());
  LONGS_EQUAL(want.tick, last.tick);
  LONGS_EQUAL(want.pose_nm_nrad[2], last.pose_nm_nrad[2]);
  LONGS_EQUAL(want.sequencer_state, last.sequencer_state);
  // The meter counted every frame the node sent: 250 actuator + 25 status + 1 heartbeat.
  LONGS_EQUAL(276, b.meter.frames());
}
