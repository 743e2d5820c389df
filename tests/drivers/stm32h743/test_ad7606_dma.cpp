// The AD7606 pair read by DMA: ad7606::DmaReader over the real
// Stm32SpiMaster start/complete mode and dma::Stream, on a FakeRegisterBus
// whose SPI3 + DMA1 stream 0 registers are answered by the shared
// register-level model (spi_rx_dma_model.hpp) clocking the AD7606 serial
// models. Checks the register sequence (RM0433 §50.4.14 order), the data,
// and that anything but one complete read per tick is sensor loss.
#include <CppUTest/TestHarness.h>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
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

struct FixedEncoder {
  std::uint32_t count = 0;
  std::uint32_t update() { return count; }
  bool signal_lost() const { return false; }
};

}  // namespace

TEST_GROUP(Ad7606Dma) {
  Bus bus;
  Chips chips;
  dma::SpiRxDmaModel model{kSpi, r::dma::kDma1, 0, r::dma::kReqSpi3Rx};
  SpiDeviceSettings devs[2] = {{&chips.cs0, 2, true, false}, {&chips.cs1, 2, true, false}};
  Stm32SpiMaster<Bus, 2> spi{bus, kSpi, devs};
  dma::Stream<Bus> stream{bus, {r::dma::kDma1, 0, r::dma::kReqSpi3Rx, true}};
  FakeInputPin busy{false};
  std::uint32_t buffer[2][4]{};
  const std::uint8_t cs[2] = {0, 1};
  ad7606::DmaReader adc{spi, cs, busy, buffer};

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
  void check_codes(const ad7606::Codes& codes) {
    for (std::size_t ch = 0; ch < 8; ++ch) {
      const int n = static_cast<int>(ch) + 1;
      LONGS_EQUAL(100 * n, codes.channel[0][ch]);
      LONGS_EQUAL(-1000 * n, codes.channel[1][ch]);
    }
  }
};

TEST(Ad7606Dma, BusyFallDmaChainThenTickTakesBothDevices) {
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kNextDevice);  // ADC0 done, ADC1 started
  CHECK(adc.advance() == ad7606::DmaReader::Step::kComplete);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  check_codes(codes);
  LONGS_EQUAL(2, model.transfers());
  LONGS_EQUAL(128, chips.adc0.last_frame_bits());  // one CS frame of 128 SCLKs per device
  LONGS_EQUAL(128, chips.adc1.last_frame_bits());
  CHECK(chips.cs0.level());
  CHECK(chips.cs1.level());
  LONGS_EQUAL(1, adc.state().reads);
  // No CPU word traffic: RXDR was never read, TXDR never written.
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kTxdr));
}

TEST(Ad7606Dma, RegisterSequenceFollowsTheDmaProcedure) {
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kOk);
  // CFG1: MBR /8 (code 2), DSIZE 32 bits, RXDMAEN. CFG2: master, SSM, AFCNTR, mode 2, simplex receiver.
  UNSIGNED_LONGS_EQUAL((2u << 28) | 31u | r::bit(14), bus.log(static_cast<std::size_t>(bus.index_of_write(kSpi + r::spi::kCfg1))).value);
  UNSIGNED_LONGS_EQUAL(r::bit(22) | r::bit(26) | r::bit(31) | r::bit(25) | (2u << 17),
                       bus.log(static_cast<std::size_t>(bus.index_of_write(kSpi + r::spi::kCfg2))).value);
  UNSIGNED_LONGS_EQUAL(4u, bus.peek(kSpi + r::spi::kCr2));  // TSIZE
  UNSIGNED_LONGS_EQUAL(kSpi + r::spi::kRxdr, bus.peek(kS0 + r::dma::kSxPar));
  UNSIGNED_LONGS_EQUAL(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&buffer[0][0])),
                       bus.peek(kS0 + r::dma::kSxM0ar));
  // RXDMAEN, then the stream (EN), then SPE, then CSTART (RM0433 §50.4.14).
  const long cfg1 = bus.index_of_write(kSpi + r::spi::kCfg1);
  const long stream_en = bus.index_of_write(kS0 + r::dma::kSxCr);
  const long spe = bus.index_of_write(kSpi + r::spi::kCr1, 1);
  const long cstart = bus.index_of_write(kSpi + r::spi::kCr1, 2);
  CHECK(cfg1 < stream_en);
  CHECK(stream_en < spe);
  CHECK(spe < cstart);
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi | r::spi::kCr1Spe | r::spi::kCr1Cstart, bus.log(static_cast<std::size_t>(cstart)).value);
  // Completion: flags cleared, SPE off, CS released; the second device's frame starts.
  CHECK(adc.advance() == ad7606::DmaReader::Step::kNextDevice);
  CHECK(chips.cs0.level());
  CHECK(!chips.cs1.level());
  UNSIGNED_LONGS_EQUAL(static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(&buffer[1][0])),
                       bus.peek(kS0 + r::dma::kSxM0ar));
}

TEST(Ad7606Dma, TheSecondDeviceAndTheNextTicksKeepTheSpiConfiguration) {
  // CFG1 / CFG2 (and the stream's PAR / FCR) are written by the first
  // transaction only: the pair shares its settings, SPE is 0 between them.
  CHECK(adc.begin() == ad7606::Status::kOk);
  bus.clear_log();
  CHECK(adc.advance() == ad7606::DmaReader::Step::kNextDevice);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kComplete);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kNextDevice);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kComplete);
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  check_codes(codes);
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg2));
  LONGS_EQUAL(0, bus.writes_to(kS0 + r::dma::kSxPar));
  LONGS_EQUAL(3, bus.writes_to(kS0 + r::dma::kSxNdtr));  // ADC1, then ADC0 and ADC1 of the next conversion
  // RXDMAEN still set from the first transaction, every frame complete.
  CHECK((bus.peek(kSpi + r::spi::kCfg1) & r::bit(14)) != 0u);
  LONGS_EQUAL(4, model.transfers());
}

