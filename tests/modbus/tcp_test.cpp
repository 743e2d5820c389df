// The bench's libmodbus TCP server adapter, driven by a libmodbus TCP client
// on 127.0.0.1 (ephemeral port): same register map, same semantics.
#include <CppUTest/TestHarness.h>
#include <modbus/modbus.h>

#include <atomic>
#include <mutex>
#include <thread>

#include "maglev/modbus_tcp/tcp_server.hpp"
#include "support/protocol_device.hpp"
#include "support/protocol_suite.hpp"

using namespace maglev::modbus;
using namespace maglev::modbus::test;

TEST_GROUP(Tcp) {
  ProtocolDevice* dev = nullptr;
  RegisterServer* server = nullptr;
  maglev::modbus_tcp::TcpServer* tcp = nullptr;
  std::mutex m;
  std::atomic<bool> stop{false};
  std::thread thread;
  modbus_t* ctx = nullptr;
  void setup() override {
    dev = new ProtocolDevice();
    server = new RegisterServer(*dev, ConfigImage::defaults());
    tcp = new maglev::modbus_tcp::TcpServer(*server, "127.0.0.1", 0, 1);
    CHECK_TEXT(tcp->ok(), tcp->error().c_str());
    CHECK(tcp->port() > 0);
    thread = std::thread([this] {
      while (!stop) {
        std::lock_guard<std::mutex> lock(m);
        tcp->poll(2);
      }
    });
    ctx = modbus_new_tcp("127.0.0.1", tcp->port());
    modbus_set_slave(ctx, 1);
    LONGS_EQUAL(0, modbus_connect(ctx));
  }
  void teardown() override {
    modbus_close(ctx);
    modbus_free(ctx);
    stop = true;
    thread.join();
    delete tcp;
    delete server;
    delete dev;
  }
};

TEST(Tcp, EveryFunctionCodeAndExceptionThroughLibmodbus) { run_protocol_suite(ctx, m, *server, *dev); }

TEST(Tcp, TwoClientsShareOneMap) {
  modbus_t* other = modbus_new_tcp("127.0.0.1", tcp->port());
  modbus_set_slave(other, 1);
  LONGS_EQUAL(0, modbus_connect(other));
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::cmd_axis), 4));
  std::uint16_t v = 0;
  LONGS_EQUAL(1, modbus_read_registers(other, addr(RegId::cmd_axis), 1, &v));
  LONGS_EQUAL(4, v);
  modbus_close(other);
  modbus_free(other);
  // The server survives a client going away and keeps serving.
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::cmd_axis), 1, &v));
}
