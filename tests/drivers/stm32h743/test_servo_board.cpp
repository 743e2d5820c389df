// firmware/app ServoLoop (safe preset, overruns, deadline, watchdog check-in),
// the board's SensorSource/ActuatorSink over the real drivers + chip models,
// and the board's clock / MPU / cache register sequences.
#include <CppUTest/TestHarness.h>

#include <cstdint>

#include "maglev/app/recorder.hpp"
#include "maglev/app/servo_loop.hpp"
#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/board/stm32h743/clock.hpp"
#include "maglev/board/stm32h743/mpu_cache.hpp"
#include "maglev/drivers/ad5764_model.hpp"
#include "maglev/drivers/ad7606_model.hpp"
#include "maglev/drivers/fake_bus.hpp"

using namespace maglev;
namespace r = maglev::stm32h7;

namespace {

struct FakeKernel {
  int calls = 0;
  bool last_overrun = false;
  std::uint16_t last_flags = 0;
  io::ActuatorCommand step(const io::SensorSample& s, bool overrun) {
    ++calls;
    last_overrun = overrun;
    last_flags = s.status_flags;
    io::ActuatorCommand c{};
    for (int j = 0; j < io::kCoils; ++j) c.dac_code[j] = static_cast<std::int16_t>(1000 + j);
    c.amplifier_enable = true;
    return c;
  }
};
struct ScriptedSensors final : app::SensorSource {
  bool ok = true;
  bool read(io::SensorSample& s) override {
    s.interferometer_counts[0] = 42;
    return ok;
  }
};
struct CapturingSink final : app::ActuatorSink {
  io::ActuatorCommand last{};
  int writes = 0;
  void write(const io::ActuatorCommand& c) override {
    last = c;
    ++writes;
  }
};

std::uint32_t g_cycles = 0;
std::uint32_t g_cycle_step = 1000;
std::uint32_t fake_cycles() { return g_cycles += g_cycle_step; }
int g_servo_ran = 0;
void count_servo_ran() { ++g_servo_ran; }

}  // namespace

TEST_GROUP(ServoLoop) {
  FakeKernel kernel;
  ScriptedSensors sensors;
  CapturingSink sink;
  app::ServoHooks hooks{&fake_cycles, nullptr, &count_servo_ran, nullptr};
  void setup() override {
    g_cycles = 0;
    g_cycle_step = 1000;
    g_servo_ran = 0;
  }
};

TEST(ServoLoop, GoodTickWritesTheKernelCommand) {
  app::ServoLoop<FakeKernel> loop(sensors, sink, kernel, {5000, 192000, 3}, hooks);
  loop.on_tick();
  LONGS_EQUAL(1, kernel.calls);
  CHECK_FALSE(kernel.last_overrun);
  LONGS_EQUAL(1007, sink.last.dac_code[7]);
  CHECK_TRUE(sink.last.amplifier_enable);
  LONGS_EQUAL(1, g_servo_ran);
  LONGS_EQUAL(1000, loop.state().last_cycles);
}

TEST(ServoLoop, BadInputsStillRunTheKernelButOutputZeroCurrent) {
  app::ServoLoop<FakeKernel> loop(sensors, sink, kernel, {5000, 192000, 3}, hooks);
  sensors.ok = false;
  loop.on_tick();
  LONGS_EQUAL(1, kernel.calls);  // the supervisor must see the fault
  CHECK(kernel.last_flags & io::kAdcFault);
  for (int j = 0; j < io::kCoils; ++j) LONGS_EQUAL(0, sink.last.dac_code[j]);
  CHECK_FALSE(sink.last.amplifier_enable);
  LONGS_EQUAL(1, loop.state().sensor_faults);
}

TEST(ServoLoop, OverBudgetTickFlagsTheNextStep) {
  app::ServoLoop<FakeKernel> loop(sensors, sink, kernel, {500, 192000, 3}, hooks);  // budget < 1000 used
  loop.on_tick();
  LONGS_EQUAL(1, loop.state().overruns);
  CHECK_FALSE(kernel.last_overrun);
  g_cycle_step = 100;
  loop.on_tick();
  CHECK_TRUE(kernel.last_overrun);  // told about the previous tick's overrun
  LONGS_EQUAL(1, loop.state().overruns);
  loop.on_tick();
  CHECK_FALSE(kernel.last_overrun);
}

