// The AD5764 chain written from SPI1's end-of-transfer interrupt:
// Stm32SpiMaster's FIFO start/complete mode (register sequence, RM0433
// §50.4.9 order), ad5764::IrqWriter over it against the bit-level chain
// model (the SPI1 registers answered by a small register-level model that
// clocks each TXDR word through the chain and queues what comes out), and
// the board's AmplifierBoardIrqActuators (enable only after the fourth
// frame, trips on a bad link or a write that never finished).
#include <CppUTest/TestHarness.h>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad5764_model.hpp"
#include "maglev/drivers/amplifier_enable.hpp"
#include "maglev/drivers/fake_bus.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"
#include "maglev/stm32h7/register_bus.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace io = maglev::io;
using Bus = r::FakeRegisterBus<>;

namespace {

constexpr r::Addr kSpi = r::spi::kSpi1;

// SPI1 as the chain sees it: TXDR words go out after CSTART; EOT once
// `wire_done`; RXDR hands back what the chain shifted out, oldest first.
struct Spi1Model {
  ad5764::ChainModel<2>* chain = nullptr;  // nullptr: MISO not connected (reads 0)
  std::uint32_t pending[4]{};
  std::size_t pending_count = 0;
  std::uint32_t rx[8]{};
  std::size_t rx_write = 0, rx_read = 0;
  bool wire_done = true;  // the test holds it false to see kBusy
  bool overrun = false;

  static void on_write(void* self, Bus& bus, r::Addr a, std::uint32_t v) {
    auto& m = *static_cast<Spi1Model*>(self);
    if (a == kSpi + r::spi::kTxdr && m.pending_count < 4) m.pending[m.pending_count++] = v;
    if (a == kSpi + r::spi::kCr1 && (v & r::spi::kCr1Cstart) != 0u) {
      for (std::size_t i = 0; i < m.pending_count; ++i) {
        const std::uint32_t miso = m.chain != nullptr ? m.chain->clock_word(m.pending[i] & 0xFFFFFFu, 24) : 0u;
        m.rx[m.rx_write++ % 8] = miso;
      }
      m.pending_count = 0;
    }
    (void)bus;
  }
  static std::uint32_t on_read(void* self, Bus&, r::Addr a, std::uint32_t stored) {
    auto& m = *static_cast<Spi1Model*>(self);
    if (a == kSpi + r::spi::kSr) {
      return r::spi::kSrTxp | (m.rx_read != m.rx_write ? r::spi::kSrRxp : 0u) | (m.wire_done ? r::spi::kSrEot : 0u) |
             (m.overrun ? r::spi::kSrOvr : 0u);
    }
    if (a == kSpi + r::spi::kRxdr) return m.rx_read != m.rx_write ? m.rx[m.rx_read++ % 8] : 0u;
    return stored;
  }
};

void sync_edge(void* chain, bool high) {
  if (high) static_cast<ad5764::ChainModel<2>*>(chain)->chip_select_released();
}

}  // namespace

TEST_GROUP(Ad5764Irq) {
  Bus bus;
  Spi1Model spi1;
  ad5764::ChainModel<2> model;
  FakeOutputPin<> sync, ldac, enable_pin;
  const SpiDeviceSettings devs[1] = {{&sync, 1, false, true}};
  Stm32SpiMaster<Bus, 1> spi{bus, kSpi, devs};
  ad5764::IrqWriter<2> writer{spi, 0, ldac};
  AmplifierEnable enable{enable_pin};
  maglev::board::stm32h743::AmplifierBoardIrqActuators actuators{writer, enable};

  void setup() override {
    spi1.chain = &model;
    bus.set_write_hook(&Spi1Model::on_write, &spi1);
    bus.set_read_hook(&Spi1Model::on_read, &spi1);
    sync.set_hook(&sync_edge, &model);
    ldac.set_hook(&ad5764::ChainModel<2>::ldac_hook, &model);
    spi.init();
    ldac.write(true);
    writer.init();
  }
  // The SPI1 interrupt until the write finished; the number of interrupts.
  int run_interrupts(int limit = 8) {
    for (int n = 1; n <= limit; ++n) {
      if (actuators.on_dac_irq()) return n;
    }
    return -1;
  }
};

