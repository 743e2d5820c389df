// Engineering access re-locks on a timer (issue 17): after 10 minutes
// without a successful write the server is back at operator level, so a
// forgotten engineer session does not leave the gains writable.
#include <cstdint>

#include "maglev/modbus/register_server.hpp"
#include "support/protocol_device.hpp"

// CppUTest last: its new/delete macros must not meet the STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev::modbus;

namespace {
std::uint16_t addr(RegId id) { return def(id).address; }
// Writes gain.x.kp (engineer level) as two words (F32).
ExceptionCode write_kp(RegisterServer& s, float v) {
  std::uint32_t bits = 0;
  static_assert(sizeof bits == sizeof v);
  __builtin_memcpy(&bits, &v, sizeof v);
  const std::uint16_t w[2] = {static_cast<std::uint16_t>(bits >> 16), static_cast<std::uint16_t>(bits & 0xFFFF)};
  return s.write_registers(addr(RegId::gain_x_kp), 2, w);
}
}  // namespace

TEST_GROUP(AccessRelock){};

TEST(AccessRelock, EngineerAccessFallsBackToOperatorAfterTenQuietMinutes) {
  test::ProtocolDevice dev;
  RegisterServer s(dev, ConfigImage::defaults());
  CHECK_TRUE(write_kp(s, 30000.0f) != ExceptionCode::kNone);  // operator level: gains locked
  const std::uint16_t key = kEngineerKey;
  CHECK_TRUE(s.write_registers(addr(RegId::access_key), 1, &key) == ExceptionCode::kNone);
  CHECK_TRUE(s.level() == Access::kEngineer);
  CHECK_TRUE(write_kp(s, 30000.0f) == ExceptionCode::kNone);
  // 9 minutes quiet: still open; a write restarts the clock.
  for (int i = 0; i < 540; ++i) s.advance_time_us(1000000);
  CHECK_TRUE(s.level() == Access::kEngineer);
  CHECK_TRUE(write_kp(s, 31000.0f) == ExceptionCode::kNone);
  for (int i = 0; i < 540; ++i) s.advance_time_us(1000000);
  CHECK_TRUE(s.level() == Access::kEngineer);
  // 10 minutes after the last write: operator again, engineer writes refused.
  for (int i = 0; i < 61; ++i) s.advance_time_us(1000000);
  CHECK_TRUE(s.level() == Access::kOperator);
  CHECK_TRUE(write_kp(s, 32000.0f) != ExceptionCode::kNone);
  DOUBLES_EQUAL(31000.0, s.config().get(RegId::gain_x_kp), 0.0);
}
