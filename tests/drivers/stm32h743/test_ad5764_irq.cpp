// The AD5764 chain written from SPI1's end-of-transfer interrupt by the
// register-level ad5764::Stm32IrqWriter, and the board's
// AmplifierBoardIrqActuators over it (enable only after the fourth frame's
// LDAC; trips on a bad link, a failed frame or a write that never finished).
//
// SPI1 and the SYNC / LDAC port are answered by a small register-level model
// on the FakeRegisterBus's hooks: TXDR words are clocked through the
// bit-level chain model (ad5764::ChainModel) once CSTART has started the
// transaction, what the chain shifts out is queued for RXDR, and BSRR writes
// move SYNC (its rising edge latches the frame) and LDAC (its falling edge
// updates the outputs). The boot is the board's: the polled ad5764::Chain
// over Stm32SpiMaster zeroes the outputs on the same registers, then the
// writer's init() takes SPI1 over.
#include <CppUTest/TestHarness.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad5764_model.hpp"
#include "maglev/drivers/ad5764_stm32_irq.hpp"
#include "maglev/drivers/amplifier_enable.hpp"
#include "maglev/drivers/fake_bus.hpp"
#include "maglev/drivers/stm32h7_gpio.hpp"
#include "maglev/drivers/stm32h7_spi.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#include "maglev/stm32h7/registers.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace s = maglev::stm32h7::spi;
namespace io = maglev::io;
using Bus = r::FakeRegisterBus<>;

namespace {

// The board's wiring (pinmap.hpp): SPI1, SYNC PD14, LDAC PD15, SCLK kernel / 4, mode 1.
constexpr ad5764::Stm32ChainWiring kWiring{r::spi::kSpi1, r::gpio::port('D'), 14, r::gpio::port('D'), 15, 1, false, true};
using Writer = ad5764::Stm32IrqWriter<Bus, kWiring>;
using Step = ad5764::IrqStep;
using Actuators = maglev::board::stm32h743::AmplifierBoardIrqActuators<Writer>;

constexpr r::Addr kSpi = kWiring.spi;
constexpr r::Addr kSyncBsrr = kWiring.sync_port + r::gpio::kBsrr;  // SYNC and LDAC share port D's BSRR here
constexpr r::Addr kLdacBsrr = kWiring.ldac_port + r::gpio::kBsrr;
constexpr std::uint32_t kSyncHigh = 1u << kWiring.sync_pin;
constexpr std::uint32_t kSyncLow = 1u << (kWiring.sync_pin + 16u);
constexpr std::uint32_t kLdacHigh = 1u << kWiring.ldac_pin;
constexpr std::uint32_t kLdacLow = 1u << (kWiring.ldac_pin + 16u);
constexpr std::uint32_t kCr1Idle = s::kCr1Ssi;
constexpr std::uint32_t kCr1Enabled = s::kCr1Ssi | s::kCr1Spe;
constexpr std::uint32_t kCr1Start = s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart;

// CFG1: MBR /4 (code 1), DSIZE 24 bits. CFG2: AFCNTR | SSM | CPHA | MASTER.
static_assert(Writer::kCfg1 == ((1u << 28) | 23u));
static_assert(Writer::kCfg2 == 0x85400000u);

// SPI1 (RM0433 §50) and the SYNC / LDAC lines as the chain sees them.
// SPI: CSTART (with SPE = 1) starts a transaction of TSIZE (CR2) frames of
// CFG1.DSIZE + 1 bits; the TxFIFO's words (written while SPE = 1, before or
// after CSTART) go out while `wire_done`, what MISO returns goes into the
// RxFIFO, EOT after the TSIZE-th frame (cleared by IFCR.EOTC). SPE = 0
// flushes both FIFOs and cuts a transaction still on the wire half-way
// through a word (the chips see a malformed frame). Anything the hardware
// would ignore, or that breaks the chain's framing, counts in `violations`.
// GPIO: BSRR set / reset bits move SYNC and LDAC (edges only): SYNC rising ->
// the chain latches its frame; LDAC falling -> the outputs update.
struct Spi1AndPinsModel {
  ad5764::ChainModel<2>* chain = nullptr;
  bool miso_connected = true;  // false: the SDO echo is gone (MISO reads 0)
  bool wire_done = true;       // false: the started transaction stays on the wire (no EOT)
  bool overrun_next = false;   // the next transaction to finish ends with OVR

