// Stm32SpiMaster's start/complete (RX DMA) mode over dma::Stream, reading
// the AD7606 pair's words: on a FakeRegisterBus whose SPI3 + DMA1 stream 0
// registers are answered by the shared register-level model
// (spi_rx_dma_model.hpp) clocking the AD7606 serial models. Checks the
// register sequence (RM0433 §50.4.14 order), the data, completion, errors and
// cancel, and what start() refuses. (The board reads the pair with the
// register-level ad7606::Stm32DmaReader: test_ad7606_stm32_dma.cpp.)
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/ad7606_model.hpp"
#include "maglev/drivers/fake_bus.hpp"
#include "maglev/drivers/spi_rx_dma_model.hpp"
#include "maglev/drivers/stm32h7_dma.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"
#include "maglev/stm32h7/register_bus.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
using Bus = r::FakeRegisterBus<>;

namespace {

constexpr r::Addr kSpi = r::spi::kSpi3;
const r::Addr kS0 = r::dma::stream(r::dma::kDma1, 0);

// The chips behind SPI3: whichever CS is low drives MISO.
struct Chips final : dma::WordSource {
  FakeOutputPin<> cs0, cs1;
  ad7606::DeviceModel adc0, adc1;
  std::uint32_t next_word() override {
    if (!cs0.level()) return adc0.clock_word(0, 32);
    if (!cs1.level()) return adc1.clock_word(0, 32);
    return 0xFFFFFFFFu;  // nobody selected: MISO floats high
  }
};

void release(void* model, bool high) {
  if (high) static_cast<ad7606::DeviceModel*>(model)->chip_select_released();
}

std::uint32_t addr_of(const std::uint32_t* p) { return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(p)); }

}  // namespace

TEST_GROUP(Ad7606Dma) {
  Bus bus;
  Chips chips;
  dma::SpiRxDmaModel model{kSpi, r::dma::kDma1, 0, r::dma::kReqSpi3Rx};
  SpiDeviceSettings devs[2] = {{&chips.cs0, 2, true, false}, {&chips.cs1, 2, true, false}};
  Stm32SpiMaster<Bus, 2> spi{bus, kSpi, devs};
  dma::Stream<Bus> stream{bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, true}};
  std::uint32_t buffer[2][4]{};

  static void on_write(void* self, Bus&, r::Addr a, std::uint32_t v) {
    auto* g = static_cast<TEST_GROUP_CppUTestGroupAd7606Dma*>(self);
    g->model.write(a, v, g->chips);
  }
  static std::uint32_t on_read(void* self, Bus&, r::Addr a, std::uint32_t stored) {
    std::uint32_t v = 0;
    return static_cast<TEST_GROUP_CppUTestGroupAd7606Dma*>(self)->model.read(a, &v) ? v : stored;
  }
  void setup() override {
    bus.set_write_hook(&on_write, this);
    bus.set_read_hook(&on_read, this);
    chips.cs0.set_hook(&release, &chips.adc0);
    chips.cs1.set_hook(&release, &chips.adc1);
    model.map_memory(&buffer[0][0], 8);
    spi.init();
    stream.init();
    spi.attach_rx_dma(&stream);
    for (std::size_t ch = 0; ch < 8; ++ch) {
      chips.adc0.set_code(ch, static_cast<std::int16_t>(100 * (static_cast<int>(ch) + 1)));
      chips.adc1.set_code(ch, static_cast<std::int16_t>(-1000 * (static_cast<int>(ch) + 1)));
    }
  }
  // ADC d's four words into buffer[d], start to completion.
  BusStatus read_device(std::uint8_t dev) {
    const BusStatus started = spi.start(SpiTransfer{dev, 32, nullptr, buffer[dev], 4});
    return started == BusStatus::kOk ? spi.complete() : started;
  }
  void check_codes() {
    ad7606::Codes codes{};
    for (std::size_t dev = 0; dev < 2; ++dev) ad7606::decode_words(buffer[dev], codes.channel[dev]);
    for (std::size_t ch = 0; ch < 8; ++ch) {
      const int n = static_cast<int>(ch) + 1;
      LONGS_EQUAL(100 * n, codes.channel[0][ch]);
      LONGS_EQUAL(-1000 * n, codes.channel[1][ch]);
    }
  }
};