TEST(ServoLoop, PendingNextTickCountsAsOverrun) {
  app::ServoHooks h = hooks;
  h.next_tick_pending = [] { return true; };
  app::ServoLoop<FakeKernel> loop(sensors, sink, kernel, {0, 192000, 3}, h);
  loop.on_tick();
  LONGS_EQUAL(1, loop.state().overruns);
}

TEST(ServoLoop, StalledTicksForceSafeOutputs) {
  app::ServoLoop<FakeKernel> loop(sensors, sink, kernel, {0, 1000, 3}, hooks);
  loop.on_tick();  // last tick started at cycle 1000
  CHECK_FALSE(loop.check_deadline(2000));  // first look: ticks seen
  CHECK_FALSE(loop.check_deadline(3500));  // 2.5 periods: not yet
  CHECK_TRUE(loop.check_deadline(4500));   // > 3 periods without a tick
  CHECK_FALSE(sink.last.amplifier_enable);
  LONGS_EQUAL(0, sink.last.dac_code[0]);
  LONGS_EQUAL(1, loop.state().missed_deadlines);
  loop.on_tick();
  CHECK_FALSE(loop.check_deadline(g_cycles + 100));
}

TEST(ServoLoop, TheDeadlinePathUsesForceSafeNotAWrite) {
  // The board's sinks override force_safe() with the enable line alone
  // (amplifier_board_io.hpp): check_deadline must not call write() on them.
  struct EnableOnlySink final : app::ActuatorSink {
    int writes = 0, forced = 0;
    void write(const io::ActuatorCommand&) override { ++writes; }
    void force_safe() override { ++forced; }
  } enable_only;
  app::ServoLoop<FakeKernel> loop(sensors, enable_only, kernel, {0, 1000, 3}, hooks);
  loop.on_tick();
  LONGS_EQUAL(1, enable_only.writes);
  CHECK_FALSE(loop.check_deadline(2000));
  CHECK_TRUE(loop.check_deadline(4500));
  LONGS_EQUAL(1, enable_only.forced);
  LONGS_EQUAL(1, enable_only.writes);  // no write from the deadline path
}

TEST(ServoLoop, RecorderKeepsTheNewestEntries) {
  app::Recorder<4> rec;
  io::SensorSample s{};
  for (std::uint32_t i = 0; i < 6; ++i) {
    s.interferometer_counts[0] = i;
    rec.record(s, io::kSafeActuatorCommand);
  }
  app::RecordEntry e{};
  CHECK_FALSE(rec.read(1, e));  // overwritten
  CHECK_TRUE(rec.read(2, e));
  LONGS_EQUAL(2, e.sample.interferometer_counts[0]);
  CHECK_FALSE(rec.read(6, e));  // nothing newer
}

namespace {
struct FakeEncoder {
  std::uint32_t count = 0;
  bool lost = false;
  std::uint32_t update() { return count; }
  bool signal_lost() const { return lost; }
};
}  // namespace

TEST_GROUP(AmplifierBoardIo) {
  drivers::FakeSpiMaster<> adc_spi;
  drivers::FakeInputPin busy{false};
  drivers::ad7606::DeviceModel adc0, adc1;
  const std::uint8_t cs[2] = {0, 1};
  std::uint32_t dma_rx[2][4] = {};
  drivers::ad7606::Adc adc{adc_spi, cs, busy, dma_rx};
  FakeEncoder e0, e1, e2;
  board::stm32h743::AmplifierBoardSensors<FakeEncoder> sensors{adc, e0, e1, e2};
  drivers::FakeSpiMaster<> dac_spi;
  drivers::FakeOutputPin<> ldac, enable_pin;
  drivers::ad5764::ChainModel<2> dac_model;
  drivers::ad5764::Chain<2> dac{dac_spi, 0, ldac};
  drivers::AmplifierEnable enable{enable_pin};
  board::stm32h743::AmplifierBoardActuators actuators{dac, enable};
  void setup() override {
    adc_spi.attach(0, &adc0);
    adc_spi.attach(1, &adc1);
    dac_spi.attach(0, &dac_model);
    ldac.set_hook(&drivers::ad5764::ChainModel<2>::ldac_hook, &dac_model);
    dac.init();
  }
};

