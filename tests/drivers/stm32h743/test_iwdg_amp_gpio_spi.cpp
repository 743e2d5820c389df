// IWDG key sequence and feed gate; amplifier-enable default OFF and latch;
// GPIO glitch-free output setup; SPI v2 master register sequence.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/amplifier_enable.hpp"
#include "maglev/drivers/fake_bus.hpp"
#include "maglev/drivers/iwdg.hpp"
#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
using Bus = r::FakeRegisterBus<>;

TEST_GROUP(Iwdg){};

TEST(Iwdg, TimingFromTimeout) {
  constexpr iwdg::Timing a = iwdg::timing_for(50);  // 32 kHz / 4 = 8 kHz -> 400 counts
  LONGS_EQUAL(0, a.pr);
  LONGS_EQUAL(399, a.rlr);
  constexpr iwdg::Timing b = iwdg::timing_for(1000);  // /8 -> 4000 counts
  LONGS_EQUAL(1, b.pr);
  LONGS_EQUAL(3999, b.rlr);
  constexpr iwdg::Timing c = iwdg::timing_for(30000);  // /256 -> 3750
  LONGS_EQUAL(6, c.pr);
  LONGS_EQUAL(3749, c.rlr);
  CHECK_FALSE(iwdg::timing_for(40000).valid);  // > 32.768 s max
}

TEST(Iwdg, StartKeySequence) {
  Bus bus;
  iwdg::Watchdog<Bus> dog(bus);
  CHECK(dog.start(50) == iwdg::Status::kOk);
  const r::Addr b = r::iwdg::kIwdg1;
  LONGS_EQUAL(5, bus.log_size());
  UNSIGNED_LONGS_EQUAL(b + r::iwdg::kKr, bus.log(0).addr);
  UNSIGNED_LONGS_EQUAL(0xCCCCu, bus.log(0).value);
  UNSIGNED_LONGS_EQUAL(0x5555u, bus.log(1).value);
  UNSIGNED_LONGS_EQUAL(b + r::iwdg::kPr, bus.log(2).addr);
  UNSIGNED_LONGS_EQUAL(0u, bus.log(2).value);
  UNSIGNED_LONGS_EQUAL(b + r::iwdg::kRlr, bus.log(3).addr);
  UNSIGNED_LONGS_EQUAL(399u, bus.log(3).value);
  UNSIGNED_LONGS_EQUAL(0xAAAAu, bus.log(4).value);
  Bus stuck;
  stuck.preset(b + r::iwdg::kSr, 0x2u);  // RVU never clears
  iwdg::Watchdog<Bus> dog2(stuck);
  CHECK(dog2.start(50) == iwdg::Status::kTimeout);
}

TEST(Iwdg, FeedGateNeedsServoAndComms) {
  Bus bus;
  iwdg::Watchdog<Bus> dog(bus);
  iwdg::FeedGate gate;
  gate.servo_ran();
  CHECK_FALSE(gate.service(dog));
  gate.comms_ran();
  CHECK_TRUE(gate.service(dog));
  CHECK_FALSE(gate.service(dog));  // both must run again before the next feed
  gate.comms_ran();
  CHECK_FALSE(gate.service(dog));
  LONGS_EQUAL(1, bus.writes_to(r::iwdg::kIwdg1 + r::iwdg::kKr));
  LONGS_EQUAL(1, gate.feeds());
  LONGS_EQUAL(3, gate.withheld());
}

TEST_GROUP(AmplifierEnable){};

TEST(AmplifierEnable, DefaultsOffAndTripLatches) {
  FakeOutputPin<> line;
  line.write(true);  // whatever the line was before
  AmplifierEnable amp(line);
  CHECK_FALSE(line.level());  // constructor drives OFF
  CHECK_TRUE(amp.request(true));
  CHECK_TRUE(line.level());
  amp.trip();
  CHECK_FALSE(line.level());
  CHECK_FALSE(amp.request(true));  // latched
  CHECK_FALSE(line.level());
  amp.clear_fault();
  CHECK_TRUE(amp.request(true));
  CHECK_TRUE(line.level());
  LONGS_EQUAL(1, amp.trips());
}