  // SPI1 state.
  bool spe = false;
  bool running = false;  // CSTART seen, not every frame clocked yet
  std::uint32_t cfg1 = 0, cfg2 = 0, cr2 = 0, ier = 0;
  std::uint32_t tsize = 0, sent = 0;
  std::uint32_t txf[4]{};  // SPI1's 16-byte FIFOs: four 17..32-bit frames
  std::size_t tx_count = 0;
  std::uint32_t rxf[4]{};
  std::size_t rx_count = 0;
  bool eot = false, ovr = false;
  int violations = 0;
  int cut_transactions = 0;
  int empty_rx_reads = 0;

  // GPIO state (idle high: the boot configures both pins high).
  bool sync_high = true;
  bool ldac_high = true;
  int sync_rises = 0;
  int frames_at_ldac = -1;   // chain frames latched when LDAC last fell
  int gpio_config_writes = 0;  // MODER / OTYPER / OSPEEDR ... of the port
  int other_pin_writes = 0;    // BSRR bits of pins that are neither SYNC nor LDAC

  // SPI1's interrupt line: EOTIE and EOT.
  bool irq_pending() const { return (ier & s::kIerEotie) != 0u && eot; }

  static std::uint32_t mask(std::uint32_t bits) { return bits >= 32u ? 0xFFFFFFFFu : (1u << bits) - 1u; }

  void clock() {
    while (running && wire_done && tx_count > 0) {
      const std::uint32_t word = txf[0];
      for (std::size_t i = 1; i < tx_count; ++i) txf[i - 1] = txf[i];
      --tx_count;
      const std::uint32_t bits = (cfg1 & 0x1Fu) + 1u;
      const std::uint32_t out = chain->clock_word(word & mask(bits), static_cast<std::uint8_t>(bits));
      if (rx_count < 4) {
        rxf[rx_count++] = miso_connected ? out : 0u;
      } else {
        ovr = true;
      }
      if (++sent == tsize) {
        running = false;
        eot = true;
        if (overrun_next) {
          ovr = true;
          overrun_next = false;
        }
      }
    }
  }
  // The transaction stops where it is: half of the word on the wire clocked.
  void cut() {
    if (!running) return;
    if (tx_count > 0) (void)chain->clock_word((txf[0] >> 12) & 0xFFFu, 12);
    ++cut_transactions;
    running = false;
  }

  void spi_write(r::Addr off, std::uint32_t v) {
    if (off == s::kCr1) {
      const bool spe_new = (v & s::kCr1Spe) != 0u;
      if (spe && !spe_new) {
        cut();
        tx_count = 0;
        rx_count = 0;
      }
      spe = spe_new;
      if ((v & s::kCr1Cstart) != 0u) {
        // A transaction outside a SYNC frame, over one still running, with
        // a stale EOT (its interrupt would come at once) or in another mode.
        if (!spe || running || sync_high || eot ||
            (cfg2 & (s::kCfg2Master | s::kCfg2Cpol | s::kCfg2Cpha)) != (s::kCfg2Master | s::kCfg2Cpha)) {
          ++violations;
        }
        if (spe && !running) {
          running = true;
          tsize = cr2 & 0xFFFFu;
          sent = 0;
          clock();
        }
      }
    } else if (off == s::kCr2 || off == s::kCfg1 || off == s::kCfg2) {
      if (spe) ++violations;  // writable only while SPE = 0
      (off == s::kCr2 ? cr2 : off == s::kCfg1 ? cfg1 : cfg2) = v;
    } else if (off == s::kIer) {
      ier = v;
    } else if (off == s::kIfcr) {
      if ((v & s::kIfcrEotc) != 0u) eot = false;
      if ((v & s::kIfcrOvrc) != 0u) ovr = false;
    } else if (off == s::kTxdr) {
      if (!spe || tx_count == 4) {
        ++violations;  // lost: SPI disabled, or the TxFIFO full
      } else {
        txf[tx_count++] = v;
        clock();
      }
    }
  }

