// The firmware RTU server driven by a real libmodbus RTU client over a
// pseudo-terminal pair. The server side reads the pty master in a thread and
// stamps every byte with a monotonic microsecond clock, as the UART driver does.
#include <CppUTest/TestHarness.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <string>
#include <thread>

#include "maglev/modbus/crc16.hpp"
#include "maglev/modbus/rtu_server.hpp"
#include "support/protocol_device.hpp"
#include "support/protocol_suite.hpp"

using namespace maglev::modbus;
using namespace maglev::modbus::test;

namespace {

std::uint32_t now_us() {
  return static_cast<std::uint32_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

constexpr int kBaud = 115200;
constexpr int kUnit = 17;

struct PtyServer {
  ProtocolDevice dev;
  RegisterServer server{dev, ConfigImage::defaults()};
  RtuServer rtu{server, kUnit, kBaud};
  std::mutex m;
  int master = -1;
  std::string slave_name;
  std::atomic<bool> stop{false};
  std::thread thread;
  int replies = 0;

  PtyServer() {
    master = posix_openpt(O_RDWR | O_NOCTTY);
    grantpt(master);
    unlockpt(master);
    slave_name = ptsname(master);
    // Raw mode on the slave before any client opens it (no echo, no CR/LF games).
    const int s = open(slave_name.c_str(), O_RDWR | O_NOCTTY);
    termios t{};
    tcgetattr(s, &t);
    cfmakeraw(&t);
    tcsetattr(s, TCSANOW, &t);
    close(s);
    thread = std::thread([this] { loop(); });
  }
  ~PtyServer() {
    stop = true;
    thread.join();
    close(master);
  }
  void loop() {
    std::uint8_t buf[512];
    std::uint8_t tx[kMaxRtuFrame];
    while (!stop) {
      pollfd p{master, POLLIN, 0};
      const int pr = ::poll(&p, 1, 1);
      std::lock_guard<std::mutex> lock(m);
      if (pr > 0 && (p.revents & POLLIN) != 0) {
        const ssize_t n = read(master, buf, sizeof buf);
        const std::uint32_t t = now_us();
        for (ssize_t i = 0; i < n; ++i) rtu.receive(buf[i], t);
      }
      const std::size_t len = rtu.poll(now_us(), tx);
      if (len > 0) {
        ++replies;
        CHECK(write(master, tx, len) == static_cast<ssize_t>(len));
      }
    }
  }
  RtuStats stats() {
    std::lock_guard<std::mutex> lock(m);
    return rtu.stats();
  }
};

void wait_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

}  // namespace

TEST_GROUP(RtuPty) {
  PtyServer* pty = nullptr;
  modbus_t* ctx = nullptr;
  void setup() override {
    pty = new PtyServer();
    ctx = modbus_new_rtu(pty->slave_name.c_str(), kBaud, 'N', 8, 1);
    CHECK(ctx != nullptr);
    modbus_set_slave(ctx, kUnit);
    modbus_set_response_timeout(ctx, 0, 500000);
    LONGS_EQUAL(0, modbus_connect(ctx));
  }
  void teardown() override {
    modbus_close(ctx);
    modbus_free(ctx);
    delete pty;
  }
  // Writes raw bytes straight into the line (bypassing libmodbus' framing).
  void inject(const std::uint8_t* bytes, std::size_t n) {
    const int s = open(pty->slave_name.c_str(), O_RDWR | O_NOCTTY);
    CHECK(s >= 0);
    CHECK(write(s, bytes, n) == static_cast<ssize_t>(n));
    close(s);
    wait_ms(20);  // > t3.5: the server closes the frame
  }
};

TEST(RtuPty, SilenceIsComputedFromBaud) {
  LONGS_EQUAL(1750, rtu_silence_us(115200));
  LONGS_EQUAL(1750, rtu_silence_us(38400));
  LONGS_EQUAL(2006, rtu_silence_us(19200));   // 3.5 * 11 / 19200 = 2.005 ms, rounded up
  LONGS_EQUAL(4011, rtu_silence_us(9600));
}

TEST(RtuPty, EveryFunctionCodeAndExceptionThroughLibmodbus) {
  run_protocol_suite(ctx, pty->m, pty->server, pty->dev);
  CHECK(pty->stats().frames > 20);
  LONGS_EQUAL(0, pty->stats().crc_errors);
}

TEST(RtuPty, BadCrcAndTruncatedFramesAreDroppedWithoutReply) {
  const Snapshot before = snap(pty->m, pty->server, pty->dev);
  // A valid "write peak current = 2.0 A" frame... (engineer key needed, so
  // unlock first through the client).
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), kEngineerKey));
  const std::uint16_t pc = addr(RegId::limit_peak_current);
  const auto hi = static_cast<std::uint8_t>(pc >> 8);
  const auto lo = static_cast<std::uint8_t>(pc & 0xFF);
  std::uint8_t f[13] = {kUnit, 0x10, hi, lo, 0x00, 0x02, 0x04, 0x40, 0x00, 0x00, 0x00, 0, 0};
  const std::uint16_t crc = crc16(f, 11);
  f[11] = static_cast<std::uint8_t>(crc & 0xFF);
  f[12] = static_cast<std::uint8_t>(crc >> 8);
  const int replies_before = pty->replies;
  std::uint8_t bad[13];
  std::memcpy(bad, f, sizeof f);
  bad[12] ^= 0x40;  // bad CRC
  inject(bad, sizeof bad);
  LONGS_EQUAL(1, static_cast<long>(pty->stats().crc_errors));
  inject(f, 7);  // truncated: header only
  LONGS_EQUAL(2, static_cast<long>(pty->stats().crc_errors));
  inject(f, 3);  // too short to be a frame
  LONGS_EQUAL(1, static_cast<long>(pty->stats().short_frames));
  // Truncated PDU with a correct CRC: byte count says 4, only 2 data bytes.
  std::uint8_t t[11] = {kUnit, 0x10, hi, lo, 0x00, 0x02, 0x04, 0x40, 0x00, 0, 0};
  const std::uint16_t tc = crc16(t, 9);
  t[9] = static_cast<std::uint8_t>(tc & 0xFF);
  t[10] = static_cast<std::uint8_t>(tc >> 8);
  inject(t, sizeof t);
  LONGS_EQUAL(replies_before + 1, pty->replies);  // only the truncated-PDU frame was answered (03)
  {
    std::uint8_t rsp[MODBUS_MAX_ADU_LENGTH];
    modbus_set_response_timeout(ctx, 0, 200000);
    // Its exception reply sits in the line: read it raw through libmodbus.
    const int n = modbus_receive_confirmation(ctx, rsp);
    LONGS_EQUAL(5, n);
    LONGS_EQUAL(0x90, rsp[1]);
    LONGS_EQUAL(0x03, rsp[2]);
  }
  check_unchanged(pty->m, pty->server, pty->dev, before);
  // A frame for another unit is ignored.
  std::uint8_t other[13];
  std::memcpy(other, f, sizeof f);
  other[0] = kUnit + 1;
  const std::uint16_t oc = crc16(other, 11);
  other[11] = static_cast<std::uint8_t>(oc & 0xFF);
  other[12] = static_cast<std::uint8_t>(oc >> 8);
  inject(other, sizeof other);
  LONGS_EQUAL(1, static_cast<long>(pty->stats().other_unit));
  check_unchanged(pty->m, pty->server, pty->dev, before);
  // The intact frame is applied: 2.0 A.
  inject(f, sizeof f);
  std::uint8_t rsp[MODBUS_MAX_ADU_LENGTH];
  LONGS_EQUAL(8, modbus_receive_confirmation(ctx, rsp));
  std::lock_guard<std::mutex> lock(pty->m);
  DOUBLES_EQUAL(2.0, pty->server.config().get(RegId::limit_peak_current), 0.0);
}