TEST(Ad7606Dma, ACompletedPairIsTakenOnlyOnce) {
  CHECK(adc.begin() == ad7606::Status::kOk);
  while (adc.advance() == ad7606::DmaReader::Step::kNextDevice) {
  }
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);  // no new read: loss, not the old words
  LONGS_EQUAL(1, adc.state().not_ready);
}

TEST(Ad7606Dma, NotStartedIsSensorLoss) {
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kIdle);
  LONGS_EQUAL(0, model.transfers());
}

TEST(Ad7606Dma, TickBeforeTheDmaCompletesCancelsAndReportsLoss) {
  model.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kBusy);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  CHECK(chips.cs0.level());                                           // CS released
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kS0 + r::dma::kSxCr) & r::dma::kCrEn);  // stream stopped
  CHECK(!spi.busy());
  // The next conversion reads normally again.
  model.inject(dma::SpiRxDmaModel::Fault::kNone);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kNextDevice);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kComplete);
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  check_codes(codes);
}

TEST(Ad7606Dma, TransferErrorIsBusErrorNotStaleData) {
  // A first good read fills the buffer with valid-looking words ...
  CHECK(adc.begin() == ad7606::Status::kOk);
  while (adc.advance() == ad7606::DmaReader::Step::kNextDevice) {
  }
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  // ... the next one fails on ADC0: the tick runs (kError) and gets no data.
  model.inject(dma::SpiRxDmaModel::Fault::kTransferError);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kError);
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
  LONGS_EQUAL(1, adc.state().bus_errors);
  CHECK(chips.cs0.level());
  CHECK(chips.cs1.level());
}

TEST(Ad7606Dma, PreviousReadNeverCompletedAtTheNextBusyFall) {
  model.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.begin() == ad7606::Status::kNotReady);  // cancelled: this conversion is lost too
  CHECK(chips.cs0.level());
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  LONGS_EQUAL(1, adc.state().not_ready);
}

TEST(Ad7606Dma, BusyHighAtTheStartIsReported) {
  busy.set(true);
  CHECK(adc.begin() == ad7606::Status::kStillBusy);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kStillBusy);
  LONGS_EQUAL(1, adc.state().busy_faults);
  LONGS_EQUAL(0, model.transfers());
}

TEST(Ad7606Dma, WrongDmamuxRequestNeverCompletes) {
  // The model moves data only for a stream routed to spi3_rx_dma: a
  // mis-routed stream (SPI2's request) stays busy, and the tick sees loss.
  dma::Stream<Bus> wrong{bus, {r::dma::kDma1, 0, r::dma::kReqSpi2Rx, true}};
  wrong.init();
  spi.attach_rx_dma(&wrong);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == ad7606::DmaReader::Step::kBusy);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  LONGS_EQUAL(0, model.transfers());
}

TEST(Ad7606Dma, DmaOutsideTheMappedBufferIsATransferError) {
  std::uint32_t elsewhere[2][4]{};
  ad7606::DmaReader stray{spi, cs, busy, elsewhere};
  CHECK(stray.begin() == ad7606::Status::kOk);
  CHECK(stray.advance() == ad7606::DmaReader::Step::kError);
  ad7606::Codes codes{};
  CHECK(stray.read(codes) == ad7606::Status::kBusError);
}

TEST(Ad7606Dma, PolledTransferRefusedWhileADmaFrameIsOpen) {
  model.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(adc.begin() == ad7606::Status::kOk);
  std::uint32_t rx[4]{};
  CHECK(spi.transfer(SpiTransfer{0, 32, nullptr, rx, 4}) == BusStatus::kBusy);
  CHECK(spi.start(SpiTransfer{1, 32, nullptr, rx, 4}) == BusStatus::kBusy);
  CHECK(spi.start(SpiTransfer{1, 32, rx, rx, 4}) == BusStatus::kBadArgument);  // receive-only
  spi.cancel();
  CHECK(spi.complete() == BusStatus::kNotStarted);
}

// The board's sensor source over the DMA reader: a completed pair is a good
// sample; no completed pair is kAdcFault and read() false (the servo loop
// counts a sensor fault), never the previous sample's ADC values.
TEST(Ad7606Dma, BoardSensorSourceReportsLossAsAdcFault) {
  FixedEncoder e0, e1, e2;
  maglev::board::stm32h743::AmplifierBoardSensors<FixedEncoder, ad7606::DmaReader> sensors{adc, e0, e1, e2};
  CHECK(adc.begin() == ad7606::Status::kOk);
  while (adc.advance() == ad7606::DmaReader::Step::kNextDevice) {
  }
  maglev::io::SensorSample s{};
  CHECK_TRUE(sensors.read(s));
  LONGS_EQUAL(100, s.displacement_adc[0]);
  LONGS_EQUAL(400, s.hall_adc[0]);           // ADC0 V4
  LONGS_EQUAL(-8000, s.coil_current_adc[7]);  // ADC1 V8
  UNSIGNED_LONGS_EQUAL(0u, s.status_flags);
  // Next tick without a new DMA read (e.g. the stream never completed):
  maglev::io::SensorSample next{};
  CHECK_FALSE(sensors.read(next));
  CHECK(next.status_flags & maglev::io::kAdcFault);
  LONGS_EQUAL(0, next.displacement_adc[0]);  // nothing copied from the old buffer
}
