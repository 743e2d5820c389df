// Hostile Modbus TCP clients against the bench's server (issue 17): partial
// MBAP headers, a frame that announces 100 bytes and sends 3, an unframed
// function code with trailing bytes, a client sending one byte a second,
// garbage, 100 concurrent connections, idle connections. Each used to freeze
// the real-time thread for as long as the client held its socket. Now:
//   * no poll() call waits on a client (wall time < 50 ms) and each does
//     bounded work: its system calls are counted and stay within the bound
//     the limits imply (a count, because CPU time on a shared virtual
//     machine includes the hypervisor's steal: CI saw 3 ms "CPU" polls),
//     and at most 1 % of polls take more than 2 ms of thread CPU time,
//   * a well-behaved client is answered within 50 ms throughout,
//   * the configuration is unchanged, the hostile connections are closed by
//     the documented rules, and a write to unit 0 gets its reply.
// Everything on 127.0.0.1, bounded loops, stops by itself.
#include <arpa/inet.h>
#include <cerrno>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "maglev/modbus_tcp/tcp_server.hpp"
#include "support/protocol_device.hpp"

// CppUTest last: its new/delete macros must not meet the STL headers.
#include <CppUTest/TestHarness.h>
#include <CppUTest/MemoryLeakWarningPlugin.h>

using namespace maglev::modbus;
using Clock = std::chrono::steady_clock;
namespace { std::uint16_t addr(RegId id) { return def(id).address; } }

namespace {

// nonblocking: a flood does not wait for the server's backlog.
int connect_raw(int port, bool nonblocking = false) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | (nonblocking ? SOCK_NONBLOCK : 0), 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  ::inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 && !(nonblocking && errno == EINPROGRESS)) {
    ::close(fd);
    return -1;
  }
  return fd;
}
void send_bytes(int fd, std::vector<std::uint8_t> b) { (void)::send(fd, b.data(), b.size(), MSG_NOSIGNAL); }
// true when the peer closed the connection (recv 0) within wait_ms.
bool closed_by_server(int fd, int wait_ms) {
  timeval tv{wait_ms / 1000, (wait_ms % 1000) * 1000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::uint8_t b[300];
  for (;;) {
    const ssize_t r = ::recv(fd, b, sizeof b, 0);
    if (r == 0) return true;
    if (r < 0) return errno == ECONNRESET;
  }
}

}  // namespace