TEST(Ad5764Irq, FifoStartLoadsTheWholeFrameBeforeCstartAndCompletesOnEot) {
  bus.clear_log();
  const std::uint32_t tx[2] = {0x100001u, 0x100064u};
  std::uint32_t rx[2] = {};
  spi1.wire_done = false;
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kOk);
  // SPE=0, CFG1 (MBR /4, DSIZE 24), CFG2, TSIZE, SPE, the two words, EOTIE, CSTART.
  const long cfg1 = bus.index_of_write(kSpi + r::spi::kCfg1);
  const long txdr0 = bus.index_of_write(kSpi + r::spi::kTxdr, 0);
  const long txdr1 = bus.index_of_write(kSpi + r::spi::kTxdr, 1);
  const long ier = bus.index_of_write(kSpi + r::spi::kIer);
  CHECK(cfg1 >= 0 && txdr0 > cfg1 && txdr1 > txdr0 && ier > txdr1);
  UNSIGNED_LONGS_EQUAL((1u << 28) | 23u, bus.log(static_cast<std::size_t>(cfg1)).value);
  UNSIGNED_LONGS_EQUAL(2u, bus.peek(kSpi + r::spi::kCr2));
  UNSIGNED_LONGS_EQUAL(r::spi::kIerEotie, bus.peek(kSpi + r::spi::kIer));
  const Bus::Write& last = bus.log(bus.log_size() - 1);
  UNSIGNED_LONGS_EQUAL(kSpi + r::spi::kCr1, last.addr);
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi | r::spi::kCr1Spe | r::spi::kCr1Cstart, last.value);
  CHECK_FALSE(sync.level());  // SYNC low for the frame
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kBusy);  // one at a time
  // Wire still running: nothing read, SYNC still low.
  CHECK(spi.complete() == BusStatus::kBusy);
  CHECK_FALSE(sync.level());
  spi1.wire_done = true;
  CHECK(spi.complete() == BusStatus::kOk);
  CHECK_TRUE(sync.level());
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + r::spi::kIer));
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi, bus.peek(kSpi + r::spi::kCr1));  // SPE = 0
  CHECK(spi.complete() == BusStatus::kNotStarted);
  // The same device and word size again: CFG1 / CFG2 are not rewritten.
  bus.clear_log();
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kOk);
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg2));
  CHECK(spi.complete() == BusStatus::kOk);
  // More than the FIFO holds: refused before anything is driven.
  const std::uint32_t three[3] = {1, 2, 3};
  CHECK(spi.start(SpiTransfer{0, 24, three, rx, 3}) == BusStatus::kBadArgument);
  CHECK_TRUE(sync.level());
}

TEST(Ad5764Irq, OverrunIsATransferErrorAndReleasesSync) {
  const std::uint32_t tx[2] = {1, 2};
  std::uint32_t rx[2] = {};
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kOk);
  spi1.overrun = true;
  CHECK(spi.complete() == BusStatus::kTransferError);
  CHECK_TRUE(sync.level());
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + r::spi::kIer));
}