  void set_sync(bool high) {
    if (high == sync_high) return;
    sync_high = high;
    if (!high) return;
    if (running) {  // SYNC raised before SPE = 0 ended the transaction
      ++violations;
      cut();
    }
    ++sync_rises;
    chain->chip_select_released();
  }
  void set_ldac(bool high) {
    if (high == ldac_high) return;
    ldac_high = high;
    if (!high) frames_at_ldac = chain->frames();
    ad5764::ChainModel<2>::ldac_hook(chain, high);
  }
  void bsrr_write(r::Addr port, std::uint32_t v) {
    std::uint32_t known = 0;
    if (port == kWiring.sync_port) {
      const std::uint32_t set = 1u << kWiring.sync_pin, reset = set << 16;
      known |= set | reset;
      if ((v & set) != 0u) {
        set_sync(true);
      } else if ((v & reset) != 0u) {
        set_sync(false);
      }
    }
    if (port == kWiring.ldac_port) {
      const std::uint32_t set = 1u << kWiring.ldac_pin, reset = set << 16;
      known |= set | reset;
      if ((v & set) != 0u) {
        set_ldac(true);
      } else if ((v & reset) != 0u) {
        set_ldac(false);
      }
    }
    if ((v & ~known) != 0u) ++other_pin_writes;
  }

  static void on_write(void* self, Bus&, r::Addr a, std::uint32_t v) {
    auto& m = *static_cast<Spi1AndPinsModel*>(self);
    if (a >= kSpi && a < kSpi + 0x400u) {
      m.spi_write(a - kSpi, v);
      return;
    }
    for (const r::Addr port : {kWiring.sync_port, kWiring.ldac_port}) {
      if (a >= port && a < port + 0x400u) {
        if (a == port + r::gpio::kBsrr) {
          m.bsrr_write(port, v);
        } else {
          ++m.gpio_config_writes;
        }
        return;  // one port: SYNC and LDAC may share it
      }
    }
  }
  static std::uint32_t on_read(void* self, Bus&, r::Addr a, std::uint32_t stored) {
    auto& m = *static_cast<Spi1AndPinsModel*>(self);
    if (a == kSpi + s::kSr) {
      m.clock();
      return (m.spe && m.tx_count < 4 ? s::kSrTxp : 0u) | (m.rx_count > 0 ? s::kSrRxp : 0u) |
             (m.eot ? s::kSrEot : 0u) | (m.ovr ? s::kSrOvr : 0u);
    }
    if (a == kSpi + s::kRxdr) {
      m.clock();
      if (m.rx_count == 0) {
        ++m.empty_rx_reads;
        return 0u;
      }
      const std::uint32_t word = m.rxf[0];
      for (std::size_t i = 1; i < m.rx_count; ++i) m.rxf[i - 1] = m.rxf[i];
      --m.rx_count;
      return word;
    }
    return stored;
  }
};

// The two words of SYNC frame `channel`: the last device's first.
constexpr std::uint32_t word(std::size_t channel, const std::int16_t (&codes)[8], std::size_t device) {
  return ad5764::data_word(static_cast<std::uint8_t>(channel), codes[device * 4 + channel]);
}

// The bus log from `from` on is exactly `expected`.
template <std::size_t N>
void check_log(const Bus& bus, std::size_t from, const Bus::Write (&expected)[N]) {
  LONGS_EQUAL(static_cast<long>(from + N), static_cast<long>(bus.log_size()));
  for (std::size_t i = 0; i < N && from + i < bus.log_size(); ++i) {
    UNSIGNED_LONGS_EQUAL(expected[i].addr, bus.log(from + i).addr);
    UNSIGNED_LONGS_EQUAL(expected[i].value, bus.log(from + i).value);
  }
}

}  // namespace