TEST(RtuPty, BroadcastWriteAppliesWithoutReply) {
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), kEngineerKey));
  const int replies_before = pty->replies;
  modbus_set_slave(ctx, MODBUS_BROADCAST_ADDRESS);
  modbus_set_response_timeout(ctx, 0, 100000);
  std::uint16_t w[2];
  set_f32(1.5f, w);
  // libmodbus waits for a reply that never comes: the timeout proves silence.
  LONGS_EQUAL(-1, modbus_write_registers(ctx, addr(RegId::limit_rms_current), 2, w));
  LONGS_EQUAL(ETIMEDOUT, errno);
  LONGS_EQUAL(replies_before, pty->replies);
  modbus_set_slave(ctx, kUnit);
  modbus_set_response_timeout(ctx, 0, 500000);
  std::uint16_t r[2];
  LONGS_EQUAL(2, modbus_read_registers(ctx, addr(RegId::limit_rms_current), 2, r));
  DOUBLES_EQUAL(1.5, get_f32(r), 0.0);
}

TEST(RtuPty, SaveToFlashThroughTheMap) {
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), kEngineerKey));
  std::uint16_t w[2];
  set_f32(3.25f, w);
  LONGS_EQUAL(2, modbus_write_registers(ctx, addr(RegId::limit_peak_current), 2, w));
  std::uint16_t flags = 0;
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::persist_flags), 1, &flags));
  CHECK(flags & kUnsaved);
  CHECK(flags & kLoadedDefaults);
  {
    std::lock_guard<std::mutex> lock(pty->m);
    pty->dev.fail_save = true;
  }
  LONGS_EQUAL(-1, modbus_write_register(ctx, addr(RegId::config_save), 1));
  LONGS_EQUAL(EMBXSFAIL, errno);  // 04 server device failure
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::persist_flags), 1, &flags));
  CHECK(flags & kUnsaved);
  {
    std::lock_guard<std::mutex> lock(pty->m);
    pty->dev.fail_save = false;
  }
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::config_save), 1));
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::persist_flags), 1, &flags));
  LONGS_EQUAL(kLoadedBankA, flags);
  std::uint16_t seq[2];
  LONGS_EQUAL(2, modbus_read_registers(ctx, addr(RegId::persist_sequence), 2, seq));
  LONGS_EQUAL(1, seq[1]);
  std::lock_guard<std::mutex> lock(pty->m);
  const auto reloaded = pty->dev.store().load();
  DOUBLES_EQUAL(3.25, reloaded.config.get(RegId::limit_peak_current), 0.0);
}
