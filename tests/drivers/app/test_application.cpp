// firmware/app Application<float> with the real kernel, register map,
// persistence (RamFlash) and the virtual CAN bus: Modbus RTU fed byte-wise,
// telemetry rate and content, watchdog feed policy, persistence boot.
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "maglev/app/application.hpp"
#include "maglev/app/can_io.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/app/telemetry.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/modbus/crc16.hpp"
#include "maglev/persistence/flash.hpp"
#include "maglev/virtual_can/virtual_can.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;
using App = app::Application<float, 64>;

namespace {

struct CapturingUart final : app::ByteSink {
  std::vector<std::uint8_t> bytes;
  int frames = 0;
  bool transmit(const std::uint8_t* d, std::size_t n) override {
    bytes.assign(d, d + n);
    ++frames;
    return true;
  }
};
struct CountingDog final : app::WatchdogFeeder {
  int feeds = 0;
  void feed() override { ++feeds; }
};

int g_critical_depth = 0;
int g_critical_sections = 0;
void enter() {
  ++g_critical_depth;
  ++g_critical_sections;
}
void exit_() { --g_critical_depth; }
int g_long_ops = 0;
void long_op(bool begin) { g_long_ops += begin ? 1 : 0; }

constexpr std::size_t kSector = 4096;
static_assert(persistence::kRecordBytes <= kSector);

struct Fixture {
  // The kernel is large: on the heap, one per test.
  std::unique_ptr<kernel::Controller<float>> kernel_storage = std::make_unique<kernel::Controller<float>>();
  kernel::Controller<float>& kernel = *kernel_storage;
  std::shared_ptr<can::VirtualBus> bus = std::make_shared<can::VirtualBus>("app-services");
  std::unique_ptr<can::VirtualCanPort> node = bus->open_endpoint();
  std::unique_ptr<can::VirtualCanPort> plant = bus->open_endpoint();
  std::vector<std::uint8_t> flash_mem = std::vector<std::uint8_t>(2 * kSector, 0xFF);
  persistence::RamFlash flash{flash_mem.data(), kSector, 2};
  persistence::ConfigStore store{flash, 0, 1};
  CapturingUart uart;
  CountingDog dog;
  drivers::iwdg::FeedGate gate;
  app::Recorder<64> recorder;
  app::ApplicationHooks hooks{&enter, &exit_, &long_op, nullptr};
};


std::vector<std::uint8_t> rtu_request(std::vector<std::uint8_t> pdu_with_unit) {
  const std::uint16_t crc = modbus::crc16(pdu_with_unit.data(), pdu_with_unit.size());
  pdu_with_unit.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  pdu_with_unit.push_back(static_cast<std::uint8_t>(crc >> 8));
  return pdu_with_unit;
}

}  // namespace

TEST_GROUP(Application) {
  void setup() override {
    g_critical_depth = 0;
    g_critical_sections = 0;
    g_long_ops = 0;
  }
};