TEST_GROUP(HostileTcp) {
  test::ProtocolDevice* dev = nullptr;
  RegisterServer* server = nullptr;
  maglev::modbus_tcp::TcpServer* tcp = nullptr;
  std::mutex m;
  std::atomic<bool> stop{false};
  std::atomic<long long> max_poll_us{0};      // wall time of one poll(): a blocking read shows here
  std::atomic<long long> max_poll_cpu_us{0};  // its CPU time: the work it did (preemption excluded, steal not)
  std::atomic<long long> polls{0};
  std::atomic<long long> polls_over_2ms_cpu{0};
  std::thread thread;
  modbus_t* contexts[8] = {};  // freed in teardown, even when a check fails
  int context_count = 0;
  modbus_t* client(int unit, int timeout_us) {
    modbus_t* c = modbus_new_tcp("127.0.0.1", tcp->port());
    contexts[context_count++] = c;
    modbus_set_slave(c, unit);
    modbus_set_response_timeout(c, 0, static_cast<std::uint32_t>(timeout_us));
    LONGS_EQUAL(0, modbus_connect(c));
    return c;
  }
  void setup() override {
    MemoryLeakWarningPlugin::saveAndDisableNewDeleteOverloads();
    dev = new test::ProtocolDevice();
    server = new RegisterServer(*dev, ConfigImage::defaults());
    maglev::modbus_tcp::TcpServerLimits lim;
    lim.max_clients = 8;
    lim.frame_timeout = std::chrono::milliseconds(300);
    lim.idle_timeout = std::chrono::milliseconds(2000);
    lim.evict_after = std::chrono::milliseconds(200);
    tcp = new maglev::modbus_tcp::TcpServer(*server, "127.0.0.1", 0, 1, lim);
    CHECK_TEXT(tcp->ok(), tcp->error().c_str());
    // The "servo thread": a poll(0) every 400 us, timed.
    thread = std::thread([this] {
      while (!stop) {
        timespec c0{}, c1{};
        std::unique_lock<std::mutex> lock(m);
        const auto t0 = Clock::now();
        ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
        tcp->poll(0);
        ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
        const long long us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - t0).count();
        const long long cpu = (c1.tv_sec - c0.tv_sec) * 1000000LL + (c1.tv_nsec - c0.tv_nsec) / 1000;
        max_poll_us = std::max(max_poll_us.load(), us);
        max_poll_cpu_us = std::max(max_poll_cpu_us.load(), cpu);
        ++polls;
        if (cpu > 2000) ++polls_over_2ms_cpu;
        lock.unlock();
        std::this_thread::sleep_for(std::chrono::microseconds(400));
      }
    });
  }
  void teardown() override {
    for (int i = 0; i < context_count; ++i) {
      modbus_close(contexts[i]);
      modbus_free(contexts[i]);
    }
    stop = true;
    thread.join();
    delete tcp;
    delete server;
    delete dev;
    MemoryLeakWarningPlugin::restoreNewDeleteOverloads();
  }
  // Bounded work per poll(): counted system calls within the limits' bound,
  // and CPU time above 2 ms in at most 1 % of the calls.
  void check_bounded_work() {
    std::lock_guard<std::mutex> lock(m);
    std::printf("[measured] %lld polls, %lld over 2 ms CPU, most system calls in one poll %llu (bound %llu)\n",
                polls.load(), polls_over_2ms_cpu.load(),
                static_cast<unsigned long long>(tcp->stats().max_poll_syscalls),
                static_cast<unsigned long long>(tcp->max_syscalls_per_poll()));
    CHECK_TRUE(tcp->stats().max_poll_syscalls >= 2);  // it did serve: poll + a recv at least
    CHECK_TRUE(tcp->stats().max_poll_syscalls <= tcp->max_syscalls_per_poll());
    CHECK_TRUE(polls.load() > 100);
    CHECK_TRUE(polls_over_2ms_cpu.load() * 100 <= polls.load());
  }
  // The well-behaved client: worst latency of `n` reads, in ms.
  double good_client_worst_ms(modbus_t* ctx, int n) {
    double worst = 0.0;
    for (int i = 0; i < n; ++i) {
      std::uint16_t v = 0;
      const auto t0 = Clock::now();
      LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::cmd_axis), 1, &v));
      worst = std::max(worst, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return worst;
  }
};