TEST_GROUP(Ad5764Irq) {
  Bus bus;
  ad5764::ChainModel<2> model;
  Spi1AndPinsModel spi1;
  // The boot path as the board wires it: SYNC / LDAC as GPIO outputs, the
  // polled chain through Stm32SpiMaster on the same SPI1.
  Stm32OutputPin<Bus> sync_pin{bus, {kWiring.sync_port, kWiring.sync_pin}};
  Stm32OutputPin<Bus> ldac_pin{bus, {kWiring.ldac_port, kWiring.ldac_pin}};
  const SpiDeviceSettings devs[1] = {{&sync_pin, kWiring.clock_divider_log2, kWiring.cpol, kWiring.cpha}};
  Stm32SpiMaster<Bus, 1> spi{bus, kSpi, devs};
  ad5764::Chain<2> boot_chain{spi, 0, ldac_pin};
  Writer writer{bus};
  FakeOutputPin<> enable_pin;
  AmplifierEnable enable{enable_pin};
  Actuators actuators{writer, enable};
  int boot_gpio_config_writes = 0;

  void setup() override {
    spi1.chain = &model;
    bus.set_write_hook(&Spi1AndPinsModel::on_write, &spi1);
    bus.set_read_hook(&Spi1AndPinsModel::on_read, &spi1);
    sync_pin.configure(true);
    ldac_pin.configure(true);
    spi.init();
    boot_chain.init();
    CHECK(boot_chain.write_zero() == ad5764::Status::kOk);
    writer.init();
    boot_gpio_config_writes = spi1.gpio_config_writes;
  }
  // Every test: nothing the hardware would have ignored or mis-framed, no
  // RXDR read of an empty FIFO, no other pin of the port touched, the
  // writer never reconfigures the pins, and the fake kept everything.
  void teardown() override {
    LONGS_EQUAL(0, spi1.violations);
    LONGS_EQUAL(0, spi1.empty_rx_reads);
    LONGS_EQUAL(0, spi1.other_pin_writes);
    LONGS_EQUAL(boot_gpio_config_writes, spi1.gpio_config_writes);
    CHECK_FALSE(bus.log_overflow());
    CHECK_FALSE(bus.capacity_exceeded());
  }
  // SPI1's interrupt while its line is pending, until the write finished:
  // the number of interrupts, or -1 when the line stayed quiet before that.
  int run_interrupts(int limit = 8) {
    for (int n = 1; n <= limit; ++n) {
      if (!spi1.irq_pending()) return -1;
      if (actuators.on_dac_irq()) return n;
    }
    return -1;
  }
  void check_outputs(const std::int16_t (&codes)[8]) {
    for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(codes[j], model.dac_register(j / 4, j % 4));
  }
};

TEST(Ad5764Irq, BootWritesThroughThePolledChainThenInitConfiguresSpi1Once) {
  // The boot write: four polled frames and one LDAC pulse, outputs at 0.
  LONGS_EQUAL(4, model.frames());
  LONGS_EQUAL(0, model.malformed_frames());
  LONGS_EQUAL(1, model.ldac_pulses());
  LONGS_EQUAL(1, static_cast<long>(boot_chain.state().writes));
  LONGS_EQUAL(0, static_cast<long>(boot_chain.state().bus_errors));
  // init() ends any frame, masks the interrupt and writes the chain's one
  // configuration with SPE = 0; SYNC and LDAC idle high.
  bus.clear_log();
  writer.init();
  check_log(bus, 0,
            {{kSpi + s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc},
             {kSpi + s::kCr1, kCr1Idle},
             {kSyncBsrr, kSyncHigh},
             {kSpi + s::kIer, 0u},
             {kSpi + s::kCfg1, (1u << 28) | 23u},  // MBR /4, DSIZE 24 bits
             {kSpi + s::kCfg2, 0x85400000u},       // AFCNTR | SSM | CPHA | MASTER
             {kLdacBsrr, kLdacHigh}});
  CHECK_FALSE(spi1.spe);
  CHECK_TRUE(spi1.sync_high);
  CHECK_TRUE(spi1.ldac_high);
  LONGS_EQUAL(4, model.frames());  // no SYNC edge: it was high
  CHECK_FALSE(writer.writing());
}

TEST(Ad5764Irq, FourInterruptsLoadEveryCoilAndLdacComesAfterTheLast) {
  const std::int16_t codes[8] = {100, -1, 32767, -32768, 1, 2, 3, -3000};
  const int frames_before = model.frames();
  const int ldac_before = model.ldac_pulses();
  CHECK(writer.begin(codes) == ad5764::Status::kOk);
  CHECK_TRUE(writer.writing());
  for (int frame = 0; frame < 3; ++frame) {
    CHECK_TRUE(spi1.irq_pending());
    CHECK(writer.advance() == Step::kNextFrame);
    LONGS_EQUAL(ldac_before, model.ldac_pulses());  // outputs unchanged until the last frame
    LONGS_EQUAL(frames_before + frame + 1, model.frames());
  }
  CHECK_TRUE(spi1.irq_pending());
  CHECK(writer.advance() == Step::kComplete);
  CHECK_FALSE(spi1.irq_pending());  // EOTIE off, EOT cleared: no fifth interrupt
  CHECK(writer.result() == ad5764::Status::kOk);
  CHECK_FALSE(writer.writing());
  CHECK(writer.advance() == Step::kIdle);
  LONGS_EQUAL(ldac_before + 1, model.ldac_pulses());
  // LDAC fell after the fourth frame's SYNC rising edge had latched it.
  LONGS_EQUAL(frames_before + 4, spi1.frames_at_ldac);
  LONGS_EQUAL(frames_before + 4, model.frames());
  LONGS_EQUAL(0, model.malformed_frames());
  LONGS_EQUAL(0, model.non_data_writes());
  check_outputs(codes);
  // A second write: its first frame's echo is the first write's last frame.
  const std::int16_t next[8] = {7, 6, 5, 4, 3, 2, 1, 0};
  CHECK(writer.begin(next) == ad5764::Status::kOk);
  for (int frame = 0; frame < 3; ++frame) CHECK(writer.advance() == Step::kNextFrame);
  CHECK(writer.advance() == Step::kComplete);
  CHECK(writer.result() == ad5764::Status::kOk);
  check_outputs(next);
  LONGS_EQUAL(0, static_cast<long>(writer.state().link_mismatches));
  LONGS_EQUAL(2, static_cast<long>(writer.state().writes));
  LONGS_EQUAL(0, static_cast<long>(writer.state().bus_errors));
}

