// The protocol checks both transports run through a REAL libmodbus client:
// every function code (0x03, 0x04, 0x06, 0x10, 0x17), every exception (01,
// 02, 03, 06) and that a refused write leaves the configuration unchanged.
#pragma once

#include <CppUTest/TestHarness.h>
#include <modbus/modbus.h>

#include <cerrno>
#include <cstdint>
#include <mutex>

#include "maglev/can_link/host_commands.hpp"
#include "maglev/modbus/register_server.hpp"
#include "protocol_device.hpp"

namespace maglev::modbus::test {

inline std::uint16_t addr(RegId id) { return def(id).address; }
inline void set_f32(float v, std::uint16_t* w) { split_words(encode(RegType::kF32, static_cast<double>(v)), w); }
inline double get_f32(const std::uint16_t* w) { return decode(RegType::kF32, join_words(w)); }

struct Snapshot {
  ConfigImage config;
  int apply_calls;
  std::size_t commands;
};

inline Snapshot snap(std::mutex& m, const RegisterServer& s, const ProtocolDevice& d) {
  std::lock_guard<std::mutex> lock(m);
  return {s.config(), d.apply_calls, d.commands.size()};
}

inline void check_unchanged(std::mutex& m, const RegisterServer& s, const ProtocolDevice& d, const Snapshot& before) {
  const Snapshot after = snap(m, s, d);
  CHECK(after.config == before.config);
  LONGS_EQUAL(before.apply_calls, after.apply_calls);
  LONGS_EQUAL(static_cast<long>(before.commands), static_cast<long>(after.commands));
}

// Expect the call `rc` to have failed with Modbus exception `code` (a macro
// so a failure names the line of the call).
#define expect_exception(rc, code)                  \
  do {                                              \
    const int rc_ = (rc);                           \
    const int errno_ = errno;                       \
    LONGS_EQUAL(-1, rc_);                           \
    LONGS_EQUAL(MODBUS_ENOBASE + (code), errno_);   \
  } while (0)

inline void run_protocol_suite(modbus_t* ctx, std::mutex& m, RegisterServer& server, ProtocolDevice& dev) {
  std::uint16_t r[8] = {};
  // --- 0x03 / 0x04 reads: identity, status f32 in ABCD order ---------------
  LONGS_EQUAL(6, modbus_read_registers(ctx, 0, 6, r));
  LONGS_EQUAL(0x4D4C, r[0]);
  LONGS_EQUAL(kSchemaHash, (static_cast<std::uint32_t>(r[4]) << 16) | r[5]);
  LONGS_EQUAL(2, modbus_read_input_registers(ctx, addr(RegId::status_x), 2, r));
  DOUBLES_EQUAL(1.25e-3, get_f32(r), 1e-9);
  LONGS_EQUAL(2, modbus_read_registers(ctx, addr(RegId::status_theta_z), 2, r));
  DOUBLES_EQUAL(-2.5e-6, get_f32(r), 1e-12);

  // --- 0x06: unlock engineer level, read it back ---------------------------
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), kEngineerKey));
  LONGS_EQUAL(1, modbus_read_registers(ctx, addr(RegId::access_level), 1, r));
  LONGS_EQUAL(2, r[0]);

  // --- 0x10: a whole axis' gains in one write, applied once ----------------
  const int calls = snap(m, server, dev).apply_calls;
  std::uint16_t gains[12];
  const float values[6] = {25000.0f, 3.0e5f, 120.0f, 400.0f, 0.8f, 0.1f};
  for (int i = 0; i < 6; ++i) set_f32(values[i], gains + 2 * i);
  const int wr = modbus_write_registers(ctx, addr(RegId::gain_y_kp), 12, gains);
  if (wr < 0) FAIL(modbus_strerror(errno));
  LONGS_EQUAL(12, wr);
  {
    std::lock_guard<std::mutex> lock(m);
    LONGS_EQUAL(calls + 1, dev.apply_calls);
    DOUBLES_EQUAL(25000.0, dev.applied.get(RegId::gain_y_kp), 0.0);
    DOUBLES_EQUAL(0.1, dev.applied.get(RegId::gain_y_setpoint_weight_d), 1e-7);
  }

  // --- 0x17: write cmd arguments + code, read back the result --------------
  std::uint16_t cmd[4];
  cmd[0] = 0;  // axis x
  set_f32(1.0e-3f, cmd + 1);
  cmd[3] = static_cast<std::uint16_t>(maglev::can::HostCommandCode::kMoveTo);
  std::uint16_t rb[5] = {};
  LONGS_EQUAL(5, modbus_write_and_read_registers(ctx, addr(RegId::cmd_axis), 4, cmd, addr(RegId::cmd_axis), 5, rb));
  DOUBLES_EQUAL(1.0e-3, get_f32(rb + 1), 1e-9);
  LONGS_EQUAL(0, rb[4]);  // cmd.result: accepted
  {
    std::lock_guard<std::mutex> lock(m);
    CHECK(!dev.commands.empty());
    LONGS_EQUAL(static_cast<int>(maglev::can::HostCommandCode::kMoveTo), static_cast<int>(dev.commands.back().code));
    DOUBLES_EQUAL(1.0e-3, static_cast<double>(dev.commands.back().value), 1e-9);
  }

  // --- exceptions; each leaves the configuration unchanged -----------------
  Snapshot before = snap(m, server, dev);
  // 01 illegal function: 0x08 diagnostics is not served.
  {
    const std::uint8_t raw[] = {static_cast<std::uint8_t>(modbus_get_slave(ctx)), 0x08, 0x00, 0x00, 0x12, 0x34};
    CHECK(modbus_send_raw_request(ctx, raw, sizeof raw) > 0);
    std::uint8_t rsp[MODBUS_MAX_ADU_LENGTH];
    const int n = modbus_receive_confirmation(ctx, rsp);
    const int h = modbus_get_header_length(ctx);
    CHECK(n >= h + 2);
    LONGS_EQUAL(0x88, rsp[h]);
    LONGS_EQUAL(0x01, rsp[h + 1]);
  }
  // 02: unknown address (gap), read-only register, half of a float.
  expect_exception(modbus_read_registers(ctx, 50, 1, r), 2);
  expect_exception(modbus_read_registers(ctx, addr(RegId::persist_flags), 7, r), 2);  // 120..126: 126 is a gap
  expect_exception(modbus_write_register(ctx, 50, 1), 2);
  expect_exception(modbus_write_register(ctx, addr(RegId::status_state), 1), 2);
  expect_exception(modbus_write_register(ctx, addr(RegId::gain_x_kp), 0x4000), 2);       // high word only
  expect_exception(modbus_write_register(ctx, addr(RegId::gain_x_kp) + 1, 0x4000), 2);   // low word only
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_x_kp), 3, gains), 2);    // kp + half of ki
  // A valid kp followed by a read-only register in the same write: nothing applied.
  expect_exception(modbus_write_registers(ctx, addr(RegId::cmd_code), 2, r), 2);
  // 03: out of range, NaN, and a whole write where only the LAST value is bad.
  std::uint16_t w[12];
  for (int i = 0; i < 12; ++i) w[i] = gains[i];
  set_f32(1.5f, w + 8);  // setpoint weight b = 1.5 > 1
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_y_kp), 12, w), 3);
  set_f32(-1.0f, w);
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_y_kp), 2, w), 3);
  w[0] = 0x7FC0;  // NaN
  w[1] = 0x0000;
  expect_exception(modbus_write_registers(ctx, addr(RegId::limit_peak_current), 2, w), 3);
  expect_exception(modbus_write_register(ctx, addr(RegId::cmd_axis), 6), 3);
  // The kernel refusing the candidate configuration is 03 too.
  {
    std::lock_guard<std::mutex> lock(m);
    dev.refuse_config = true;
  }
  set_f32(2.5f, w);
  expect_exception(modbus_write_registers(ctx, addr(RegId::limit_peak_current), 2, w), 3);
  {
    std::lock_guard<std::mutex> lock(m);
    dev.refuse_config = false;
    dev.apply_calls = before.apply_calls;  // the refused call is counted; nothing was applied
  }
  check_unchanged(m, server, dev, before);
  // 06: gains while moving or levitated (live tuning off), limits while levitated.
  {
    std::lock_guard<std::mutex> lock(m);
    dev.activity_ = Activity::kMoving;
  }
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_y_kp), 12, gains), 6);
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), kEngineerKey));
  expect_exception(modbus_write_register(ctx, addr(RegId::config_save), 1), 6);  // no flash write while moving
  {
    std::lock_guard<std::mutex> lock(m);
    dev.activity_ = Activity::kHolding;
  }
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_y_kp), 12, gains), 6);
  set_f32(3.0f, w);
  expect_exception(modbus_write_registers(ctx, addr(RegId::limit_peak_current), 2, w), 6);
  set_f32(0.2f, w);
  expect_exception(modbus_write_registers(ctx, addr(RegId::max_velocity_x), 2, w), 6);
  check_unchanged(m, server, dev, before);
  // Live tuning lets gains through while moving.
  {
    std::lock_guard<std::mutex> lock(m);
    dev.activity_ = Activity::kMoving;
  }
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::tuning_live), 1));
  set_f32(26000.0f, w);
  LONGS_EQUAL(2, modbus_write_registers(ctx, addr(RegId::gain_y_kp), 2, w));
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::tuning_live), 0));
  {
    std::lock_guard<std::mutex> lock(m);
    DOUBLES_EQUAL(26000.0, server.config().get(RegId::gain_y_kp), 0.0);
    CHECK(dev.last_live_tuning);
    dev.activity_ = Activity::kIdle;
  }
  // 01 again: engineer register after locking.
  LONGS_EQUAL(1, modbus_write_register(ctx, addr(RegId::access_key), 0));
  before = snap(m, server, dev);
  expect_exception(modbus_write_registers(ctx, addr(RegId::gain_y_kp), 2, w), 1);
  check_unchanged(m, server, dev, before);
  // Operator registers still work when locked.
  set_f32(0.2f, w);
  LONGS_EQUAL(2, modbus_write_registers(ctx, addr(RegId::max_velocity_x), 2, w));
}

}  // namespace maglev::modbus::test