TEST(Ad5764Irq, FourInterruptsLoadEveryCoilAndLdacComesAfterTheLast) {
  const std::int16_t codes[8] = {100, -1, 32767, -32768, 1, 2, 3, -3000};
  const int frames_before = model.frames();  // spi.init() released SYNC once
  CHECK(writer.begin(codes) == ad5764::Status::kOk);
  CHECK_TRUE(writer.writing());
  using Step = ad5764::IrqWriter<2>::Step;
  for (int frame = 0; frame < 3; ++frame) {
    CHECK(writer.advance() == Step::kNextFrame);
    LONGS_EQUAL(0, model.ldac_pulses());  // outputs unchanged until the last frame
  }
  CHECK(writer.advance() == Step::kComplete);
  CHECK(writer.result() == ad5764::Status::kOk);
  CHECK(writer.advance() == Step::kIdle);
  LONGS_EQUAL(1, model.ldac_pulses());
  LONGS_EQUAL(4, model.frames() - frames_before);
  LONGS_EQUAL(0, model.malformed_frames());
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(codes[j], model.dac_register(j / 4, j % 4));
  // A second write: its first frame's echo is the first write's last frame.
  const std::int16_t next[8] = {7, 6, 5, 4, 3, 2, 1, 0};
  CHECK(writer.begin(next) == ad5764::Status::kOk);
  for (int frame = 0; frame < 3; ++frame) CHECK(writer.advance() == Step::kNextFrame);
  CHECK(writer.advance() == Step::kComplete);
  CHECK(writer.result() == ad5764::Status::kOk);
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(next[j], model.dac_register(j / 4, j % 4));
  LONGS_EQUAL(0, static_cast<long>(writer.state().link_mismatches));
  LONGS_EQUAL(2, static_cast<long>(writer.state().writes));
}

TEST(Ad5764Irq, FramesOneToThreeRestartFromTheInterruptWithoutReconfiguring) {
  // complete_and_restart(): the next frame of the same shape straight from
  // the frame-end interrupt. Per write: TSIZE and CSTART once per frame,
  // EOTIE set by the first start and cleared by the last completion only,
  // CFG1 / CFG2 untouched (the same device and word size as the write before).
  const std::int16_t first[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  CHECK(writer.begin(first) == ad5764::Status::kOk);
  LONGS_EQUAL(4, run_interrupts());
  const std::int16_t codes[8] = {-5, 6000, -7, 8, 32767, -32768, 0, 12};
  bus.clear_log();
  const int frames_before = model.frames();
  CHECK(writer.begin(codes) == ad5764::Status::kOk);
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kOk);
  LONGS_EQUAL(4, model.frames() - frames_before);
  LONGS_EQUAL(0, model.malformed_frames());
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(codes[j], model.dac_register(j / 4, j % 4));
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + r::spi::kCfg2));
  LONGS_EQUAL(4, bus.writes_to(kSpi + r::spi::kCr2));
  LONGS_EQUAL(8, bus.writes_to(kSpi + r::spi::kTxdr));
  LONGS_EQUAL(2, bus.writes_to(kSpi + r::spi::kIer));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + r::spi::kIer));
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi, bus.peek(kSpi + r::spi::kCr1));  // SPE = 0 at the end
  CHECK_TRUE(sync.level());
  LONGS_EQUAL(0, static_cast<long>(writer.state().link_mismatches));
}

TEST(Ad5764Irq, ActuatorsEnableOnlyAfterTheFourthFrameAndDisableAtOnce) {
  io::ActuatorCommand c{{100, 200, 300, 400, -100, -200, -300, -400}, true};
  actuators.write(c);
  CHECK_FALSE(enable_pin.level());  // nothing on the outputs yet: not enabled
  LONGS_EQUAL(4, run_interrupts());
  CHECK_TRUE(enable_pin.level());
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(c.dac_code[j], model.dac_register(j / 4, j % 4));
  actuators.write(io::kSafeActuatorCommand);
  CHECK_FALSE(enable_pin.level());  // off before the first zero frame is on the wire
  LONGS_EQUAL(100, model.dac_register(0, 0));
  LONGS_EQUAL(4, run_interrupts());
  CHECK_FALSE(enable_pin.level());
  LONGS_EQUAL(0, model.dac_register(0, 0));
  CHECK_FALSE(enable.fault_latched());
}

TEST(Ad5764Irq, AnUntrustworthyLinkTripsTheEnable) {
  spi1.chain = nullptr;  // SDO echo gone (reads 0)
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kLinkMismatch);
  CHECK_FALSE(enable_pin.level());
  CHECK_TRUE(enable.fault_latched());
}