TEST(Ad5764Irq, RegisterTrafficPerWriteLeavesTheConfigurationToInit) {
  // Per write: per frame TSIZE, SPE, SYNC low, two TXDR words, CSTART, and
  // at its end IFCR, SPE = 0, SYNC high; EOTIE set by begin() and cleared by
  // the last frame only; CFG1 / CFG2 never (init() wrote them); one SR and
  // two RXDR reads per frame (no TXP / RXP polls).
  const std::int16_t first[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  CHECK(writer.begin(first) == ad5764::Status::kOk);
  LONGS_EQUAL(4, run_interrupts());
  const std::int16_t codes[8] = {-5, 6000, -7, 8, 32767, -32768, 0, 12};
  bus.clear_log();
  const std::uint32_t reads_before = bus.reads();
  const int frames_before = model.frames();
  CHECK(writer.begin(codes) == ad5764::Status::kOk);
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kOk);
  LONGS_EQUAL(4, model.frames() - frames_before);
  LONGS_EQUAL(0, model.malformed_frames());
  check_outputs(codes);
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kCfg2));
  LONGS_EQUAL(4, bus.writes_to(kSpi + s::kCr2));
  LONGS_EQUAL(8, bus.writes_to(kSpi + s::kTxdr));
  LONGS_EQUAL(2, bus.writes_to(kSpi + s::kIer));
  LONGS_EQUAL(12, bus.writes_to(kSpi + s::kCr1));   // 4 x (SPE, CSTART, SPE = 0)
  LONGS_EQUAL(4, bus.writes_to(kSpi + s::kIfcr));
  LONGS_EQUAL(10, bus.writes_to(kSyncBsrr));        // 4 x SYNC low / high, LDAC low / high
  LONGS_EQUAL(40, static_cast<long>(bus.log_size()));  // nothing else
  UNSIGNED_LONGS_EQUAL(12u, bus.reads() - reads_before);
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + s::kIer));
  UNSIGNED_LONGS_EQUAL(kCr1Idle, bus.peek(kSpi + s::kCr1));  // SPE = 0 at the end
  CHECK_TRUE(spi1.sync_high);
  CHECK_TRUE(spi1.ldac_high);
  LONGS_EQUAL(0, static_cast<long>(writer.state().link_mismatches));
}