TEST(Ad7606Dma, StartFollowsTheDmaProcedureAndCompleteEndsTheFrame) {
  bus.clear_log();
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, buffer[0], 4}) == BusStatus::kOk);
  CHECK(spi.busy());
  CHECK(!chips.cs0.level());
  // CFG1: MBR /8 (code 2), DSIZE 32 bits, RXDMAEN. CFG2: master, SSM, AFCNTR, mode 2, simplex receiver.
  UNSIGNED_LONGS_EQUAL((2u << 28) | 31u | r::bit(14), bus.log(static_cast<std::size_t>(bus.index_of_write(kSpi + r::spi::kCfg1))).value);
  UNSIGNED_LONGS_EQUAL(r::bit(22) | r::bit(26) | r::bit(31) | r::bit(25) | (2u << 17),
                       bus.log(static_cast<std::size_t>(bus.index_of_write(kSpi + r::spi::kCfg2))).value);
  UNSIGNED_LONGS_EQUAL(4u, bus.peek(kSpi + r::spi::kCr2));  // TSIZE
  UNSIGNED_LONGS_EQUAL(kSpi + r::spi::kRxdr, bus.peek(kS0 + r::dma::kSxPar));
  UNSIGNED_LONGS_EQUAL(addr_of(&buffer[0][0]), bus.peek(kS0 + r::dma::kSxM0ar));
  // RXDMAEN, then the stream (EN), then SPE, then CSTART (RM0433 §50.4.14).
  const long cfg1 = bus.index_of_write(kSpi + r::spi::kCfg1);
  const long stream_en = bus.index_of_write(kS0 + r::dma::kSxCr);
  const long spe = bus.index_of_write(kSpi + r::spi::kCr1, 1);
  const long cstart = bus.index_of_write(kSpi + r::spi::kCr1, 2);
  CHECK(cfg1 < stream_en);
  CHECK(stream_en < spe);
  CHECK(spe < cstart);
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi | r::spi::kCr1Spe | r::spi::kCr1Cstart, bus.log(static_cast<std::size_t>(cstart)).value);
  // Completion: the words in memory, SPE off, CS released; once.
  bus.clear_log();
  CHECK(spi.complete() == BusStatus::kOk);
  CHECK(chips.cs0.level());
  CHECK(!spi.busy());
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi, bus.peek(kSpi + r::spi::kCr1));
  LONGS_EQUAL(1, bus.writes_to(kSpi + r::spi::kIfcr));
  CHECK(spi.complete() == BusStatus::kNotStarted);
  LONGS_EQUAL(128, chips.adc0.last_frame_bits());  // one CS frame of 128 SCLKs
  // No CPU word traffic: TXDR never written.
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kTxdr));
  // The second device on its own buffer.
  CHECK(read_device(1) == BusStatus::kOk);
  UNSIGNED_LONGS_EQUAL(addr_of(&buffer[1][0]), bus.peek(kS0 + r::dma::kSxM0ar));
  CHECK(chips.cs1.level());
  LONGS_EQUAL(128, chips.adc1.last_frame_bits());
  LONGS_EQUAL(2, model.transfers());
  check_codes();
}

TEST(Ad7606Dma, TheSecondDeviceAndTheNextTicksKeepTheSpiConfiguration) {
  // CFG1 / CFG2 (and the stream's PAR / FCR) are written by the first
  // transaction only: the pair shares its settings, SPE is 0 between them.
  CHECK(read_device(0) == BusStatus::kOk);
  bus.clear_log();
  CHECK(read_device(1) == BusStatus::kOk);
  CHECK(read_device(0) == BusStatus::kOk);
  CHECK(read_device(1) == BusStatus::kOk);
  check_codes();
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg2));
  LONGS_EQUAL(0, bus.writes_to(kS0 + r::dma::kSxPar));
  LONGS_EQUAL(3, bus.writes_to(kS0 + r::dma::kSxNdtr));
  // RXDMAEN still set from the first transaction, every frame complete.
  CHECK((bus.peek(kSpi + r::spi::kCfg1) & r::bit(14)) != 0u);
  LONGS_EQUAL(4, model.transfers());
}

