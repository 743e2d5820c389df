// lab::Recorder: the signal table, triggers (immediate, command, level with
// pre-trigger, fault), decimation, the ring and its readout, and refusals
// (nothing changes).
#include <cstring>
#include <memory>

#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/signals.hpp"
#include "maglev/register_schema/register_map.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::lab;

namespace {

float g_pool[kBoardPoolWords];

// A status whose x pose is `n` um and x error is `n` nm: the recorded values name their tick.
kernel::ControllerStatus status_at(int n) {
  kernel::ControllerStatus st{};
  st.pose.pico[0] = static_cast<std::int64_t>(n) * 1000000;  // n um
  st.reference.pico[0] = st.pose.pico[0] + static_cast<std::int64_t>(n) * 1000;
  st.effort_A[3] = 0.5f;
  st.state = kernel::SequencerState::kReady;
  return st;
}

RecorderConfig two_channels(std::uint32_t length, std::uint32_t pre, TriggerMode mode) {
  RecorderConfig c{};
  c.channel_count = 2;
  c.channel[0] = find_signal("x.pose");
  c.channel[1] = find_signal("x.error");
  c.length = length;
  c.pretrigger = pre;
  c.mode = mode;
  return c;
}

}  // namespace

TEST_GROUP(Signals){};

TEST(Signals, NamesRoundTripAndUnknownIdsAreRefused) {
  char buf[40];
  int known = 0;
  for (std::uint16_t id = 0; id < kSignalIdEnd + 5; ++id) {
    if (!signal_name(id, buf, sizeof buf)) {
      CHECK_FALSE(signal_known(id));
      continue;
    }
    ++known;
    CHECK_EQUAL(id, find_signal(buf));
  }
  CHECK_EQUAL(kSignalIdEnd - 1, known);  // ids 1 .. end-1, no gaps
  STRCMP_EQUAL("theta_z.pose", (signal_name(find_signal("theta_z.pose"), buf, sizeof buf), buf));
  STRCMP_EQUAL("rad", signal_unit(find_signal("theta_x.error")));
  STRCMP_EQUAL("m", signal_unit(find_signal("z.reference")));
  STRCMP_EQUAL("A", signal_unit(find_signal("coil8.current")));
  CHECK_EQUAL(0, find_signal("x.nonsense"));
  // The register map's signal-id range is the table's.
  CHECK_EQUAL(kSignalIdEnd - 1, static_cast<int>(modbus::def(modbus::RegId::rec_channel_0).max));
}

TEST(Signals, FaultWatchIsTheRegisterDefaults) {
  const RecorderConfig c = fault_watch_config(2500.0f);
  using modbus::RegId;
  CHECK_EQUAL(static_cast<int>(modbus::def(RegId::rec_channel_count).default_value), c.channel_count);
  for (int i = 0; i < kMaxChannels; ++i) {
    CHECK_EQUAL(static_cast<int>(modbus::def(static_cast<RegId>(static_cast<int>(RegId::rec_channel_0) + i)).default_value),
                c.channel[i]);
  }
  CHECK_EQUAL(static_cast<std::uint32_t>(modbus::def(RegId::rec_length).default_value), c.length);
  CHECK_EQUAL(static_cast<std::uint32_t>(modbus::def(RegId::rec_pretrigger).default_value), c.pretrigger);
  CHECK_EQUAL(static_cast<int>(modbus::def(RegId::rec_trigger_mode).default_value), static_cast<int>(c.mode));
}

TEST_GROUP(Recorder) {
  std::unique_ptr<Recorder> r;
  void setup() override { r = std::make_unique<Recorder>(g_pool, kBoardPoolWords); }
  void run(int from, int to) {
    for (int n = from; n < to; ++n) r->sample(status_at(n), io::SensorSample{});
  }
};

TEST(Recorder, CapacityIs16kSamplesAtEightChannels) {
  CHECK_EQUAL(16384u, r->capacity(8));
  CHECK_EQUAL(131072u, r->capacity(1));
}

TEST(Recorder, IdleRecordsNothing) {
  CHECK(r->configure(two_channels(10, 0, TriggerMode::kImmediate)) == RecorderError::kOk);
  run(0, 100);
  CHECK(r->state() == RecorderState::kIdle);
  CHECK_EQUAL(0u, r->captured());
}

TEST(Recorder, ImmediateWithPretrigger) {
  CHECK(r->configure(two_channels(100, 30, TriggerMode::kImmediate)) == RecorderError::kOk);
  CHECK(r->arm() == RecorderError::kOk);
  run(0, 99);
  CHECK(r->state() == RecorderState::kTriggered);
  run(99, 200);
  CHECK(r->state() == RecorderState::kDone);
  CHECK_EQUAL(100u, r->captured());
  CHECK_EQUAL(30u, r->trigger_index());
  for (std::uint32_t s = 0; s < 100; ++s) {
    DOUBLES_EQUAL(static_cast<double>(s) * 1e-6, r->at(2 * s), 1e-15 + 1e-7 * static_cast<double>(s) * 1e-6);      // x.pose = tick um
    DOUBLES_EQUAL(static_cast<double>(s) * 1e-9, r->at(2 * s + 1), 1e-16 + 1e-7 * static_cast<double>(s) * 1e-9);  // x.error = tick nm
  }
  CHECK_EQUAL(1, r->capture_id());
}