TEST(Application, ModbusRtuRequestFedBytewiseGetsTheRightReply) {
  Fixture fx;
  App application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  // Read holding registers 0..1 (id.magic, and the next one) from unit 1.
  const auto req = rtu_request({0x01, 0x03, 0x00, 0x00, 0x00, 0x01});
  std::uint32_t t = 1000;
  for (std::uint8_t b : req) {
    application.on_uart_byte(b, t);
    application.service(t + 10, 0);  // mid-frame polls must not cut the frame
    t += 87;                         // one 11-bit character at 115200 baud
  }
  LONGS_EQUAL(0, fx.uart.frames);
  application.service(t + 1000, 0);  // less than t3.5 (1750 us) of silence
  LONGS_EQUAL(0, fx.uart.frames);
  application.service(t + 1800, 0);
  LONGS_EQUAL(1, fx.uart.frames);
  const auto want = rtu_request({0x01, 0x03, 0x02, 0x4D, 0x4C});  // 0x4D4C 'ML'
  LONGS_EQUAL(want.size(), fx.uart.bytes.size());
  for (std::size_t i = 0; i < want.size(); ++i) LONGS_EQUAL(want[i], fx.uart.bytes[i]);
  LONGS_EQUAL(1, application.rtu().stats().frames);
  LONGS_EQUAL(0, g_critical_depth);

  // Status read through the guarded device: status.state (100) = kIdle = 0,
  // taken inside the critical section.
  const int before = g_critical_sections;
  const auto req2 = rtu_request({0x01, 0x04, 0x00, 100, 0x00, 0x01});
  for (std::uint8_t b : req2) {
    application.on_uart_byte(b, t);
    t += 87;
  }
  application.service(t + 2000, 0);
  LONGS_EQUAL(2, fx.uart.frames);
  const auto want2 = rtu_request({0x01, 0x04, 0x02, 0x00, 0x00});
  LONGS_EQUAL(want2.size(), fx.uart.bytes.size());
  for (std::size_t i = 0; i < want2.size(); ++i) LONGS_EQUAL(want2[i], fx.uart.bytes[i]);
  CHECK(g_critical_sections > before);
  LONGS_EQUAL(0, g_critical_depth);
}

