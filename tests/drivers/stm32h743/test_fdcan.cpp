// FDCAN: bit timing register values, init sequence, message RAM layout and
// element encoding.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/fdcan.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace can = maglev::can;
using Bus = r::FakeRegisterBus<128, 512>;

TEST_GROUP(FdcanTiming){};

TEST(FdcanTiming, OneMegabitNominalAt80MHz) {
  constexpr fdcan::BitTiming t = fdcan::nominal_timing(80'000'000, 1'000'000, 800);
  CHECK_TRUE(t.valid);
  LONGS_EQUAL(1, t.prescaler);
  LONGS_EQUAL(63, t.tseg1);
  LONGS_EQUAL(16, t.tseg2);
  LONGS_EQUAL(16, t.sjw);
  UNSIGNED_LONGS_EQUAL(0x1E003E0Fu, fdcan::nbtp_value(t));
}

TEST(FdcanTiming, FiveMegabitDataWithTdcAt80MHz) {
  constexpr fdcan::BitTiming t = fdcan::data_timing(80'000'000, 5'000'000, 750);
  CHECK_TRUE(t.valid);
  LONGS_EQUAL(1, t.prescaler);
  LONGS_EQUAL(11, t.tseg1);
  LONGS_EQUAL(4, t.tseg2);
  UNSIGNED_LONGS_EQUAL(0x00800A33u, fdcan::dbtp_value(t, true));
  UNSIGNED_LONGS_EQUAL(0x00000C00u, fdcan::tdcr_value(t, 0));  // TDCO = 12 mtq
}

TEST(FdcanTiming, CrossCheckAt40MHzAndAnImpossibleRate) {
  UNSIGNED_LONGS_EQUAL(0x0E001E07u, fdcan::nbtp_value(fdcan::nominal_timing(40'000'000, 1'000'000, 800)));
  UNSIGNED_LONGS_EQUAL(0x00800411u, fdcan::dbtp_value(fdcan::data_timing(40'000'000, 5'000'000, 750), true));
  CHECK_FALSE(fdcan::data_timing(80'000'000, 30'000'000, 750).valid);  // < 4 tq per bit
}

TEST(FdcanTiming, MessageRamLayoutFitsAndIsWordAligned) {
  constexpr fdcan::Layout l = fdcan::layout(0);
  UNSIGNED_LONGS_EQUAL(0x000u, l.rx_fifo0);
  UNSIGNED_LONGS_EQUAL(0x480u, l.tx_fifo);
  UNSIGNED_LONGS_EQUAL(0x6C0u, l.end);
  CHECK(l.end <= r::fdcan::kMessageRamBytes);
}

TEST_GROUP(Fdcan) {
  Bus bus;
  fdcan::Fdcan<Bus> port{bus, fdcan::Config{}};
  static constexpr r::Addr kBase = r::fdcan::kFdcan1;
};

TEST(Fdcan, InitProgramsTimingOnlyWhileInitAndCceAreSet) {
  CHECK(port.init() == fdcan::InitStatus::kOk);
  UNSIGNED_LONGS_EQUAL(0x1E003E0Fu, bus.peek(kBase + r::fdcan::kNbtp));
  UNSIGNED_LONGS_EQUAL(0x00800A33u, bus.peek(kBase + r::fdcan::kDbtp));
  UNSIGNED_LONGS_EQUAL(0x00000C00u, bus.peek(kBase + r::fdcan::kTdcr));
  UNSIGNED_LONGS_EQUAL(0x00100000u, bus.peek(kBase + r::fdcan::kRxf0c));  // 16 elements at +0
  UNSIGNED_LONGS_EQUAL(0x08000480u, bus.peek(kBase + r::fdcan::kTxbc));   // 8-deep FIFO at +0x480
  UNSIGNED_LONGS_EQUAL(7u, bus.peek(kBase + r::fdcan::kRxesc));
  UNSIGNED_LONGS_EQUAL(7u, bus.peek(kBase + r::fdcan::kTxesc));
  UNSIGNED_LONGS_EQUAL(0x0Bu, bus.peek(kBase + r::fdcan::kGfc));
  UNSIGNED_LONGS_EQUAL(0x300u, bus.peek(kBase + r::fdcan::kCccr));  // FDOE | BRSE, INIT left
  const long init = bus.index_of_write(kBase + r::fdcan::kCccr, 0);
  const long cce = bus.index_of_write(kBase + r::fdcan::kCccr, 1);
  const long nbtp = bus.index_of_write(kBase + r::fdcan::kNbtp);
  const long run = bus.index_of_write(kBase + r::fdcan::kCccr, 3);
  UNSIGNED_LONGS_EQUAL(0x1u, bus.log(static_cast<std::size_t>(init)).value);
  UNSIGNED_LONGS_EQUAL(0x3u, bus.log(static_cast<std::size_t>(cce)).value);
  CHECK(cce < nbtp && nbtp < run);
}