TEST(AmplifierEnable, TheLineIsWrittenOnlyWhenItsLevelChanges) {
  // The DAC interrupt requests the enable on every tick: the line is the
  // only thing it drives, so a request that changes nothing writes nothing.
  FakeOutputPin<> line;
  AmplifierEnable amp(line);
  const std::size_t after_construction = line.writes();  // the constructor's OFF
  CHECK_TRUE(amp.request(true));
  CHECK_TRUE(amp.request(true));
  CHECK_TRUE(amp.request(true));
  LONGS_EQUAL(after_construction + 1, line.writes());
  CHECK_TRUE(line.level());
  CHECK_FALSE(amp.request(false));
  CHECK_FALSE(amp.request(false));
  LONGS_EQUAL(after_construction + 2, line.writes());
  CHECK_FALSE(line.level());
  // A trip always drives the line (even when already low), and a latched
  // request changes nothing.
  amp.trip();
  LONGS_EQUAL(after_construction + 3, line.writes());
  CHECK_FALSE(amp.request(true));
  LONGS_EQUAL(after_construction + 3, line.writes());
  CHECK_FALSE(line.level());
}

TEST(AmplifierEnable, GpioIsDrivenLowBeforeBecomingAnOutput) {
  Bus bus;
  const PinId pin{r::gpio::port('E'), 9};
  Stm32OutputPin<Bus> out(bus, pin);
  out.configure(false);
  const long bsrr = bus.index_of_write(pin.port + r::gpio::kBsrr);
  const long moder = bus.index_of_write(pin.port + r::gpio::kModer);
  UNSIGNED_LONGS_EQUAL(0x58021000u, pin.port);
  UNSIGNED_LONGS_EQUAL(1u << 25, bus.log(static_cast<std::size_t>(bsrr)).value);  // BR9
  CHECK(bsrr < moder);
  UNSIGNED_LONGS_EQUAL(1u << 18, bus.peek(pin.port + r::gpio::kModer));  // MODER9 = 01
  AmplifierEnable amp(out);
  amp.request(true);
  UNSIGNED_LONGS_EQUAL(1u << 9, bus.peek(pin.port + r::gpio::kBsrr));  // BS9
}

TEST_GROUP(Stm32Spi){};

TEST(Stm32Spi, TransferRegisterSequence) {
  Bus bus;
  FakeOutputPin<> cs0;
  FakeOutputPin<> cs1;
  const SpiDeviceSettings devs[2] = {{&cs0, 1, false, true}, {&cs1, 2, true, false}};
  Stm32SpiMaster<Bus, 2> spi(bus, r::spi::kSpi1, devs);
  spi.init();
  bus.preset(r::spi::kSpi1 + r::spi::kSr, r::spi::kSrTxp | r::spi::kSrRxp | r::spi::kSrEot);
  bus.preset(r::spi::kSpi1 + r::spi::kRxdr, 0xABCDEFu);
  bus.clear_log();
  const std::uint32_t tx[2] = {0x100001u, 0x100064u};
  std::uint32_t rx[2] = {};
  CHECK(spi.transfer(SpiTransfer{0, 24, tx, rx, 2}) == BusStatus::kOk);
  const r::Addr b = r::spi::kSpi1;
  UNSIGNED_LONGS_EQUAL(b + r::spi::kCfg1, bus.log(1).addr);
  UNSIGNED_LONGS_EQUAL((1u << 28) | 23u, bus.log(1).value);  // MBR /4, DSIZE 24 bits
  UNSIGNED_LONGS_EQUAL(0x85400000u, bus.log(2).value);       // AFCNTR|SSM|CPHA|MASTER
  UNSIGNED_LONGS_EQUAL(2u, bus.log(3).value);                // TSIZE
  UNSIGNED_LONGS_EQUAL(0x1201u, bus.log(5).value);           // SSI|CSTART|SPE
  LONGS_EQUAL(2, bus.writes_to(b + r::spi::kTxdr));
  UNSIGNED_LONGS_EQUAL(0x100064u, bus.peek(b + r::spi::kTxdr));
  UNSIGNED_LONGS_EQUAL(0xABCDEFu, rx[1]);
  // CS: high at init, low for the frame, high after.
  LONGS_EQUAL(3, cs0.writes());
  CHECK_FALSE(cs0.history(1));
  CHECK_TRUE(cs0.level());
  LONGS_EQUAL(1, cs1.writes());
  bus.preset(b + r::spi::kSr, 0u);  // TXP never comes: bounded wait
  CHECK(spi.transfer(SpiTransfer{1, 32, nullptr, nullptr, 1}) == BusStatus::kTimeout);
  CHECK_TRUE(cs1.level());  // CS released even on error
}
