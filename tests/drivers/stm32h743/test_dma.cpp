// DMA stream driver (RM0433 §15/§17): the exact register sequence that arms a
// peripheral -> memory stream, its DMAMUX routing, completion and error flags
// per stream (LISR/HISR bit positions), and that a result is reported once.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/stm32h7_dma.hpp"
#include "maglev/stm32h7/register_bus.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
using Bus = r::FakeRegisterBus<>;

TEST_GROUP(DmaStream){};

TEST(DmaStream, FlagPositionsFollowTheManual) {
  // §15.5.5: stream 0 at 0, 1 at 6, 2 at 16, 3 at 22; 4..7 the same in HISR.
  LONGS_EQUAL(0, r::dma::flag_shift(0));
  LONGS_EQUAL(6, r::dma::flag_shift(1));
  LONGS_EQUAL(16, r::dma::flag_shift(2));
  LONGS_EQUAL(22, r::dma::flag_shift(3));
  LONGS_EQUAL(22, r::dma::flag_shift(7));
  UNSIGNED_LONGS_EQUAL(r::dma::kLisr, r::dma::isr(3));
  UNSIGNED_LONGS_EQUAL(r::dma::kHisr, r::dma::isr(4));
  UNSIGNED_LONGS_EQUAL(r::dma::kHifcr, r::dma::ifcr(7));
  UNSIGNED_LONGS_EQUAL(0x40020010u, r::dma::stream(r::dma::kDma1, 0));
  UNSIGNED_LONGS_EQUAL(0x400200B8u, r::dma::stream(r::dma::kDma1, 7));
  UNSIGNED_LONGS_EQUAL(0x40020800u, r::dma::dmamux_channel(r::dma::kDma1, 0));
  UNSIGNED_LONGS_EQUAL(0x40020824u, r::dma::dmamux_channel(r::dma::kDma2, 1));  // channel 9
}

TEST(DmaStream, InitRoutesTheDmamuxChannel) {
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 2, r::dma::kReqSpi3Rx, true});
  s.init();
  UNSIGNED_LONGS_EQUAL(61u, bus.peek(0x40020808u));  // DMAMUX1 C2CR = spi3_rx_dma
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(r::dma::stream(r::dma::kDma1, 2) + r::dma::kSxCr));
  UNSIGNED_LONGS_EQUAL(0x3Du << 16, bus.peek(r::dma::kDma1 + r::dma::kLifcr));  // stream 2's flags cleared
  CHECK(s.poll() == dma::Status::kIdle);
}

TEST(DmaStream, PeripheralAddressAndDirectModeAreWrittenOncePerPeripheral) {
  // PAR and FCR keep their values while EN = 0: the next transfer of the
  // same peripheral writes only the flags, M0AR, NDTR and CR.
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, true});
  s.init();
  const r::Addr st = r::dma::stream(r::dma::kDma1, 0);
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  bus.write32(r::dma::kDma1 + r::dma::kLisr, r::dma::kFlagTc);  // transfer complete
  bus.write32(st + r::dma::kSxCr, 0u);                           // the hardware clears EN
  CHECK(s.poll() == dma::Status::kComplete);
  bus.clear_log();
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000110u, 4) == dma::Status::kBusy);
  LONGS_EQUAL(0, bus.writes_to(st + r::dma::kSxPar));
  LONGS_EQUAL(0, bus.writes_to(st + r::dma::kSxFcr));
  UNSIGNED_LONGS_EQUAL(0x30000110u, bus.peek(st + r::dma::kSxM0ar));
  LONGS_EQUAL(1, bus.writes_to(st + r::dma::kSxNdtr));
  LONGS_EQUAL(static_cast<long>(bus.log_size()) - 1, bus.index_of_write(st + r::dma::kSxCr));
  // Another peripheral: PAR (and FCR) again; after init() too.
  s.abort();
  bus.clear_log();
  CHECK(s.start_peripheral_to_memory(0x40013030u, 0x30000100u, 4) == dma::Status::kBusy);
  UNSIGNED_LONGS_EQUAL(0x40013030u, bus.peek(st + r::dma::kSxPar));
  LONGS_EQUAL(1, bus.writes_to(st + r::dma::kSxFcr));
  s.abort();
  s.init();
  bus.clear_log();
  CHECK(s.start_peripheral_to_memory(0x40013030u, 0x30000100u, 4) == dma::Status::kBusy);
  LONGS_EQUAL(1, bus.writes_to(st + r::dma::kSxPar));
}