TEST(Ad7606Dma, CancelStopsAStalledStreamAndReleasesCs) {
  model.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, buffer[0], 4}) == BusStatus::kOk);
  CHECK(spi.complete() == BusStatus::kBusy);
  CHECK(spi.complete() == BusStatus::kBusy);
  spi.cancel();
  CHECK(chips.cs0.level());                                                 // CS released
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kS0 + r::dma::kSxCr) & r::dma::kCrEn);  // stream stopped
  CHECK(!spi.busy());
  CHECK(spi.complete() == BusStatus::kNotStarted);
  // The next transaction runs normally again.
  model.inject(dma::SpiRxDmaModel::Fault::kNone);
  CHECK(read_device(0) == BusStatus::kOk);
  CHECK(read_device(1) == BusStatus::kOk);
  check_codes();
}

TEST(Ad7606Dma, TransferErrorIsReportedAndReleasesCs) {
  model.inject(dma::SpiRxDmaModel::Fault::kTransferError);
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, buffer[0], 4}) == BusStatus::kOk);
  CHECK(spi.complete() == BusStatus::kTransferError);
  CHECK(chips.cs0.level());
  CHECK(!spi.busy());
  // A buffer the DMA may not write (outside the mapped memory): a transfer error too.
  std::uint32_t elsewhere[4]{};
  CHECK(spi.start(SpiTransfer{1, 32, nullptr, elsewhere, 4}) == BusStatus::kOk);
  CHECK(spi.complete() == BusStatus::kTransferError);
  CHECK(chips.cs1.level());
}

TEST(Ad7606Dma, WrongDmamuxRequestNeverCompletes) {
  // The model moves data only for a stream routed to spi3_rx_dma: a
  // mis-routed stream (SPI2's request) stays busy until cancelled.
  dma::Stream<Bus> wrong{bus, {r::dma::kDma1, 0, r::dma::kReqSpi2Rx, true}};
  wrong.init();
  spi.attach_rx_dma(&wrong);
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, buffer[0], 4}) == BusStatus::kOk);
  CHECK(spi.complete() == BusStatus::kBusy);
  spi.cancel();
  CHECK(chips.cs0.level());
  LONGS_EQUAL(0, model.transfers());
}

TEST(Ad7606Dma, PolledTransferRefusedWhileADmaFrameIsOpen) {
  model.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, buffer[0], 4}) == BusStatus::kOk);
  std::uint32_t rx[4]{};
  CHECK(spi.transfer(SpiTransfer{0, 32, nullptr, rx, 4}) == BusStatus::kBusy);
  CHECK(spi.start(SpiTransfer{1, 32, nullptr, rx, 4}) == BusStatus::kBusy);
  CHECK(spi.start(SpiTransfer{1, 32, rx, rx, 4}) == BusStatus::kBadArgument);  // receive-only
  spi.cancel();
  CHECK(spi.complete() == BusStatus::kNotStarted);
}

// start() is receive-only: with TX words it is refused before anything is
// driven, even with the DMA stream attached and the bus idle (the AD5764
// chain's interrupt writes are ad5764::Stm32IrqWriter's, not the master's).
TEST(Ad7606Dma, StartWithTxWordsIsRefusedAndDrivesNothing) {
  const std::uint32_t tx[2] = {0x100001u, 0x100064u};
  std::uint32_t rx[2]{};
  bus.clear_log();
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kBadArgument);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));
  CHECK_TRUE(chips.cs0.level());
  CHECK_FALSE(spi.busy());
  CHECK(spi.complete() == BusStatus::kNotStarted);
  // The same shape receive-only is accepted.
  CHECK(spi.start(SpiTransfer{0, 32, nullptr, &buffer[0][0], 4}) == BusStatus::kOk);
  CHECK_TRUE(spi.busy());
  spi.cancel();
  CHECK_FALSE(spi.busy());
}
