// Runs INSIDE the test VM (vcan0 up, MTU 72). SocketCAN transport with our
// codec: lockstep sensor/actuator exchange between two sockets in two
// threads and between two processes, ID filters, receive timeouts,
// error-frame counting, the FD flag the kernel sets on received frames.
#include <linux/can.h>
#include <linux/can/error.h>
#include <net/if.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "maglev/can_link/codec.hpp"
#include "maglev/controller_node/controller_node.hpp"
#include "maglev/lockstep/plant_endpoint.hpp"
#include "maglev/can_port/open_can_port.hpp"
#include "maglev/socketcan/socketcan_port.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>
#include <CppUTest/MemoryLeakWarningPlugin.h>

using namespace maglev;
using namespace maglev::can;

namespace {
const char* kIf = "vcan0";

io::SensorSample sample_for(std::uint32_t tick) {
  io::SensorSample s{};
  for (int i = 0; i < 3; ++i) s.interferometer_counts[i] = tick * 3u + static_cast<std::uint32_t>(i);
  for (int i = 0; i < 3; ++i) s.displacement_adc[i] = static_cast<std::int16_t>(-static_cast<int>(tick % 1000));
  for (int i = 0; i < 4; ++i) s.hall_adc[i] = static_cast<std::int16_t>(i * 100);
  for (int i = 0; i < 8; ++i) s.coil_current_adc[i] = static_cast<std::int16_t>(i - 4);
  s.status_flags = static_cast<std::uint16_t>(tick & 0x7);
  return s;
}
io::ActuatorCommand answer(const io::SensorSample& s) {
  io::ActuatorCommand a{};
  for (int j = 0; j < 8; ++j) a.dac_code[j] = static_cast<std::int16_t>((s.interferometer_counts[j % 3] & 0x7FF) - 1000);
  a.amplifier_enable = true;
  return a;
}
constexpr std::uint32_t kTicks = 500;

// The controller endpoint: the controller node's CanServoIo (the firmware
// application's CanSensorSource / CanActuatorSink).
int run_controller(CanPort& port) {
  hil::CanServoIo cio(port);
  io::SensorSample s{};
  for (std::uint32_t i = 0; i < kTicks; ++i) {
    if (!cio.port().wait(5'000'000) || !cio.sensors().read(s)) return 1;
    cio.actuators().write(answer(s));
    if (cio.actuators().stats().send_errors != 0) return 2;
  }
  return cio.rx_stats().rejected_total() == 0 ? 0 : 3;
}
// tick t through the plant endpoint; false: no answer within 5 s.
bool exchange(lockstep::PlantEndpoint& plant, std::uint32_t t, io::ActuatorCommand* cmd) {
  const std::uint8_t counter = plant.send_tick(t, t * 400e-6, sample_for(t));
  return plant.await_actuator(counter, 5'000'000, cmd);
}
}  // namespace

TEST_GROUP(SocketCan) {
  void setup() override { MemoryLeakWarningPlugin::saveAndDisableNewDeleteOverloads(); }
  void teardown() override { MemoryLeakWarningPlugin::restoreNewDeleteOverloads(); }
};

