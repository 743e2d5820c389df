// USART RS-485: BRR, DE assertion/deassertion times, Modbus t3.5 timeout.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/usart_rs485.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace u = maglev::stm32h7::usart;
using Bus = r::FakeRegisterBus<>;

TEST_GROUP(Rs485Math){};

TEST(Rs485Math, BaudRateRegister) {
  UNSIGNED_LONGS_EQUAL(1042u, rs485::brr_value(120'000'000, 115'200));  // 1041.67 -> 0.03 % error
  UNSIGNED_LONGS_EQUAL(6250u, rs485::brr_value(120'000'000, 19'200));   // exact
  UNSIGNED_LONGS_EQUAL(0x209u, rs485::brr_value(60'000'000, 115'200));
}

TEST(Rs485Math, DriverEnableSampleTimes) {
  UNSIGNED_LONGS_EQUAL(2u, rs485::de_sample_times(1000, 115'200));   // 1.84 -> 2 sixteenths
  UNSIGNED_LONGS_EQUAL(1u, rs485::de_sample_times(1000, 19'200));    // 0.31 -> 1
  UNSIGNED_LONGS_EQUAL(31u, rs485::de_sample_times(100'000, 115'200));  // capped at the 5-bit max
}

TEST(Rs485Math, ModbusT35) {
  UNSIGNED_LONGS_EQUAL(202u, rs485::modbus_t35_bits(115'200));  // fixed 1.75 ms
  UNSIGNED_LONGS_EQUAL(39u, rs485::modbus_t35_bits(19'200));    // 3.5 chars x 11 bits
  UNSIGNED_LONGS_EQUAL(39u, rs485::modbus_t35_bits(9'600));
}

TEST_GROUP(Rs485) {
  Bus bus;
  rs485::UsartRs485<Bus> port{bus, rs485::Config{}};
  static constexpr r::Addr kB = u::kUsart3;
};

TEST(Rs485, InitWritesDeTimingBeforeEnabling) {
  port.init();
  UNSIGNED_LONGS_EQUAL(1042u, bus.peek(kB + u::kBrr));
  UNSIGNED_LONGS_EQUAL(0x4000u, bus.peek(kB + u::kCr3));    // DEM, DE active high
  UNSIGNED_LONGS_EQUAL(0x800000u, bus.peek(kB + u::kCr2));  // RTOEN
  UNSIGNED_LONGS_EQUAL(202u, bus.peek(kB + u::kRtor));
  // DEAT = 2 (bits 25:21), DEDT = 2 (bits 20:16), M0, PCE, TE, RE, UE.
  UNSIGNED_LONGS_EQUAL(0x0042140Du, bus.peek(kB + u::kCr1));
  const long config = bus.index_of_write(kB + u::kCr1, 1);
  const long enable = bus.index_of_write(kB + u::kCr1, 2);
  UNSIGNED_LONGS_EQUAL(0x0042140Cu, bus.log(static_cast<std::size_t>(config)).value);  // UE still 0
  CHECK(config < enable);
  CHECK(bus.index_of_write(kB + u::kBrr) < config);
}

TEST(Rs485, TransmitWritesBytesInOrderAndWaitsForTc) {
  bus.preset(kB + u::kIsr, u::kIsrTxe | u::kIsrTc);
  const std::uint8_t frame[] = {0x01, 0x03, 0x00, 0x10, 0x00, 0x02, 0xC5, 0xCE};
  CHECK_TRUE(port.transmit(frame, sizeof frame));
  LONGS_EQUAL(8, bus.writes_to(kB + u::kTdr));
  UNSIGNED_LONGS_EQUAL(0xC5u, bus.log(static_cast<std::size_t>(bus.index_of_write(kB + u::kTdr, 6))).value);
  bus.preset(kB + u::kIsr, 0u);  // TXE stuck low
  CHECK_FALSE(port.transmit(frame, 1, 50));
  LONGS_EQUAL(1, port.counters().tx_timeouts);
}

TEST(Rs485, ReceiveCountsAndClearsErrors) {
  bus.preset(kB + u::kIsr, u::kIsrRxne | u::kIsrPe);
  bus.preset(kB + u::kRdr, 0x15Au);
  std::uint8_t b = 0;
  CHECK_TRUE(port.receive_byte(b));
  UNSIGNED_LONGS_EQUAL(0x5Au, b);
  LONGS_EQUAL(1, port.counters().parity_errors);
  UNSIGNED_LONGS_EQUAL(u::kIsrPe, bus.peek(kB + u::kIcr));
  bus.preset(kB + u::kIsr, u::kIsrRtof);
  CHECK_TRUE(port.frame_gap_elapsed());
  UNSIGNED_LONGS_EQUAL(u::kIsrRtof, bus.peek(kB + u::kIcr));
}