TEST(Ad5764Irq, AWriteThatNeverFinishedIsAbandonedAndTrips) {
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  spi1.wire_done = false;  // the frame's EOT never comes
  actuators.write(c);
  CHECK_FALSE(actuators.on_dac_irq());  // a spurious interrupt: still busy
  actuators.write(c);                   // the next tick
  CHECK_TRUE(enable.fault_latched());
  CHECK_FALSE(enable_pin.level());
  CHECK_TRUE(sync.level());  // the abandoned frame's SYNC released
  LONGS_EQUAL(0, model.ldac_pulses());
  UNSIGNED_LONGS_EQUAL(1u, writer.state().bus_errors);
  // The tick after that starts a fresh write (the trip stays latched).
  spi1.wire_done = true;
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK_FALSE(enable_pin.level());
}

TEST(Ad5764Irq, AFailedFrameNeverPulsesLdac) {
  io::ActuatorCommand c{{9, 9, 9, 9, 9, 9, 9, 9}, true};
  actuators.write(c);
  CHECK_FALSE(actuators.on_dac_irq());  // frame 0 done, frame 1 started
  spi1.overrun = true;
  CHECK_TRUE(actuators.on_dac_irq());  // frame 1 failed: the write ends
  CHECK(writer.result() == ad5764::Status::kBusError);
  LONGS_EQUAL(0, model.ldac_pulses());
  CHECK_TRUE(enable.fault_latched());
  // The failed frame ended cleanly: EOTIE off, SPE = 0, SYNC released.
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + r::spi::kIer));
  UNSIGNED_LONGS_EQUAL(r::spi::kCr1Ssi, bus.peek(kSpi + r::spi::kCr1));
  CHECK_TRUE(sync.level());
  CHECK(spi.complete() == BusStatus::kNotStarted);
}

TEST(Ad5764Irq, AStrayInterruptEndsTheTransactionInsteadOfReentering) {
  // A frame on the wire that no write owns (its begin() was abandoned by a
  // higher-priority one): the interrupt ends it, EOTIE off, SYNC released.
  const std::uint32_t tx[2] = {1, 2};
  std::uint32_t rx[2] = {};
  CHECK(spi.start(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kOk);
  CHECK(writer.advance() == ad5764::IrqWriter<2>::Step::kIdle);
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + r::spi::kIer));
  CHECK_TRUE(sync.level());
  CHECK(spi.complete() == BusStatus::kNotStarted);
  LONGS_EQUAL(0, model.ldac_pulses());
}

TEST(Ad5764Irq, TheMissedDeadlinePathOnlyDropsTheEnableAndATickResumingOverItDoesNotTrip) {
  // ServoLoop::check_deadline (SysTick, below the tick and SPI1) calls
  // force_safe(). It must start no DAC frame: the tick resuming at that
  // moment preempts it, and a half-started frame would be abandoned by the
  // tick's begin() with a latched trip.
  io::ActuatorCommand c{{10, 20, 30, 40, 50, 60, 70, 80}, true};
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK_TRUE(enable_pin.level());
  const int ldac_before = model.ldac_pulses();
  bus.clear_log();
  actuators.force_safe();  // the tick source stopped
  CHECK_FALSE(enable_pin.level());
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // no SPI1 register touched
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
  CHECK_FALSE(enable.fault_latched());
  // A write already on the wire when the deadline fires completes without
  // enabling; the next tick's command enables again after its LDAC.
  actuators.write(c);
  CHECK_FALSE(actuators.on_dac_irq());
  actuators.force_safe();
  LONGS_EQUAL(3, run_interrupts());
  CHECK_FALSE(enable_pin.level());
  CHECK_FALSE(enable.fault_latched());
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK_TRUE(enable_pin.level());
  CHECK_FALSE(enable.fault_latched());
  LONGS_EQUAL(0, static_cast<long>(enable.trips()));
}