TEST(DmaStream, StartArmsPeripheralToMemoryEnableLast) {
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, true});
  s.init();
  bus.clear_log();
  const r::Addr st = r::dma::stream(r::dma::kDma1, 0);
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  UNSIGNED_LONGS_EQUAL(0x40003C30u, bus.peek(st + r::dma::kSxPar));
  UNSIGNED_LONGS_EQUAL(0x30000100u, bus.peek(st + r::dma::kSxM0ar));
  UNSIGNED_LONGS_EQUAL(4u, bus.peek(st + r::dma::kSxNdtr));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(st + r::dma::kSxFcr));  // direct mode
  // DIR = 0 (P->M), MINC, PSIZE = MSIZE = word, PL very high, TCIE|TEIE|DMEIE, EN.
  const std::uint32_t cr = r::bit(10) | (2u << 11) | (2u << 13) | (3u << 16) | r::bit(4) | r::bit(2) | r::bit(1) | 1u;
  UNSIGNED_LONGS_EQUAL(cr, bus.peek(st + r::dma::kSxCr));
  // Flags cleared before the addresses; CR (with EN) is the last write.
  CHECK(bus.index_of_write(r::dma::kDma1 + r::dma::kLifcr) < bus.index_of_write(st + r::dma::kSxPar));
  LONGS_EQUAL(static_cast<long>(bus.log_size()) - 1, bus.index_of_write(st + r::dma::kSxCr));
  CHECK(s.poll() == dma::Status::kBusy);
}

TEST(DmaStream, RefusesWhileEnabledAndBadArguments) {
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, false});
  s.init();
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000102u, 4) == dma::Status::kBadArgument);  // unaligned
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 0) == dma::Status::kBadArgument);
  bus.preset(r::dma::stream(r::dma::kDma1, 0) + r::dma::kSxCr, r::dma::kCrEn);  // a transfer still runs
  bus.clear_log();
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kStillRunning);
  LONGS_EQUAL(0, bus.log_size());  // nothing touched
}

namespace {
// What the hardware does at the end of a transfer (or on an error): EN
// clears, the stream's flags are set.
void hardware_ends(Bus& bus, unsigned stream, std::uint32_t hisr) {
  const r::Addr cr = r::dma::stream(r::dma::kDma1, stream) + r::dma::kSxCr;
  bus.preset(cr, bus.peek(cr) & ~r::dma::kCrEn);
  bus.preset(r::dma::kDma1 + r::dma::kHisr, hisr);
}
}  // namespace

TEST(DmaStream, CompletionAndErrorReportedOnceFromTheirOwnStreamBits) {
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 5, r::dma::kReqSpi3Rx, true});  // HISR bits 11..6
  s.init();
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  bus.preset(r::dma::kDma1 + r::dma::kLisr, 0xFFFFFFFFu);          // other streams' flags: ignored
  bus.preset(r::dma::kDma1 + r::dma::kHisr, r::dma::kFlagTc);      // stream 4's TCIF: not ours
  CHECK(s.poll() == dma::Status::kBusy);
  hardware_ends(bus, 5, r::dma::kFlagTc << 6);  // stream 5 TCIF
  CHECK(s.poll() == dma::Status::kComplete);
  UNSIGNED_LONGS_EQUAL(0x3Du << 6, bus.peek(r::dma::kDma1 + r::dma::kHifcr));
  CHECK(s.poll() == dma::Status::kIdle);  // reported once
  // TEIF (even together with TCIF) is an error.
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  hardware_ends(bus, 5, (r::dma::kFlagTc | r::dma::kFlagTe) << 6);
  CHECK(s.poll() == dma::Status::kError);
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  hardware_ends(bus, 5, r::dma::kFlagDme << 6);
  CHECK(s.poll() == dma::Status::kError);
}

TEST(DmaStream, AbortDisablesAndClears) {
  Bus bus;
  dma::Stream<Bus> s(bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, true});
  s.init();
  CHECK(s.start_peripheral_to_memory(0x40003C30u, 0x30000100u, 4) == dma::Status::kBusy);
  s.abort();
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(r::dma::stream(r::dma::kDma1, 0) + r::dma::kSxCr));
  CHECK(s.poll() == dma::Status::kIdle);
}