TEST(AmplifierBoardIo, SensorsFillEveryFieldAndFlags) {
  e0.count = 0xFFFFFFFEu;
  e1.count = 7;
  e2.count = 123456;
  e1.lost = true;
  adc0.set_code(0, 32767);  // displacement 0 railed: no target
  adc0.set_code(1, -200);
  adc0.set_code(3, 1111);   // Hall A.Bx
  adc1.set_code(7, -4096);  // coil 8 current monitor
  io::SensorSample s{};
  CHECK_TRUE(sensors.read(s));
  UNSIGNED_LONGS_EQUAL(0xFFFFFFFEu, s.interferometer_counts[0]);
  UNSIGNED_LONGS_EQUAL(123456u, s.interferometer_counts[2]);
  LONGS_EQUAL(-200, s.displacement_adc[1]);
  LONGS_EQUAL(1111, s.hall_adc[0]);
  LONGS_EQUAL(-4096, s.coil_current_adc[7]);
  UNSIGNED_LONGS_EQUAL(io::kBeamLoss1 | io::kDisplacementOutOfRange0, s.status_flags);
  UNSIGNED_LONGS_EQUAL(0xF000u, dma_rx[1][3] & 0xFFFFu);  // raw words landed in the DMA buffer
  busy.set(true);
  CHECK_FALSE(sensors.read(s));
  CHECK(s.status_flags & io::kAdcFault);
}

TEST(AmplifierBoardIo, ActuatorsLoadCurrentsThenEnable) {
  io::ActuatorCommand c{{100, 200, 300, 400, -100, -200, -300, -400}, true};
  actuators.write(c);
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(c.dac_code[j], dac_model.dac_register(j / 4, j % 4));
  CHECK_TRUE(enable_pin.level());
  actuators.write(io::kSafeActuatorCommand);
  CHECK_FALSE(enable_pin.level());
  LONGS_EQUAL(0, dac_model.dac_register(1, 3));
}

TEST(AmplifierBoardIo, UntrustworthyDacLinkTripsTheEnable) {
  dac_spi.attach(0, nullptr);  // SDO echo gone
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  actuators.write(c);
  CHECK_FALSE(enable_pin.level());
  CHECK_TRUE(enable.fault_latched());
}

namespace {
using ClockBus = r::FakeRegisterBus<64, 256>;
void clock_hw(void*, ClockBus& bus, r::Addr addr, std::uint32_t v) {
  if (addr == r::rcc::kBase + r::rcc::kCr) {
    std::uint32_t ready = v;
    if (v & r::rcc::kCrHseon) ready |= r::rcc::kCrHserdy;
    if (v & r::rcc::kCrPll1on) ready |= r::rcc::kCrPll1rdy;
    bus.preset(addr, ready);
  } else if (addr == r::rcc::kBase + r::rcc::kCfgr) {
    bus.preset(addr, (v & ~0x38u) | ((v & 7u) << 3));  // SWS follows SW
  } else if (addr == r::pwr::kBase + r::pwr::kD3cr) {
    bus.preset(addr, v | r::pwr::kD3crVosrdy);
  }
}
}  // namespace

TEST_GROUP(BoardClock){};