TEST(Ad5764Irq, FrameOrderAndBusyUntilEot) {
  const std::int16_t codes[8] = {10, 11, 12, 13, -20, -21, -22, -23};
  CHECK_FALSE(spi1.spe);  // SPE = 0 (init() / the last frame's end): TSIZE writable
  bus.clear_log();
  spi1.wire_done = false;
  CHECK(writer.begin(codes) == ad5764::Status::kOk);
  // TSIZE, SPE, SYNC low, both words in the TxFIFO, EOTIE, then CSTART.
  check_log(bus, 0,
            {{kSpi + s::kCr2, 2u},
             {kSpi + s::kCr1, kCr1Enabled},
             {kSyncBsrr, kSyncLow},
             {kSpi + s::kTxdr, word(0, codes, 1)},  // the last device's word first
             {kSpi + s::kTxdr, word(0, codes, 0)},
             {kSpi + s::kIer, s::kIerEotie},
             {kSpi + s::kCr1, kCr1Start}});
  CHECK_FALSE(spi1.sync_high);
  CHECK_TRUE(spi1.running);
  // The wire still running: no EOT, so kBusy, nothing written, SYNC low.
  CHECK_FALSE(spi1.irq_pending());
  CHECK(writer.advance() == Step::kBusy);
  CHECK(writer.advance() == Step::kBusy);
  LONGS_EQUAL(7, static_cast<long>(bus.log_size()));
  CHECK_FALSE(spi1.sync_high);
  CHECK_TRUE(writer.writing());
  // EOT: the frame ends (IFCR, SPE = 0, SYNC high: the chips latch it) and
  // frame 1 is loaded and started in the same interrupt.
  spi1.wire_done = true;
  const int frames_before = model.frames();
  CHECK(writer.advance() == Step::kNextFrame);
  LONGS_EQUAL(frames_before + 1, model.frames());
  check_log(bus, 7,
            {{kSpi + s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc},
             {kSpi + s::kCr1, kCr1Idle},
             {kSyncBsrr, kSyncHigh},
             {kSpi + s::kCr2, 2u},
             {kSpi + s::kCr1, kCr1Enabled},
             {kSyncBsrr, kSyncLow},
             {kSpi + s::kTxdr, word(1, codes, 1)},
             {kSpi + s::kTxdr, word(1, codes, 0)},
             {kSpi + s::kCr1, kCr1Start}});
  LONGS_EQUAL(1, bus.writes_to(kSpi + s::kIer));  // EOTIE kept between the frames
  CHECK(writer.advance() == Step::kNextFrame);
  CHECK(writer.advance() == Step::kNextFrame);
  // The last frame: IER = 0 before the frame ends, LDAC pulsed after SYNC rose.
  const std::size_t last = bus.log_size();
  CHECK(writer.advance() == Step::kComplete);
  check_log(bus, last,
            {{kSpi + s::kIer, 0u},
             {kSpi + s::kIfcr, s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc},
             {kSpi + s::kCr1, kCr1Idle},
             {kSyncBsrr, kSyncHigh},
             {kLdacBsrr, kLdacLow},
             {kLdacBsrr, kLdacHigh}});
  check_outputs(codes);
}

TEST(Ad5764Irq, ActuatorsEnableOnlyAfterTheFourthFrameAndDisableAtOnce) {
  io::ActuatorCommand c{{100, 200, 300, 400, -100, -200, -300, -400}, true};
  actuators.write(c);
  CHECK_FALSE(enable_pin.level());  // nothing on the outputs yet: not enabled
  for (int frame = 0; frame < 3; ++frame) {
    CHECK_FALSE(actuators.on_dac_irq());
    CHECK_FALSE(enable_pin.level());
  }
  CHECK_TRUE(actuators.on_dac_irq());
  CHECK_TRUE(enable_pin.level());
  CHECK_TRUE(enable.enabled());
  check_outputs(c.dac_code);
  actuators.write(io::kSafeActuatorCommand);
  CHECK_FALSE(enable_pin.level());  // off before the first zero frame is on the wire
  LONGS_EQUAL(100, model.dac_register(0, 0));
  LONGS_EQUAL(4, run_interrupts());
  CHECK_FALSE(enable_pin.level());
  LONGS_EQUAL(0, model.dac_register(0, 0));
  LONGS_EQUAL(0, model.dac_register(1, 3));
  CHECK_FALSE(enable.fault_latched());
  LONGS_EQUAL(0, static_cast<long>(enable.trips()));
}

TEST(Ad5764Irq, AnUntrustworthyLinkTripsTheEnable) {
  spi1.miso_connected = false;  // SDO echo gone (MISO reads 0)
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kLinkMismatch);
  // Frames 1-3 each echo nothing (frame 0 has no echo to compare after init()).
  LONGS_EQUAL(3, static_cast<long>(writer.state().link_mismatches));
  CHECK_FALSE(enable_pin.level());
  CHECK_TRUE(enable.fault_latched());
  LONGS_EQUAL(1, static_cast<long>(enable.trips()));
}

TEST(Ad5764Irq, TheFirstFrameIsCheckedAgainstThePreviousWritesLastFrame) {
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK_TRUE(enable_pin.level());
  // The next write's frame 0 only: its echo (the last write's frame 3) lost.
  spi1.miso_connected = false;
  actuators.write(c);  // frame 0 is clocked at CSTART
  spi1.miso_connected = true;
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kLinkMismatch);
  LONGS_EQUAL(1, static_cast<long>(writer.state().link_mismatches));
  CHECK_TRUE(enable.fault_latched());
  CHECK_FALSE(enable_pin.level());
}