TEST(Fdcan, SendWritesTheTxElementAndRequestsTransmission) {
  bus.preset(kBase + r::fdcan::kTxfqs, 3u << 16);  // put index 3
  can::CanFrame f{};
  f.id = 0x123;
  f.len = 12;
  f.flags = can::kFlagFd | can::kFlagBrs;
  for (int i = 0; i < 12; ++i) f.data[i] = static_cast<std::uint8_t>(i);
  CHECK(port.send(f) == can::PortStatus::kOk);
  const r::Addr e = r::fdcan::kMessageRam + 0x480 + 3 * 72;
  UNSIGNED_LONGS_EQUAL(0x4000B158u, e);
  UNSIGNED_LONGS_EQUAL(0x048C0000u, bus.peek(e));      // std ID in [28:18]
  UNSIGNED_LONGS_EQUAL(0x00390000u, bus.peek(e + 4));  // FDF | BRS | DLC 9 (12 bytes)
  UNSIGNED_LONGS_EQUAL(0x03020100u, bus.peek(e + 8));
  UNSIGNED_LONGS_EQUAL(0x0B0A0908u, bus.peek(e + 16));
  UNSIGNED_LONGS_EQUAL(0x8u, bus.peek(kBase + r::fdcan::kTxbar));
  LONGS_EQUAL(1, port.counters().tx_frames);
}

TEST(Fdcan, SendRejectsFullQueueBusOffAndBadLengths) {
  can::CanFrame f{};
  f.id = 0x10;
  f.len = 12;  // needs FD
  CHECK(port.send(f) == can::PortStatus::kBadFrame);
  f.flags = can::kFlagFd;
  f.len = 13;
  CHECK(port.send(f) == can::PortStatus::kBadFrame);
  f.len = 8;
  bus.preset(kBase + r::fdcan::kTxfqs, r::fdcan::kTxfqsTfqf);
  CHECK(port.send(f) == can::PortStatus::kTxFull);
  bus.preset(kBase + r::fdcan::kPsr, r::fdcan::kPsrBo);
  CHECK(port.send(f) == can::PortStatus::kBusOff);
  LONGS_EQUAL(4, port.counters().tx_errors);
  LONGS_EQUAL(0, bus.writes_to(kBase + r::fdcan::kTxbar));
}

TEST(Fdcan, ReceiveDecodesTheRxElementAndAcknowledges) {
  const r::Addr e = r::fdcan::kMessageRam + 2 * 72;
  bus.preset(kBase + r::fdcan::kRxf0s, (2u << 8) | 1u);  // get index 2, fill level 1
  bus.preset(e, (0x7FFu << 18) | r::fdcan::kElemEsi);
  bus.preset(e + 4, r::fdcan::kElemFdf | r::fdcan::kElemBrs | (15u << 16));  // DLC 15 = 64 bytes
  for (unsigned w = 0; w < 16; ++w) bus.preset(e + 8 + 4 * w, 0x01010101u * w);
  can::CanFrame f{};
  CHECK(port.receive(f, 0) == can::PortStatus::kOk);
  UNSIGNED_LONGS_EQUAL(0x7FFu, f.id);
  LONGS_EQUAL(64, f.len);
  LONGS_EQUAL(can::kFlagFd | can::kFlagBrs | can::kFlagEsi, f.flags);
  LONGS_EQUAL(15, f.data[63]);
  LONGS_EQUAL(1, f.data[4]);
  UNSIGNED_LONGS_EQUAL(2u, bus.peek(kBase + r::fdcan::kRxf0a));
  bus.preset(kBase + r::fdcan::kRxf0s, 0u);
  CHECK(port.receive(f, 0) == can::PortStatus::kTimeout);
  LONGS_EQUAL(1, port.counters().rx_timeouts);
}

TEST(Fdcan, RxFifoMessageLostIsCountedAndCleared) {
  bus.preset(kBase + r::fdcan::kIr, r::fdcan::kIrRf0l);
  can::CanFrame f{};
  port.receive(f, 0);
  LONGS_EQUAL(1, port.counters().rx_overruns);
  UNSIGNED_LONGS_EQUAL(r::fdcan::kIrRf0l, bus.log(static_cast<std::size_t>(bus.index_of_write(kBase + r::fdcan::kIr))).value);
}