TEST(SocketCan, OpenByNameAndFdFlagOnReceive) {
  std::string err;
  auto a = open_can_port(kIf, &err);
  auto b = open_can_port(kIf, &err);
  CHECK_TEXT(a != nullptr, err.c_str());
  CHECK_TEXT(b != nullptr, err.c_str());
  STRCMP_EQUAL("socketcan:vcan0", a->name());
  CanFrame f{};
  encode_sensor(sample_for(7), 7, f);
  CHECK(PortStatus::kOk == a->send(f));
  CanFrame in{};
  CHECK(PortStatus::kOk == b->receive(in, 1'000'000));
  LONGS_EQUAL(0x030, in.id);
  LONGS_EQUAL(32, in.len);
  CHECK_TRUE((in.flags & 0x04) != 0);  // CANFD_FDF set by the kernel
  CHECK_TRUE((in.flags & kFlagBrs) != 0);
  MEMCMP_EQUAL(f.data, in.data, 32);
  LinkReceiver rx;
  CHECK(RxStatus::kOk == rx.accept(in));
  // The sender does not see its own frame (CAN_RAW_RECV_OWN_MSGS off).
  CHECK(PortStatus::kTimeout == a->receive(in, 20'000));
  std::printf("\n[vm] received FD frame flags 0x%02x\n", in.flags);
}

TEST(SocketCan, ReceiveTimeoutIsHonoured) {
  auto a = SocketCanPort::open(kIf);
  CHECK_TRUE(a != nullptr);
  CanFrame in{};
  const auto t0 = std::chrono::steady_clock::now();
  CHECK(PortStatus::kTimeout == a->receive(in, 50'000));
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  CHECK_TRUE(ms >= 49.0);
  CHECK_TRUE(ms < 1000.0);
  LONGS_EQUAL(1, a->counters().rx_timeouts);
}

TEST(SocketCan, IdFilterPassesOnlyTheActuatorFrame) {
  SocketCanOptions opt;
  opt.filters.push_back({message(MessageKind::kActuator).can_id, 0x7FF});
  auto filtered = SocketCanPort::open(kIf, opt);
  auto tx = SocketCanPort::open(kIf);
  CHECK_TRUE(filtered != nullptr);
  CHECK_TRUE(tx != nullptr);
  CanFrame f{};
  encode_sensor(sample_for(1), 1, f);
  tx->send(f);
  encode_sync(SyncFrame{1, 2}, 1, f);
  tx->send(f);
  encode_actuator(answer(sample_for(1)), 1, f);
  tx->send(f);
  CanFrame in{};
  CHECK(PortStatus::kOk == filtered->receive(in, 1'000'000));
  LONGS_EQUAL(0x020, in.id);
  CHECK(PortStatus::kTimeout == filtered->receive(in, 50'000));
  LONGS_EQUAL(1, filtered->counters().rx_frames);
}

TEST(SocketCan, ErrorFramesAreCountedNotReturned) {
  auto rx = SocketCanPort::open(kIf);
  CHECK_TRUE(rx != nullptr);
  // Inject an error frame the way a CAN controller driver reports one:
  // a frame with CAN_ERR_FLAG (vcan loops it back to error-filter sockets).
  const int s = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  CHECK_TRUE(s >= 0);
  auto tx = SocketCanPort::open(kIf);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(if_nametoindex(kIf));
  CHECK_EQUAL(0, ::bind(s, reinterpret_cast<sockaddr*>(&addr), sizeof addr));
  can_frame err{};
  err.can_id = CAN_ERR_FLAG | CAN_ERR_PROT;
  err.len = CAN_ERR_DLC;
  err.data[2] = CAN_ERR_PROT_BIT;
  const ssize_t n = ::write(s, &err, sizeof err);
  ::close(s);
  CHECK_EQUAL(static_cast<ssize_t>(sizeof err), n);
  // Then a real data frame: receive() must skip the error frame and count it.
  CanFrame f{};
  encode_sync(SyncFrame{5, 6}, 0, f);
  tx->send(f);
  CanFrame in{};
  CHECK(PortStatus::kOk == rx->receive(in, 1'000'000));
  LONGS_EQUAL(0x010, in.id);
  LONGS_EQUAL(1, rx->counters().error_frames);
  LONGS_EQUAL(CAN_ERR_PROT, rx->last_error_class());
}

TEST(SocketCan, LockstepTwoThreadsTwoSockets) {
  auto plant_port = SocketCanPort::open(kIf);
  auto ctrl_port = SocketCanPort::open(kIf);
  int ctrl_rc = -1;
  std::thread ctrl([&] { ctrl_rc = run_controller(*ctrl_port); });
  lockstep::PlantEndpoint plant(*plant_port, nullptr, lockstep::PlantEndpoint::Config{false, false});
  io::ActuatorCommand cmd = io::kSafeActuatorCommand;
  const auto t0 = std::chrono::steady_clock::now();
  std::uint32_t ok = 0;
  for (std::uint32_t t = 0; t < kTicks; ++t) {
    if (!exchange(plant, t, &cmd)) break;
    const auto want = answer(sample_for(t));
    MEMCMP_EQUAL(want.dac_code, cmd.dac_code, sizeof cmd.dac_code);
    ++ok;
  }
  ctrl.join();
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  LONGS_EQUAL(kTicks, ok);
  LONGS_EQUAL(0, ctrl_rc);
  LONGS_EQUAL(0, plant.receiver().stats().rejected_total());
  std::printf("\n[vm] SocketCAN lockstep, 2 threads: %.0f ticks/s (TCG-emulated guest)\n", kTicks / s);
}

TEST(SocketCan, LockstepTwoProcesses) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    auto port = SocketCanPort::open(kIf);
    _exit(port ? run_controller(*port) : 9);
  }
  auto plant_port = SocketCanPort::open(kIf);
  lockstep::PlantEndpoint plant(*plant_port, nullptr, lockstep::PlantEndpoint::Config{false, false});
  io::ActuatorCommand cmd = io::kSafeActuatorCommand;
  std::uint32_t ok = 0;
  // The child needs a moment to bind; the first sensor frames would be lost.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  for (std::uint32_t t = 0; t < kTicks; ++t) {
    if (!exchange(plant, t, &cmd)) break;
    ++ok;
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  LONGS_EQUAL(kTicks, ok);
  CHECK_TRUE(WIFEXITED(status));
  LONGS_EQUAL(0, WEXITSTATUS(status));
}