TEST(Ad5764Irq, AWriteThatNeverFinishedIsAbandonedAndTrips) {
  io::ActuatorCommand c{{1, 2, 3, 4, 5, 6, 7, 8}, true};
  const int ldac_before = model.ldac_pulses();
  spi1.wire_done = false;  // the frame's EOT never comes
  actuators.write(c);
  CHECK_FALSE(spi1.irq_pending());
  CHECK_FALSE(actuators.on_dac_irq());  // a spurious interrupt: still busy
  CHECK_FALSE(spi1.sync_high);
  actuators.write(c);  // the next tick
  CHECK_TRUE(enable.fault_latched());
  CHECK_FALSE(enable_pin.level());
  // The abandoned frame: SPE = 0 cut it mid-word, SYNC released, the chips
  // ignored the short frame, no LDAC, the interrupt masked.
  LONGS_EQUAL(1, spi1.cut_transactions);
  CHECK_TRUE(spi1.sync_high);
  LONGS_EQUAL(1, model.malformed_frames());
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(0, model.input_register(j / 4, j % 4));
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + s::kIer));
  UNSIGNED_LONGS_EQUAL(kCr1Idle, bus.peek(kSpi + s::kCr1));
  UNSIGNED_LONGS_EQUAL(1u, writer.state().bus_errors);
  CHECK_FALSE(writer.writing());
  // The tick after that starts a fresh write (the trip stays latched).
  spi1.wire_done = true;
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kOk);
  check_outputs(c.dac_code);
  CHECK_FALSE(enable_pin.level());
  LONGS_EQUAL(1, static_cast<long>(enable.trips()));
  LONGS_EQUAL(1, model.malformed_frames());
}

TEST(Ad5764Irq, AFailedFrameNeverPulsesLdac) {
  io::ActuatorCommand c{{9, 9, 9, 9, 9, 9, 9, 9}, true};
  const int ldac_before = model.ldac_pulses();
  actuators.write(c);
  spi1.overrun_next = true;             // frame 1 will end with OVR
  CHECK_FALSE(actuators.on_dac_irq());  // frame 0 done, frame 1 started
  CHECK_TRUE(spi1.ovr);
  CHECK_TRUE(actuators.on_dac_irq());  // frame 1 failed: the write ends
  CHECK(writer.result() == ad5764::Status::kBusError);
  UNSIGNED_LONGS_EQUAL(1u, writer.state().bus_errors);
  CHECK_FALSE(writer.writing());
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
  CHECK_TRUE(enable.fault_latched());
  CHECK_FALSE(enable_pin.level());
  // Frames 0 and 1 reached the input registers, never the outputs; frame 2
  // never went out.
  LONGS_EQUAL(9, model.input_register(0, 1));
  LONGS_EQUAL(0, model.input_register(0, 2));
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(0, model.dac_register(j / 4, j % 4));
  // The failed frame ended cleanly: EOTIE off, OVR cleared, SPE = 0, SYNC released.
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + s::kIer));
  CHECK_FALSE(spi1.ovr);
  CHECK_FALSE(spi1.irq_pending());
  UNSIGNED_LONGS_EQUAL(kCr1Idle, bus.peek(kSpi + s::kCr1));
  CHECK_TRUE(spi1.sync_high);
  CHECK(writer.advance() == Step::kIdle);
}

TEST(Ad5764Irq, AStrayInterruptEndsTheTransactionInsteadOfReentering) {
  // A frame on the wire that no write owns (its begin() was abandoned by a
  // higher-priority one), EOT pending with EOTIE set: the interrupt ends it,
  // EOTIE off, EOT cleared, SYNC released.
  const int ldac_before = model.ldac_pulses();
  bus.write32(kSpi + s::kCr2, 2u);
  bus.write32(kSpi + s::kCr1, kCr1Enabled);
  bus.write32(kSyncBsrr, kSyncLow);
  bus.write32(kSpi + s::kTxdr, ad5764::data_word(3, 1234));
  bus.write32(kSpi + s::kTxdr, ad5764::data_word(3, 1234));
  bus.write32(kSpi + s::kIer, s::kIerEotie);
  bus.write32(kSpi + s::kCr1, kCr1Start);
  CHECK_TRUE(spi1.irq_pending());
  CHECK(writer.advance() == Step::kIdle);
  CHECK_FALSE(spi1.irq_pending());
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + s::kIer));
  UNSIGNED_LONGS_EQUAL(kCr1Idle, bus.peek(kSpi + s::kCr1));
  CHECK_TRUE(spi1.sync_high);
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
  LONGS_EQUAL(0, model.dac_register(0, 3));
  CHECK_FALSE(writer.writing());
  UNSIGNED_LONGS_EQUAL(0u, writer.state().bus_errors);
  // Another one with nothing on the wire: no SYNC edge, nothing latched.
  const int frames_before = model.frames();
  CHECK(writer.advance() == Step::kIdle);
  LONGS_EQUAL(frames_before, model.frames());
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
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
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // no SPI1 or GPIO register touched
  LONGS_EQUAL(ldac_before, model.ldac_pulses());
  CHECK_FALSE(enable.fault_latched());
  // A write already on the wire when the deadline fires completes without
  // enabling; the next tick's command enables again after its LDAC.
  actuators.write(c);
  CHECK_FALSE(actuators.on_dac_irq());
  actuators.force_safe();
  LONGS_EQUAL(3, run_interrupts());
  CHECK(writer.result() == ad5764::Status::kOk);
  LONGS_EQUAL(ldac_before + 1, model.ldac_pulses());
  CHECK_FALSE(enable_pin.level());
  CHECK_FALSE(enable.fault_latched());
  actuators.write(c);
  LONGS_EQUAL(4, run_interrupts());
  CHECK_TRUE(enable_pin.level());
  CHECK_FALSE(enable.fault_latched());
  LONGS_EQUAL(0, static_cast<long>(enable.trips()));
}