TEST(Application, TelemetryAtTheCatalogRateWithTheKernelStatus) {
  Fixture fx;
  kernel::Controller<float>& kernel = fx.kernel;
  App application(kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  can::LinkReceiver rx;
  int status_frames = 0;
  int heartbeats = 0;
  std::uint32_t first_status_tick = 0;
  std::uint32_t last_status_tick = 0;
  io::SensorSample s{};
  for (std::uint32_t tick = 1; tick <= 500; ++tick) {
    (void)kernel.step(s, false);
    application.service(tick * 400u, tick);
    can::CanFrame f{};
    while (fx.plant->receive(f, 0) == can::PortStatus::kOk) {
      CHECK(rx.accept(f) == can::RxStatus::kOk);  // CRC, length, consecutive counters
      if (f.id == can::message(can::MessageKind::kControllerStatus).can_id) {
        can::ControllerStatusFrame got{};
        can::decode_controller_status(f, got);
        const can::ControllerStatusFrame want = app::to_status_frame(kernel.status());
        LONGS_EQUAL(kernel.status().tick, got.tick);
        LONGS_EQUAL(want.sequencer_state, got.sequencer_state);
        LONGS_EQUAL(want.fault_code, got.fault_code);
        LONGS_EQUAL(want.scale_k_e4, got.scale_k_e4);
        LONGS_EQUAL(want.pose_nm_nrad[0], got.pose_nm_nrad[0]);
        if (status_frames == 0) first_status_tick = got.tick;
        if (status_frames > 0) LONGS_EQUAL(10, got.tick - last_status_tick);  // 250 Hz at 2.5 kHz
        last_status_tick = got.tick;
        ++status_frames;
      } else if (f.id == can::message(can::MessageKind::kHeartbeatController).can_id) {
        can::HeartbeatFrame hb{};
        can::decode_heartbeat(f, hb);
        CHECK(hb.node_state == can::NodeState::kOperational);
        LONGS_EQUAL((tick - 1) * 400u / 1000u, hb.uptime_ms);  // uptime since the first service
        ++heartbeats;
      } else {
        FAIL("unexpected frame");
      }
    }
  }
  LONGS_EQUAL(50, status_frames);  // 500 ticks / 10
  LONGS_EQUAL(2, heartbeats);      // 500 ticks / 250
  LONGS_EQUAL(1, first_status_tick);
  LONGS_EQUAL(50, application.stats().status_frames);
  LONGS_EQUAL(0, application.stats().can_tx_errors);
  // A loop that stalled for 95 ticks sends one status frame, not nine.
  application.service(595u * 400u, 595);
  can::CanFrame f{};
  int burst = 0;
  while (fx.plant->receive(f, 0) == can::PortStatus::kOk) burst += f.id == can::message(can::MessageKind::kControllerStatus).can_id;
  LONGS_EQUAL(1, burst);
}

TEST(Application, StatusFrameConversion) {
  kernel::ControllerStatus st{};
  st.pose[maglev::kernel::Axis::kX] = 1'234'567;        // 1234.567 nm -> 1235
  st.pose[maglev::kernel::Axis::kY] = -1'234'500;       // -1234.5 nm -> -1235 (half away from zero)
  st.pose[maglev::kernel::Axis::kZ] = 20'000'000;       // 20 um
  st.pose[maglev::kernel::Axis::kThetaZ] = -4'000'000'000'000'000;  // saturates
  st.state = kernel::SequencerState::kReady;
  st.fault = kernel::FaultCode::kStaleFrames;
  st.saturated = true;
  st.scale_k = 0.5f;
  const float currents[io::kCoils] = {0.25f, -4.0f, 1.0f, 4.0f, 0.0f, -0.5f, 2.0f, -3.9996f};
  for (int j = 0; j < io::kCoils; ++j) st.coil_current_A[j] = currents[j];
  st.tick = 777;
  const can::ControllerStatusFrame f = app::to_status_frame(st);
  LONGS_EQUAL(1235, f.pose_nm_nrad[0]);
  LONGS_EQUAL(-1235, f.pose_nm_nrad[1]);
  LONGS_EQUAL(20000, f.pose_nm_nrad[2]);
  LONGS_EQUAL(INT32_MIN, f.pose_nm_nrad[5]);
  LONGS_EQUAL(static_cast<int>(kernel::SequencerState::kReady), f.sequencer_state);
  LONGS_EQUAL(static_cast<int>(kernel::FaultCode::kStaleFrames), f.fault_code);
  LONGS_EQUAL(5000, f.scale_k_e4);
  LONGS_EQUAL(250, f.current_command_mA[0]);
  LONGS_EQUAL(-4000, f.current_command_mA[1]);
  LONGS_EQUAL(-4000, f.current_command_mA[7]);
  LONGS_EQUAL(0x8A, f.saturation_flags);  // coils 2, 4, 8 are at |i| = 4 A (within 0.1 %)
  LONGS_EQUAL(777, f.tick);
  st.saturated = false;
  LONGS_EQUAL(0, app::to_status_frame(st).saturation_flags);
}

namespace {
struct NullKernel {
  io::ActuatorCommand step(const io::SensorSample&, bool) { return io::kSafeActuatorCommand; }
};
struct NullSensors final : app::SensorSource {
  bool read(io::SensorSample&) override { return true; }
};
struct NullSink final : app::ActuatorSink {
  void write(const io::ActuatorCommand&) override {}
};
drivers::iwdg::FeedGate* g_gate = nullptr;
void servo_ran() { g_gate->servo_ran(); }
}  // namespace

TEST(Application, WatchdogFedOnlyWhenServoAndCommsBothRan) {
  Fixture fx;
  App application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  g_gate = &fx.gate;
  NullKernel k;
  NullSensors sensors;
  NullSink sink;
  app::ServoLoop<NullKernel> loop(sensors, sink, k, app::ServoConfig{}, app::ServoHooks{nullptr, nullptr, &servo_ran, nullptr});

  // Both ran: fed.
  loop.on_tick();
  application.service(0, 1);
  LONGS_EQUAL(1, fx.dog.feeds);
  // Servo stalled: comms keep running but the dog starves.
  for (int i = 0; i < 50; ++i) application.service(100u * static_cast<std::uint32_t>(i), 1);
  LONGS_EQUAL(1, fx.dog.feeds);
  LONGS_EQUAL(50, fx.gate.withheld());
  // Comms stalled: the servo keeps ticking, nobody feeds.
  for (int i = 0; i < 50; ++i) loop.on_tick();
  LONGS_EQUAL(1, fx.dog.feeds);
  // Comms back: one feed for the window, then again only after the next tick.
  application.service(10'000, 51);
  LONGS_EQUAL(2, fx.dog.feeds);
  application.service(10'400, 51);
  LONGS_EQUAL(2, fx.dog.feeds);
  loop.on_tick();
  application.service(10'800, 52);
  LONGS_EQUAL(3, fx.dog.feeds);
}

namespace {
// A cycle counter that advances g_step cycles per read: a tick (two reads) takes g_step.
std::uint32_t g_cycles = 0;
std::uint32_t g_step = 1000;
std::uint32_t fake_cycles() {
  g_cycles += g_step;
  return g_cycles;
}
std::uint32_t read_i32(const modbus::RegisterServer& r, modbus::RegId id) {
  const modbus::RegisterDef& d = modbus::def(id);
  std::uint16_t w[2] = {0, 0};
  CHECK(r.read_registers(d.address, 2, w) == modbus::ExceptionCode::kNone);
  return (static_cast<std::uint32_t>(w[0]) << 16) | w[1];  // I32: high word first
}
}  // namespace

TEST(Application, ServoTimingRegistersReadTheLoopsOwnCounters) {
  Fixture fx;
  App application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  NullKernel k;
  NullSensors sensors;
  NullSink sink;
  // Budget 1500 cycles: the 2500-cycle tick below is an overrun.
  app::ServoLoop<NullKernel> loop(sensors, sink, k, app::ServoConfig{1500, 3000, 3},
                                  app::ServoHooks{&fake_cycles, nullptr, nullptr, nullptr});
  // Not attached: the registers exist and read 0 (the bench, the host server).
  LONGS_EQUAL(0, read_i32(application.registers(), modbus::RegId::servo_max_cycles));
  application.attach_servo_state(&loop.state());
  g_step = 1000;
  loop.on_tick();  // 1000 cycles
  g_step = 2500;
  loop.on_tick();  // 2500
  g_step = 1000;
  loop.on_tick();  // 1000
  LONGS_EQUAL(2500, read_i32(application.registers(), modbus::RegId::servo_max_cycles));
  LONGS_EQUAL(1000, read_i32(application.registers(), modbus::RegId::servo_last_cycles));
  LONGS_EQUAL(1, read_i32(application.registers(), modbus::RegId::servo_overruns));
  CHECK(g_critical_sections > 0);  // read with the tick masked
  LONGS_EQUAL(0, g_critical_depth);
}

TEST(Application, InterruptChainCyclesReadOverModbusOnceAttached) {
  Fixture fx;
  App application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  app::InterruptMeter meter;
  // Not attached (the bench, the host server, the HIL board): they read 0.
  LONGS_EQUAL(0, read_i32(application.registers(), modbus::RegId::servo_max_interrupt_cycles));
  application.attach_interrupt_meter(&meter.state());
  meter.begin_tick();
  meter.add(0, 7000);
  meter.begin_tick();
  meter.add(0, 6500);
  meter.begin_tick();
  LONGS_EQUAL(7000, read_i32(application.registers(), modbus::RegId::servo_max_interrupt_cycles));
  LONGS_EQUAL(6500, read_i32(application.registers(), modbus::RegId::servo_last_interrupt_cycles));
  // The servo registers stay unattached (they read 0) and independent.
  LONGS_EQUAL(0, read_i32(application.registers(), modbus::RegId::servo_max_cycles));
}

TEST(Application, RecorderIsDrainedOldestFirstAndLossCounted) {
  Fixture fx;
  App application(fx.kernel, nullptr, nullptr, nullptr, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  io::SensorSample s{};
  for (std::uint32_t i = 0; i < 10; ++i) {
    s.interferometer_counts[0] = i;
    fx.recorder.record(s, io::kSafeActuatorCommand);
  }
  application.service(0, 0);
  LONGS_EQUAL(10, application.stats().recorder_drained);
  LONGS_EQUAL(9, application.last_record().sample.interferometer_counts[0]);
  for (std::uint32_t i = 10; i < 110; ++i) {  // 100 more into a 64-entry ring
    s.interferometer_counts[0] = i;
    fx.recorder.record(s, io::kSafeActuatorCommand);
  }
  application.service(0, 0);
  LONGS_EQUAL(36, application.stats().recorder_lost);
  LONGS_EQUAL(74, application.stats().recorder_drained);
  LONGS_EQUAL(109, application.last_record().sample.interferometer_counts[0]);
}

TEST(Application, BootWithACorruptBankRaisesTheFlagAndUsesTheOtherBank) {
  Fixture fx;
  // Two saved records: payload mass 0.1 kg, then 0.2 kg (the newer one).
  modbus::ConfigImage image = modbus::image_from_kernel(kernel::default_kernel_config());
  image.set(modbus::RegId::payload_mass, 0.1);
  CHECK_TRUE(fx.store.save(image));
  image.set(modbus::RegId::payload_mass, 0.2);
  CHECK_TRUE(fx.store.save(image));
  // Find the bank holding sequence 2 by loading once, then corrupt its payload.
  persistence::ConfigStore probe(fx.flash, 0, 1);
  const persistence::LoadResult first = probe.load();
  CHECK((first.status.flags & (modbus::kLoadedBankA | modbus::kLoadedBankB)) != 0);
  DOUBLES_EQUAL(0.2, first.config.get(modbus::RegId::payload_mass), 1e-6);
  const bool newest_is_a = (first.status.flags & modbus::kLoadedBankA) != 0;
  fx.flash_mem[(newest_is_a ? 0 : kSector) + persistence::kFlashWordBytes + 5] ^= 0x10;

  kernel::Controller<float>& kernel = fx.kernel;
  persistence::ConfigStore store(fx.flash, 0, 1);
  App application(kernel, &store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  const modbus::PersistStatus p = application.persist_status();
  CHECK((p.flags & (newest_is_a ? modbus::kBankACorrupt : modbus::kBankBCorrupt)) != 0);
  CHECK((p.flags & (newest_is_a ? modbus::kLoadedBankB : modbus::kLoadedBankA)) != 0);
  CHECK((p.flags & modbus::kLoadedDefaults) == 0);
  // The older record was applied to the kernel.
  DOUBLES_EQUAL(0.1, kernel.config().payload_mass_kg, 1e-6);
  // And the flag is visible over Modbus (persist.flags, address 120).
  std::uint16_t flags_reg = 0;
  CHECK(application.registers().read_registers(120, 1, &flags_reg) == modbus::ExceptionCode::kNone);
  LONGS_EQUAL(p.flags, flags_reg);
}

TEST(Application, SaveOverModbusWritesFlashOutsideTheCriticalSection) {
  Fixture fx;
  kernel::Controller<float>& kernel = fx.kernel;
  App application(kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  CHECK((application.persist_status().flags & modbus::kLoadedDefaults) != 0);  // empty flash
  std::uint32_t t = 0;
  auto send = [&](std::vector<std::uint8_t> pdu) {
    for (std::uint8_t b : rtu_request(std::move(pdu))) {
      application.on_uart_byte(b, t);
      t += 87;
    }
    t += 2000;
    application.service(t, 0);
  };
  send({0x01, 0x06, 0x00, 210, 0x4E, 0x47});  // access.key = engineer
  send({0x01, 0x06, 0x00, 212, 0x00, 0x01});  // config.save = 1
  LONGS_EQUAL(2, fx.uart.frames);
  LONGS_EQUAL(0x06, fx.uart.bytes[1]);        // echo, no exception
  LONGS_EQUAL(1, g_long_ops);
  LONGS_EQUAL(1, application.stats().saves);
  persistence::ConfigStore probe(fx.flash, 0, 1);
  const persistence::LoadResult loaded = probe.load();
  CHECK((loaded.status.flags & (modbus::kLoadedBankA | modbus::kLoadedBankB)) != 0);
}

// The HIL node as the board's HIL image wires it: CanSensorSource owns RX on
// the shared port, Application only transmits (drain_can_rx = false) and
// reports the source's rejections in its heartbeat.
namespace {
// The board's HIL image wiring (stm32h743 main.cpp): one port, the source's
// receiver statistics and host-command queue handed to the Application.
app::ApplicationConfig hil_config(app::ApplicationConfig cfg) {
  cfg.drain_can_rx = false;
  return cfg;
}
app::ApplicationHooks hil_hooks(app::ApplicationHooks hooks, app::CanSensorSource& sensors) {
  hooks.rx_stats = &sensors.receiver();
  hooks.host_commands = &sensors.host_commands();
  return hooks;
}
struct HilNode {
  HilNode(Fixture& fx, const app::ApplicationConfig& cfg)
      : sensors(*fx.node, app::CanSensorConfig{}),
        actuators(*fx.node, sensors),
        application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog, hil_config(cfg),
                    hil_hooks(fx.hooks, sensors)),
        loop(sensors, actuators, fx.kernel, app::ServoConfig{}, app::ServoHooks{nullptr, nullptr, &servo_ran, nullptr}) {
    g_gate = &fx.gate;
  }
  app::CanSensorSource sensors;
  app::CanActuatorSink actuators;
  App application;
  app::ServoLoop<kernel::Controller<float>> loop;
};
}  // namespace

TEST(Application, HilWiringSharesOnePortAndReportsSourceRejections) {
  Fixture fx;
  app::ApplicationConfig cfg{};
  cfg.heartbeat_period_ticks = 20;
  cfg.sync_period_ticks = can::kSyncPeriodTicks;  // 25
  HilNode hil(fx, cfg);
  App& application = hil.application;
  auto& loop = hil.loop;
  io::SensorSample s{};
  int actuator_frames = 0;
  int status_frames = 0;
  int sync_frames = 0;
  can::SyncFrame last_sync{};
  can::HeartbeatFrame last_hb{};
  for (std::uint32_t tick = 1; tick <= 40; ++tick) {
    can::CanFrame f{};
    can::encode_sensor(s, static_cast<std::uint8_t>(tick), f);
    if (tick == 5) f.data[10] ^= 0x04;  // one corrupted frame on the wire
    CHECK(fx.plant->send(f) == can::PortStatus::kOk);
    loop.on_tick();
    application.service(tick * 400u, loop.state().ticks);
    while (fx.plant->receive(f, 0) == can::PortStatus::kOk) {
      if (f.id == can::message(can::MessageKind::kActuator).can_id) ++actuator_frames;
      if (f.id == can::message(can::MessageKind::kControllerStatus).can_id) ++status_frames;
      if (f.id == can::message(can::MessageKind::kHeartbeatController).can_id) can::decode_heartbeat(f, last_hb);
      if (f.id == can::message(can::MessageKind::kSync).can_id) {
        can::decode_sync(f, last_sync);
        ++sync_frames;
      }
    }
  }
  LONGS_EQUAL(39, actuator_frames);  // every tick but the corrupted one
  LONGS_EQUAL(4, status_frames);     // ticks 1, 11, 21, 31
  LONGS_EQUAL(1, last_hb.rx_rejected);
  LONGS_EQUAL(2, sync_frames);  // ticks 1 and 26
  LONGS_EQUAL(26, last_sync.tick);
  LONGS_EQUAL(26 * 400, last_sync.time_us);
  LONGS_EQUAL(0, application.stats().can_rx_frames);  // the application never stole a sensor frame
  LONGS_EQUAL(40, fx.dog.feeds);
}

namespace {
// kStep: step by `value`; kMoveTo: move to `value` (no velocity: refused by
// the kernel once it looks); any other code: the command without fields.
can::CanFrame host_command(can::HostCommandCode code, std::uint16_t seq, std::uint8_t counter, double value = 0.0) {
  const can::HostCommandFrame h = code == can::HostCommandCode::kStep ? can::make_host_command(seq, 0, can::StepArgs{value})
                                  : code == can::HostCommandCode::kMoveTo
                                      ? can::make_host_command(seq, 0, can::MoveToArgs{value, 0.0, 0.0})
                                      : can::make_host_command(code, seq, 0);
  can::CanFrame f{};
  can::encode_host_command(h, counter, f);
  return f;
}
std::vector<can::HostCommandAckFrame> drain_acks(can::CanPort& plant) {
  std::vector<can::HostCommandAckFrame> acks;
  can::CanFrame f{};
  while (plant.receive(f, 0) == can::PortStatus::kOk) {
    if (f.id != can::message(can::MessageKind::kHostCommandAck).can_id) continue;
    can::HostCommandAckFrame a{};
    can::decode_host_command_ack(f, a);
    acks.push_back(a);
  }
  return acks;
}
}  // namespace

TEST(Application, HostCommandMappingIsTheBenchOne) {
  kernel::Pose64 ref{};
  ref[maglev::kernel::Axis::kX] = 1'500'000;        // 1.5 um
  ref[maglev::kernel::Axis::kThetaZ] = -250'000; // -0.25 urad
  can::HostCommandFrame h = can::make_host_command(0, 0, can::MoveByArgs{2e-6, 1e-3, 0.5});
  kernel::MotionCommand c{};
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  CHECK(c.type == kernel::MotionType::kMoveTo);
  CHECK(c.axis == kernel::Axis::kX);
  DOUBLES_EQUAL(3.5e-6, c.target, 1e-18);
  DOUBLES_EQUAL(1e-3, c.velocity, 0.0);
  DOUBLES_EQUAL(0.5, c.acceleration, 0.0);
  h = can::make_host_command(0, 2 /* theta_z */, can::MoveJerkByArgs{1e-6, 1e-3, 0.5, 40.0});
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  CHECK(c.type == kernel::MotionType::kMoveJerkLimited);
  DOUBLES_EQUAL(0.75e-6, c.target, 1e-18);
  DOUBLES_EQUAL(40.0, c.jerk, 0.0);
  h = can::make_host_command(0, 2, can::ExciteArgs{0.1, 5.0, 2.0, 255.0});
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  CHECK(c.type == kernel::MotionType::kExcite);
  LONGS_EQUAL(255, c.harmonics);
  // Not a whole number of lines in 1..255: 0, which the kernel refuses
  // (it used to be clamped into another excitation than the one asked for).
  for (double bad : {300.0, 0.0, -7.0, 2.5}) {
    h = can::make_host_command(0, 2, can::ExciteArgs{0.1, 5.0, 2.0, bad});
    CHECK(motion_commands::to_motion_command(h, ref, &c));
    LONGS_EQUAL(0, c.harmonics);
  }
  // A sinusoid's duration becomes whole half cycles, at least as long: the
  // kernel ends a sinusoid only at rest.
  h = can::make_host_command(0, 0, can::SinusoidArgs{1e-6, 1.2, 1.0});
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  CHECK(c.type == kernel::MotionType::kSinusoid);
  DOUBLES_EQUAL(1.5, c.turns, 0.0);
  h = can::make_host_command(0, 0, can::SinusoidArgs{1e-6, 0.75, 4.0});  // paper 002's 3 cycles
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  DOUBLES_EQUAL(3.0, c.turns, 0.0);
  h = can::make_host_command(0, 0, can::SinusoidArgs{1e-6, 2.0, 1e-12});  // at least half a cycle
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  DOUBLES_EQUAL(0.5, c.turns, 0.0);
  h = can::make_host_command(0, 0, can::SinusoidArgs{1e-6, 2.0, -0.3});  // stays negative: refused by the kernel
  CHECK(motion_commands::to_motion_command(h, ref, &c));
  CHECK(c.turns < 0.0);
  h.code = can::HostCommandCode::kShutdown;
  c.target = 42.0;
  CHECK_FALSE(motion_commands::to_motion_command(h, ref, &c));
  DOUBLES_EQUAL(42.0, c.target, 0.0);  // untouched
}

TEST(Application, HilBoardExecutesHostCommandsAndAcks) {
  Fixture fx;
  HilNode hil(fx, app::ApplicationConfig{});
  const app::CanSensorSource& sensors = hil.sensors;
  App& application = hil.application;
  auto& loop = hil.loop;
  io::SensorSample s{};
  can::CanFrame f{};
  // Tick 1: sensor frame + three host commands; one more arrives corrupted.
  can::encode_sensor(s, 1, f);
  CHECK(fx.plant->send(f) == can::PortStatus::kOk);
  CHECK(fx.plant->send(host_command(can::HostCommandCode::kMoveTo, 7, 1, 1e-6)) == can::PortStatus::kOk);
  CHECK(fx.plant->send(host_command(can::HostCommandCode::kHome, 8, 2)) == can::PortStatus::kOk);
  CHECK(fx.plant->send(host_command(can::HostCommandCode::kShutdown, 9, 3)) == can::PortStatus::kOk);
  can::CanFrame bad = host_command(can::HostCommandCode::kLand, 10, 4);
  bad.data[12] ^= 0x01;
  CHECK(fx.plant->send(bad) == can::PortStatus::kOk);
  loop.on_tick();
  LONGS_EQUAL(3, sensors.stats().host_commands);
  LONGS_EQUAL(1, sensors.stats().rejected);
  LONGS_EQUAL(3, hil.sensors.host_commands().size());
  CHECK(fx.kernel.status().state == kernel::SequencerState::kIdle);  // never executed in the tick
  application.service(400u, loop.state().ticks);
  LONGS_EQUAL(0, hil.sensors.host_commands().size());
  LONGS_EQUAL(3, application.stats().host_commands);
  const auto acks = drain_acks(*fx.plant);
  LONGS_EQUAL(3, acks.size());
  LONGS_EQUAL(7, acks[0].seq);
  CHECK(acks[0].code == can::HostCommandCode::kMoveTo);
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kRefusedNotReady), acks[0].result);  // idle: not levitated
  LONGS_EQUAL(static_cast<int>(kernel::SequencerState::kIdle), acks[0].sequencer_state);
  LONGS_EQUAL(1, acks[0].tick);
  LONGS_EQUAL(8, acks[1].seq);
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted), acks[1].result);
  LONGS_EQUAL(static_cast<int>(kernel::SequencerState::kIdle), acks[1].sequencer_state);  // taken at the next step
  LONGS_EQUAL(9, acks[2].seq);
  LONGS_EQUAL(can::kHostResultNotExecuted, acks[2].result);
  // The accepted home starts on the next servo tick.
  can::encode_sensor(s, 2, f);
  CHECK(fx.plant->send(f) == can::PortStatus::kOk);
  loop.on_tick();
  CHECK(fx.kernel.status().state == kernel::SequencerState::kHoming);
  LONGS_EQUAL(0, g_critical_depth);
}

TEST(Application, ProductionRxPathExecutesHostCommands) {
  Fixture fx;
  App application(fx.kernel, &fx.store, fx.node.get(), &fx.uart, &fx.recorder, fx.gate, fx.dog,
                  app::ApplicationConfig{}, fx.hooks);
  CHECK(fx.plant->send(host_command(can::HostCommandCode::kHome, 21, 1)) == can::PortStatus::kOk);
  CHECK(fx.plant->send(host_command(can::HostCommandCode::kHome, 22, 1)) == can::PortStatus::kOk);  // repeated counter
  application.service(400u, 5);
  LONGS_EQUAL(2, application.stats().can_rx_frames);
  LONGS_EQUAL(1, application.stats().host_commands);
  const auto acks = drain_acks(*fx.plant);
  LONGS_EQUAL(1, acks.size());
  LONGS_EQUAL(21, acks[0].seq);
  LONGS_EQUAL(static_cast<int>(kernel::CommandResult::kAccepted), acks[0].result);
  LONGS_EQUAL(5, acks[0].tick);
  io::SensorSample s{};
  (void)fx.kernel.step(s, false);
  CHECK(fx.kernel.status().state == kernel::SequencerState::kHoming);
}