TEST(BoardClock, Pll1To480MHzAtVos0WithFlashLatencyFirst) {
  ClockBus bus;
  bus.set_write_hook(&clock_hw, nullptr);
  bus.preset(r::pwr::kBase + r::pwr::kCsr1, r::pwr::kCsr1Actvosrdy);
  bus.preset(r::pwr::kBase + r::pwr::kCr3, 0x6u);                       // reset: SCUEN | LDOEN
  bus.preset(r::rcc::kBase + r::rcc::kPllckselr, 0x02020200u);          // reset value
  bus.preset(r::rcc::kBase + r::rcc::kPllcfgr, 0x01FF0000u);            // reset value
  CHECK(board::stm32h743::configure_clock_480MHz(bus) == board::stm32h743::ClockStatus::kOk);
  UNSIGNED_LONGS_EQUAL(0x2u, bus.peek(r::pwr::kBase + r::pwr::kCr3));   // LDO only
  UNSIGNED_LONGS_EQUAL(0xC000u, bus.peek(r::pwr::kBase + r::pwr::kD3cr) & 0xC000u);  // VOS1
  UNSIGNED_LONGS_EQUAL(1u, bus.peek(r::syscfg::kBase + r::syscfg::kPwrcr));          // ODEN -> VOS0
  UNSIGNED_LONGS_EQUAL(0x02020012u, bus.peek(r::rcc::kBase + r::rcc::kPllckselr));   // HSE, DIVM1 = 1
  UNSIGNED_LONGS_EQUAL(0x01FF000Cu, bus.peek(r::rcc::kBase + r::rcc::kPllcfgr));     // RGE 8-16 MHz, wide VCO
  UNSIGNED_LONGS_EQUAL(0x010B0277u, bus.peek(r::rcc::kBase + r::rcc::kPll1divr));    // N120 P2 Q12 R2
  UNSIGNED_LONGS_EQUAL(0x48u, bus.peek(r::rcc::kBase + r::rcc::kD1cfgr));
  UNSIGNED_LONGS_EQUAL(0x440u, bus.peek(r::rcc::kBase + r::rcc::kD2cfgr));
  UNSIGNED_LONGS_EQUAL(0x40u, bus.peek(r::rcc::kBase + r::rcc::kD3cfgr));
  UNSIGNED_LONGS_EQUAL(0x24u, bus.peek(r::flash::kBase + r::flash::kAcr));
  UNSIGNED_LONGS_EQUAL(0x1Bu, bus.peek(r::rcc::kBase + r::rcc::kCfgr));  // SW = SWS = PLL1
  UNSIGNED_LONGS_EQUAL(1u << 28, bus.peek(r::rcc::kBase + r::rcc::kD2ccip1r));  // FDCAN <- pll1_q
  CHECK(bus.peek(r::rcc::kBase + r::rcc::kCr) & r::rcc::kCrHsebyp);
  // Order: ODEN after VOS1; flash latency before the SYSCLK switch; PLL configured before PLL1ON.
  CHECK(bus.index_of_write(r::pwr::kBase + r::pwr::kD3cr) < bus.index_of_write(r::syscfg::kBase + r::syscfg::kPwrcr));
  CHECK(bus.index_of_write(r::flash::kBase + r::flash::kAcr) < bus.index_of_write(r::rcc::kBase + r::rcc::kCfgr));
  CHECK(bus.index_of_write(r::rcc::kBase + r::rcc::kPll1divr) < bus.index_of_write(r::rcc::kBase + r::rcc::kCr, 1));
  LONGS_EQUAL(480000000, board::stm32h743::kCpu_Hz);
  LONGS_EQUAL(80000000, board::stm32h743::kPll1q_Hz);
}

TEST(BoardClock, HseThatNeverStartsIsReported) {
  ClockBus bus;
  bus.preset(r::pwr::kBase + r::pwr::kCsr1, r::pwr::kCsr1Actvosrdy);
  bus.preset(r::pwr::kBase + r::pwr::kD3cr, r::pwr::kD3crVosrdy);
  CHECK(board::stm32h743::configure_clock_480MHz(bus, 100) == board::stm32h743::ClockStatus::kHseTimeout);
  LONGS_EQUAL(0, bus.writes_to(r::rcc::kBase + r::rcc::kCfgr));  // never switched
}

TEST(BoardClock, MpuMakesD2SramNonCacheableAndCachesInvalidateEverySetWay) {
  r::FakeRegisterBus<32, 1024> bus;
  board::stm32h743::configure_mpu(bus);
  UNSIGNED_LONGS_EQUAL(0x38800000u, bus.peek(r::mpu::kBase + r::mpu::kRbar));  // last region written
  LONGS_EQUAL(0, bus.log(static_cast<std::size_t>(bus.index_of_write(r::mpu::kBase + r::mpu::kRbar))).value - 0x30000000u);
  UNSIGNED_LONGS_EQUAL(0x130C0025u, bus.log(static_cast<std::size_t>(bus.index_of_write(r::mpu::kBase + r::mpu::kRasr))).value);
  UNSIGNED_LONGS_EQUAL(5u, bus.peek(r::mpu::kBase + r::mpu::kCtrl));  // PRIVDEFENA | ENABLE
  r::FakeRegisterBus<32, 1024> cache;
  cache.preset(r::scb::kBase + r::scb::kCcsidr, (127u << 13) | (3u << 3) | 1u);  // 16 KB, 4-way, 32 B lines
  board::stm32h743::enable_caches(cache);
  LONGS_EQUAL(512, cache.writes_to(r::scb::kDcisw));
  UNSIGNED_LONGS_EQUAL((127u << 5) | (3u << 30), cache.peek(r::scb::kDcisw));
  UNSIGNED_LONGS_EQUAL(r::scb::kCcrIc | r::scb::kCcrDc, cache.peek(r::scb::kBase + r::scb::kCcr));
  CHECK(cache.index_of_write(r::scb::kIciallu) < cache.index_of_write(r::scb::kBase + r::scb::kCcr));
}