TEST(HostileTcp, NoClientStallsTheLoopOrAGoodClient) {
  modbus_t* good = client(1, 50000);  // 50 ms: a slower answer fails the read
  std::uint16_t axis = 0;
  LONGS_EQUAL(1, modbus_read_registers(good, addr(RegId::cmd_axis), 1, &axis));
  ConfigImage before{};
  {
    std::lock_guard<std::mutex> lock(m);
    before = server->config();
  }

  // 1. A 3-byte partial MBAP header, held open.
  const int partial = connect_raw(tcp->port());
  send_bytes(partial, {0x00, 0x01, 0x00});
  // 2. A request that announces 100 bytes and sends 3.
  const int short_body = connect_raw(tcp->port());
  send_bytes(short_body, {0x00, 0x02, 0x00, 0x00, 0x00, 0x64, 0x01, 0x03, 0x00});
  // 3. Function 0x11 with 4 extra bytes, unframed (MBAP length says 2).
  const int extra = connect_raw(tcp->port());
  send_bytes(extra, {0x00, 0x03, 0x00, 0x00, 0x00, 0x02, 0x01, 0x11, 0xDE, 0xAD, 0xBE, 0xEF});
  // 4. Garbage: a protocol id that is not Modbus.
  const int garbage = connect_raw(tcp->port());
  send_bytes(garbage, {0x47, 0x45, 0x54, 0x20, 0x2F, 0x20, 0x48, 0x54, 0x54, 0x50});
  // 5. One byte every 100 ms (slower than the frame timeout allows).
  const int slow = connect_raw(tcp->port());
  std::thread slow_sender([&] {
    const std::uint8_t req[12] = {0x00, 0x05, 0x00, 0x00, 0x00, 0x06, 0x01, 0x03, 0x00, 0xC8, 0x00, 0x01};
    for (std::uint8_t b : req) {
      if (::send(slow, &b, 1, MSG_NOSIGNAL) != 1) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  const double worst_ms = good_client_worst_ms(good, 60);
  slow_sender.join();

  std::printf("\n[measured] good client worst latency %.2f ms, worst poll() %lld us wall / %lld us CPU under 5 hostile"
              " clients\n", worst_ms, max_poll_us.load(), max_poll_cpu_us.load());
  CHECK_TRUE(worst_ms < 50.0);
  // Never waits on a client (the old server blocked for as long as the
  // client held its socket: seconds) and does bounded work.
  CHECK_TRUE(max_poll_us.load() < 50000);
  check_bounded_work();
  // The rules closed each of them: bad MBAP at once, partial frames after the frame timeout.
  CHECK_TRUE(closed_by_server(garbage, 1000));
  CHECK_TRUE(closed_by_server(partial, 1000));
  CHECK_TRUE(closed_by_server(short_body, 1000));
  CHECK_TRUE(closed_by_server(slow, 1000));
  // 0x11 with a 2-byte MBAP length is a whole frame (answered); its 4 extra
  // bytes then break the next frame's MBAP rules: closed.
  CHECK_TRUE(closed_by_server(extra, 1000));
  {
    std::lock_guard<std::mutex> lock(m);
    CHECK_TRUE(server->config() == before);
    CHECK_TRUE(tcp->stats().bad_frames >= 1);   // the garbage
    CHECK_TRUE(tcp->stats().slow_closed >= 4);  // partial, short body, one byte at a time, 0x11's extra bytes
  }
  for (int fd : {partial, short_body, extra, garbage, slow}) ::close(fd);
}

TEST(HostileTcp, AHundredConnectionsNeitherLockOutNorStall) {
  modbus_t* good = client(1, 50000);
  std::uint16_t first = 0;  // an operator at work: one request answered
  LONGS_EQUAL(1, modbus_read_registers(good, addr(RegId::cmd_axis), 1, &first));
  std::vector<int> flood;
  for (int i = 0; i < 100; ++i) flood.push_back(connect_raw(tcp->port(), true));
  const double worst_ms = good_client_worst_ms(good, 40);
  // A new operator gets in once the silent connections are past evict_after.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  modbus_t* late = client(1, 50000);
  std::uint16_t v = 0;
  LONGS_EQUAL(1, modbus_read_registers(late, addr(RegId::cmd_axis), 1, &v));
  std::printf("\n[measured] 100 connections: good client worst %.2f ms, worst poll() %lld us wall / %lld us CPU,"
              " clients %zu\n", worst_ms, max_poll_us.load(), max_poll_cpu_us.load(), tcp->clients());
  CHECK_TRUE(worst_ms < 50.0);
  CHECK_TRUE(max_poll_us.load() < 50000);
  check_bounded_work();
  CHECK_TRUE(tcp->clients() <= 8);
  for (int fd : flood) ::close(fd);
}

TEST(HostileTcp, AWriteToUnitZeroIsAnsweredAndIdleClientsAreClosed) {
  modbus_t* c = client(0, 200000);
  // Modbus/TCP has no broadcast: unit 0 gets its reply like unit 1.
  LONGS_EQUAL(1, modbus_write_register(c, addr(RegId::cmd_axis), 3));
  std::uint16_t v = 0;
  LONGS_EQUAL(1, modbus_read_registers(c, addr(RegId::cmd_axis), 1, &v));
  LONGS_EQUAL(3, v);
  // An idle connection is closed after idle_timeout (2 s here).
  const int idle = connect_raw(tcp->port());
  CHECK_TRUE(closed_by_server(idle, 4000));
  ::close(idle);
  std::lock_guard<std::mutex> lock(m);
  CHECK_TRUE(tcp->stats().idle_closed >= 1);
}