TEST(Recorder, LevelTriggerKeepsThePretriggerSamplesAcrossTheRingWrap) {
  // 8 channels: ring of 16384; trigger after more than one ring of history.
  RecorderConfig c = two_channels(1000, 400, TriggerMode::kLevel);
  c.channel_count = 8;
  for (int i = 2; i < 8; ++i) c.channel[i] = find_signal("z.effort");
  c.trigger_signal = find_signal("x.pose");
  c.level = 20000e-6f;  // x.pose crosses 20 mm at tick 20000
  c.edge = TriggerEdge::kRising;
  CHECK(r->configure(c) == RecorderError::kOk);
  CHECK(r->arm() == RecorderError::kOk);
  run(0, 20000);
  CHECK(r->state() == RecorderState::kArmed);
  run(20000, 21000);
  CHECK(r->state() == RecorderState::kDone);
  CHECK_EQUAL(400u, r->trigger_index());
  // The trigger sample is the first at/above the level.
  DOUBLES_EQUAL(20000e-6, r->at(400 * 8), 1e-8);
  DOUBLES_EQUAL(19999e-6, r->at(399 * 8), 1e-8);
  DOUBLES_EQUAL(19600e-6, r->at(0), 1e-8);
  DOUBLES_EQUAL(20599e-6, r->at(999 * 8), 1e-8);
  DOUBLES_EQUAL(0.5, r->at(999 * 8 + 7), 1e-8);
}

TEST(Recorder, FallingEdgeDoesNotFireOnRisingSignal) {
  RecorderConfig c = two_channels(10, 0, TriggerMode::kLevel);
  c.trigger_signal = find_signal("x.pose");
  c.level = 50e-6f;
  c.edge = TriggerEdge::kFalling;
  CHECK(r->configure(c) == RecorderError::kOk);
  CHECK(r->arm() == RecorderError::kOk);
  run(0, 200);
  CHECK(r->state() == RecorderState::kArmed);
}

TEST(Recorder, FaultTriggerKeepsTheSecondBeforeTheFault) {
  CHECK(r->configure(fault_watch_config(2500.0f)) == RecorderError::kOk);
  CHECK(r->arm() == RecorderError::kOk);
  for (int n = 0; n < 10000; ++n) {
    kernel::ControllerStatus st = status_at(n);
    if (n >= 7000) {
      st.fault = kernel::FaultCode::kAdcFault;
      st.state = kernel::SequencerState::kFault;
    }
    r->sample(st, io::SensorSample{});
  }
  CHECK(r->state() == RecorderState::kDone);
  CHECK_EQUAL(2500u, r->trigger_index());
  // Channel 0 x.pose, channel 7 fault: the fault appears exactly at the trigger sample.
  DOUBLES_EQUAL(4500e-6, r->at(0), 1e-8);
  DOUBLES_EQUAL(0.0, r->at(2499 * 8 + 7), 0.0);
  CHECK(r->at(2500 * 8 + 7) > 0.0f);
}

TEST(Recorder, CommandTriggerAndDecimation) {
  RecorderConfig c = two_channels(10, 2, TriggerMode::kCommand);
  c.decimation = 5;
  CHECK(r->configure(c) == RecorderError::kOk);
  CHECK(r->trigger() == RecorderError::kNotArmed);
  CHECK(r->arm() == RecorderError::kOk);
  run(0, 100);
  CHECK(r->state() == RecorderState::kArmed);
  CHECK(r->trigger() == RecorderError::kOk);
  run(100, 200);
  CHECK(r->state() == RecorderState::kDone);
  // Every 5th tick: 0, 5, ..., the trigger at the first recorded tick >= 100.
  DOUBLES_EQUAL(100e-6, r->at(2 * 2), 1e-8);
  DOUBLES_EQUAL(95e-6, r->at(2 * 1), 1e-8);
  DOUBLES_EQUAL(135e-6, r->at(2 * 9), 1e-8);
}

TEST(Recorder, RefusalsChangeNothing) {
  const RecorderConfig good = two_channels(100, 10, TriggerMode::kImmediate);
  CHECK(r->configure(good) == RecorderError::kOk);
  RecorderConfig c = good;
  c.channel[1] = 999;
  CHECK(r->configure(c) == RecorderError::kUnknownSignal);
  c = good;
  c.channel_count = 9;
  CHECK(r->configure(c) == RecorderError::kChannelCount);
  c = good;
  c.channel_count = 8;
  for (int i = 0; i < 8; ++i) c.channel[i] = 1;
  c.length = 16385;
  CHECK(r->configure(c) == RecorderError::kLength);
  c = good;
  c.pretrigger = 100;
  CHECK(r->configure(c) == RecorderError::kPretrigger);
  c = good;
  c.mode = TriggerMode::kLevel;
  c.trigger_signal = 0;
  CHECK(r->configure(c) == RecorderError::kUnknownSignal);
  CHECK_EQUAL(2, r->config().channel_count);
  CHECK_EQUAL(100u, r->config().length);
  CHECK(r->arm() == RecorderError::kOk);
  CHECK(r->configure(good) == RecorderError::kBusy);
  CHECK(r->arm() == RecorderError::kBusy);
  CHECK(r->state() == RecorderState::kArmed);
}