// The wiring is the template argument: another SPI, SYNC and LDAC on two
// other ports, another divider and mode.
TEST_GROUP(Ad5764IrqWiring){};

TEST(Ad5764IrqWiring, EveryAccessGoesToTheWiredPeripheralAndPins) {
  constexpr ad5764::Stm32ChainWiring kOther{r::spi::kSpi4, r::gpio::port('A'), 4, r::gpio::port('E'), 3, 2, true, false};
  using Other = ad5764::Stm32IrqWriter<Bus, kOther>;
  static_assert(Other::kCfg1 == ((2u << 28) | 23u));  // MBR /8
  static_assert(Other::kCfg2 == (s::kCfg2Master | s::kCfg2Ssm | s::kCfg2Afcntr | s::kCfg2Cpol));  // mode 2
  const r::Addr spi4 = r::spi::kSpi4;
  const r::Addr sync_bsrr = r::gpio::port('A') + r::gpio::kBsrr;
  const r::Addr ldac_bsrr = r::gpio::port('E') + r::gpio::kBsrr;
  Bus bus;
  Other w{bus};
  w.init();
  UNSIGNED_LONGS_EQUAL(Other::kCfg1, bus.peek(spi4 + s::kCfg1));
  UNSIGNED_LONGS_EQUAL(Other::kCfg2, bus.peek(spi4 + s::kCfg2));
  UNSIGNED_LONGS_EQUAL(1u << 4, bus.peek(sync_bsrr));  // SYNC high
  UNSIGNED_LONGS_EQUAL(1u << 3, bus.peek(ldac_bsrr));  // LDAC high
  const std::int16_t codes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  CHECK(w.begin(codes) == ad5764::Status::kOk);
  UNSIGNED_LONGS_EQUAL(1u << 20, bus.peek(sync_bsrr));  // SYNC low
  UNSIGNED_LONGS_EQUAL(word(0, codes, 0), bus.peek(spi4 + s::kTxdr));
  bus.preset(spi4 + s::kSr, s::kSrEot);  // every frame done at once
  for (int frame = 0; frame < 3; ++frame) CHECK(w.advance() == Step::kNextFrame);
  CHECK(w.advance() == Step::kComplete);
  // RXDR reads 0 here: no echo.
  CHECK(w.result() == ad5764::Status::kLinkMismatch);
  UNSIGNED_LONGS_EQUAL(1u << 4, bus.peek(sync_bsrr));
  const std::size_t n = bus.log_size();
  UNSIGNED_LONGS_EQUAL(ldac_bsrr, bus.log(n - 2).addr);  // the LDAC pulse last
  UNSIGNED_LONGS_EQUAL(1u << 19, bus.log(n - 2).value);
  UNSIGNED_LONGS_EQUAL(ldac_bsrr, bus.log(n - 1).addr);
  UNSIGNED_LONGS_EQUAL(1u << 3, bus.log(n - 1).value);
  // Nothing anywhere else: SPI4, port A's BSRR and port E's BSRR only.
  for (std::size_t i = 0; i < n; ++i) {
    const r::Addr a = bus.log(i).addr;
    CHECK_TRUE((a >= spi4 && a < spi4 + 0x400u) || a == sync_bsrr || a == ldac_bsrr);
  }
  LONGS_EQUAL(8, bus.writes_to(spi4 + s::kTxdr));
}
