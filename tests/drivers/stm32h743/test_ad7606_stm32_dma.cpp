// The AD7606 pair read by the SPI3 RX DMA at the register level:
// ad7606::Stm32DmaReader with the board's wiring, on a FakeRegisterBus whose
// hooks answer
//   - SPI3 + DMA1 stream 0 + its DMAMUX channel: the shared register-level
//     model (spi_rx_dma_model.hpp), the words clocked out of
//   - the two AD7606 serial models (ad7606_model.hpp), selected by
//   - port E as a GPIO model: BSRR writes move CS0 (PE15) / CS1 (PE10), the
//     selected device drives MISO, a CS rising edge ends that device's frame;
//     IDR answers the pins' levels and BUSY (PE11).
// On top of the shared model, the SPI's RX overrun (SR.OVR, cleared by
// IFCR.OVRC) and a lost EOT are injected here: the shared model has no such
// faults.
// Checks the data and channel order, the register sequence (RM0433 §15.3.19,
// §50.4.14), the per-tick register traffic (what never changes is written
// once, by init()), and that anything but one complete pair per tick is
// sensor loss, never the previous tick's words.
#include <CppUTest/TestHarness.h>

#include <cstddef>
#include <cstdint>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/ad7606_model.hpp"
#include "maglev/drivers/ad7606_stm32_dma.hpp"
#include "maglev/drivers/spi_rx_dma_model.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#include "maglev/stm32h7/registers.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace s = maglev::stm32h7::spi;
namespace d = maglev::stm32h7::dma;
using Bus = r::FakeRegisterBus<>;

namespace {

// The board's wiring (pinmap.hpp): SPI3, CS PE15 / PE10, BUSY PE11, DMA1
// stream 0 on DMAMUX1 request spi3_rx_dma, SCLK kernel / 8, mode 2.
constexpr ad7606::Stm32AdcWiring kWiring{r::spi::kSpi3, {r::gpio::port('E'), r::gpio::port('E')}, {15, 10}, r::gpio::port('E'), 11,
                                         r::dma::kDma1, 0, r::dma::kReqSpi3Rx, 2, true, false};
using Reader = ad7606::Stm32DmaReader<Bus, kWiring>;
using Step = Reader::Step;

constexpr r::Addr kSpi = kWiring.spi;
constexpr r::Addr kPortE = r::gpio::port('E');
constexpr r::Addr kBsrr = kPortE + r::gpio::kBsrr;
constexpr r::Addr kStream = d::stream(d::kDma1, 0);
constexpr r::Addr kCr = kStream + d::kSxCr;
constexpr r::Addr kNdtr = kStream + d::kSxNdtr;
constexpr r::Addr kPar = kStream + d::kSxPar;
constexpr r::Addr kM0ar = kStream + d::kSxM0ar;
constexpr r::Addr kFcr = kStream + d::kSxFcr;
constexpr r::Addr kLisr = d::kDma1 + d::kLisr;
constexpr r::Addr kLifcr = d::kDma1 + d::kLifcr;
constexpr r::Addr kMux = d::kDmamux1;  // DMAMUX1 channel 0 = DMA1 stream 0
constexpr std::uint32_t kCs0Low = 1u << (15 + 16), kCs0High = 1u << 15;
constexpr std::uint32_t kCs1Low = 1u << (10 + 16), kCs1High = 1u << 10;
constexpr std::uint32_t kStreamFlags = 0x3Du;  // stream 0: FEIF 0, DMEIF 2, TEIF 3, HTIF 4, TCIF 5

// Independent of the reader's own constants (RM0433 §50.11.3/4, §15.5.11):
// CFG1 = MBR 2 (/8) | DSIZE 31 (32 bits) | RXDMAEN (bit 14);
// CFG2 = AFCNTR 31 | SSM 26 | CPOL 25 | MASTER 22 | COMM 2 (simplex receiver, bits 18:17);
// SxCR = PL very high (17:16) | MSIZE word (14:13) | PSIZE word (12:11) | MINC 10 |
//        DIR P->M (0) | TCIE 4 | TEIE 2 | DMEIE 1 | EN 0.
constexpr std::uint32_t kCfg1 = (2u << 28) | 31u | (1u << 14);
constexpr std::uint32_t kCfg2 = (1u << 31) | (1u << 26) | (1u << 25) | (1u << 22) | (2u << 17);
constexpr std::uint32_t kSxCrRun = 0x00035417u;
static_assert(Reader::kCfg1 == kCfg1);
static_assert(Reader::kCfg2 == kCfg2);
static_assert((Reader::kStreamCr | d::kCrEn) == kSxCrRun);

constexpr std::int16_t kCodes[2][8] = {
    {101, -202, 303, -404, 505, -606, 32767, -32768},  // ADC0 V1..V8 (V7 / V8: the code range's ends)
    {-1000, 2000, -3000, 4000, -5000, 6000, -7000, 8000},
};

// Port E, SPI3 and DMA1 stream 0 as the reader sees them.
struct Hardware final : dma::WordSource {
  dma::SpiRxDmaModel spi_dma{kSpi, d::kDma1, 0, d::kReqSpi3Rx};
  ad7606::DeviceModel adc[2];
  bool cs_high[2] = {true, true};  // the board configures both CS pins high before init()
  bool busy = false;               // BUSY (PE11): high while converting
  bool overrun_next = false;       // the next transfer that moves data ends with SPI SR.OVR
  bool ovr = false;
  bool eot_lost = false;  // SR never shows EOT
  int both_selected = 0;  // words clocked with both CS low (MISO contention)
  int unselected = 0;     // words clocked with no CS low
  int sr_reads = 0, idr_reads = 0, rxdr_reads = 0;

  std::uint32_t next_word() override {
    if (!cs_high[0] && !cs_high[1]) ++both_selected;
    if (!cs_high[0]) return adc[0].clock_word(0, 32);
    if (!cs_high[1]) return adc[1].clock_word(0, 32);
    ++unselected;
    return 0xFFFFFFFFu;  // MISO floats high
  }

  void write(r::Addr a, std::uint32_t v) {
    for (std::size_t dev = 0; dev < 2; ++dev) {
      if (a != kWiring.cs_port[dev] + r::gpio::kBsrr) continue;
      const unsigned pin = kWiring.cs_pin[dev];
      const bool was_high = cs_high[dev];
      if ((v & (1u << pin)) != 0u) {
        cs_high[dev] = true;  // BSx wins over BRx (RM0433 §11.4.7)
      } else if ((v & (1u << (pin + 16u))) != 0u) {
        cs_high[dev] = false;
      }
      if (!was_high && cs_high[dev]) adc[dev].chip_select_released();
    }
    const std::uint32_t before = spi_dma.transfers();
    spi_dma.write(a, v, *this);
    if (spi_dma.transfers() != before && overrun_next) {
      ovr = true;
      overrun_next = false;
    }
    if (a == kSpi + s::kIfcr && (v & s::kIfcrOvrc) != 0u) ovr = false;
  }

  std::uint32_t read(r::Addr a, std::uint32_t stored) {
    if (a == kWiring.busy_port + r::gpio::kIdr) {
      ++idr_reads;
      std::uint32_t idr = busy ? (1u << kWiring.busy_pin) : 0u;
      for (std::size_t dev = 0; dev < 2; ++dev) {
        if (kWiring.cs_port[dev] == kWiring.busy_port && cs_high[dev]) idr |= 1u << kWiring.cs_pin[dev];
      }
      return idr;
    }
    if (a == kSpi + s::kRxdr) ++rxdr_reads;
    std::uint32_t v = 0;
    if (!spi_dma.read(a, &v)) return stored;
    if (a == kSpi + s::kSr) {
      ++sr_reads;
      if (ovr) v |= s::kSrOvr;
      if (eot_lost) v &= ~s::kSrEot;
    }
    return v;
  }
};

void on_write(void* hw, Bus&, r::Addr a, std::uint32_t v) { static_cast<Hardware*>(hw)->write(a, v); }
std::uint32_t on_read(void* hw, Bus&, r::Addr a, std::uint32_t stored) { return static_cast<Hardware*>(hw)->read(a, stored); }

std::uint32_t addr_of(const std::uint32_t* p) { return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(p)); }

struct FixedEncoder {
  std::uint32_t count = 0;
  std::uint32_t update() { return count; }
  bool signal_lost() const { return false; }
};

}  // namespace

TEST_GROUP(Ad7606Stm32Dma) {
  Bus bus;
  Hardware hw;
  std::uint32_t buffer[2][4]{};
  Reader adc{bus, buffer};

  void setup() override {
    bus.set_write_hook(&on_write, &hw);
    bus.set_read_hook(&on_read, &hw);
    hw.spi_dma.map_memory(&buffer[0][0], 8);
    for (std::size_t ch = 0; ch < 8; ++ch) {
      hw.adc[0].set_code(ch, kCodes[0][ch]);
      hw.adc[1].set_code(ch, kCodes[1][ch]);
    }
    adc.init();  // the log holds init()'s writes only
  }
  void check_codes(const ad7606::Codes& codes) {
    for (std::size_t dev = 0; dev < 2; ++dev) {
      for (std::size_t ch = 0; ch < 8; ++ch) LONGS_EQUAL(kCodes[dev][ch], codes.channel[dev][ch]);
    }
  }
  // A full pair: begin, ADC0 done -> ADC1 started, ADC1 done, the tick.
  void good_tick(ad7606::Codes& codes) {
    CHECK(adc.begin() == ad7606::Status::kOk);
    CHECK(adc.advance() == Step::kNextDevice);
    CHECK(adc.advance() == Step::kComplete);
    CHECK(adc.read(codes) == ad7606::Status::kOk);
    check_codes(codes);
  }
  static void fill(ad7606::Codes& codes, std::int16_t v) {
    for (auto& dev : codes.channel) {
      for (auto& c : dev) c = v;
    }
  }
  static void check_untouched(const ad7606::Codes& codes, std::int16_t v) {
    for (const auto& dev : codes.channel) {
      for (const auto c : dev) LONGS_EQUAL(v, c);
    }
  }
};

TEST(Ad7606Stm32Dma, InitWritesTheSpiTheRouteAndTheStreamOnce) {
  LONGS_EQUAL(1, bus.writes_to(kSpi + s::kCfg1));
  LONGS_EQUAL(1, bus.writes_to(kSpi + s::kCfg2));
  UNSIGNED_LONGS_EQUAL(kCfg1, bus.peek(kSpi + s::kCfg1));  // MBR 2, DSIZE 32 bits, RXDMAEN
  UNSIGNED_LONGS_EQUAL(kCfg2, bus.peek(kSpi + s::kCfg2));  // master, SSM, AFCNTR, mode 2, simplex receiver
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kSpi + s::kIer));
  // SPE = 0 (CR1 = SSI) before the configuration registers are written.
  const long cr1 = bus.index_of_write(kSpi + s::kCr1);
  CHECK(cr1 >= 0);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi, bus.log(static_cast<std::size_t>(cr1)).value);
  CHECK(cr1 < bus.index_of_write(kSpi + s::kCfg1));
  CHECK(cr1 < bus.index_of_write(kSpi + s::kCfg2));
  LONGS_EQUAL(1, bus.writes_to(kSpi + s::kCr1));  // never SPE / CSTART
  // DMAMUX1 channel 0 <- request 61 (spi3_rx_dma); PAR = SPI3 RXDR; direct mode.
  LONGS_EQUAL(1, bus.writes_to(kMux));
  UNSIGNED_LONGS_EQUAL(61u, bus.peek(kMux));
  LONGS_EQUAL(1, bus.writes_to(kPar));
  UNSIGNED_LONGS_EQUAL(0x40003C30u, bus.peek(kPar));
  LONGS_EQUAL(1, bus.writes_to(kFcr));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kFcr));
  // The stream off and its flags cleared before PAR is written.
  const long off = bus.index_of_write(kCr);
  CHECK(off >= 0);
  UNSIGNED_LONGS_EQUAL(0u, bus.log(static_cast<std::size_t>(off)).value);
  CHECK(off < bus.index_of_write(kPar));
  LONGS_EQUAL(1, bus.writes_to(kLifcr));
  UNSIGNED_LONGS_EQUAL(kStreamFlags, bus.peek(kLifcr));
  // Both CS high (set bits only), nothing armed, nothing clocked.
  LONGS_EQUAL(2, bus.writes_to(kBsrr));
  UNSIGNED_LONGS_EQUAL(kCs0High, bus.log(static_cast<std::size_t>(bus.index_of_write(kBsrr, 0))).value);
  UNSIGNED_LONGS_EQUAL(kCs1High, bus.log(static_cast<std::size_t>(bus.index_of_write(kBsrr, 1))).value);
  CHECK(hw.cs_high[0]);
  CHECK(hw.cs_high[1]);
  LONGS_EQUAL(0, bus.writes_to(kM0ar));
  LONGS_EQUAL(0, bus.writes_to(kNdtr));
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kCr2));
  LONGS_EQUAL(0, hw.spi_dma.transfers());
  CHECK_FALSE(bus.capacity_exceeded());
}

TEST(Ad7606Stm32Dma, APairReadDecodesBothDevicesInChannelOrder) {
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK_FALSE(hw.cs_high[0]);  // ADC0's frame open until the DMA interrupt
  CHECK(hw.cs_high[1]);
  CHECK(adc.advance() == Step::kNextDevice);  // ADC0 done, ADC1 started
  CHECK(hw.cs_high[0]);
  CHECK_FALSE(hw.cs_high[1]);
  CHECK(adc.advance() == Step::kComplete);
  CHECK(hw.cs_high[0]);
  CHECK(hw.cs_high[1]);
  CHECK(adc.advance() == Step::kIdle);  // a spurious interrupt after the pair: nothing
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  check_codes(codes);
  // The raw words: word w = V(2w+1) << 16 | V(2w+2), as the device clocked them.
  UNSIGNED_LONGS_EQUAL(0x0065FF36u, buffer[0][0]);  // 101, -202
  UNSIGNED_LONGS_EQUAL(0x7FFF8000u, buffer[0][3]);  // 32767, -32768
  LONGS_EQUAL(1, adc.state().reads);
  LONGS_EQUAL(0, adc.state().not_ready);
  LONGS_EQUAL(0, adc.state().bus_errors);
  LONGS_EQUAL(0, adc.state().busy_faults);
  LONGS_EQUAL(2, hw.spi_dma.transfers());
  LONGS_EQUAL(128, hw.adc[0].last_frame_bits());  // one CS frame of 128 SCLKs per device
  LONGS_EQUAL(128, hw.adc[1].last_frame_bits());
  LONGS_EQUAL(0, hw.both_selected);
  LONGS_EQUAL(0, hw.unselected);
  // No CPU word traffic: RXDR never read, TXDR never written.
  LONGS_EQUAL(0, hw.rxdr_reads);
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kTxdr));
  LONGS_EQUAL(1, hw.idr_reads);  // BUSY read once, at begin()
}

TEST(Ad7606Stm32Dma, EachDeviceFollowsTheDmaProcedure) {
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kOk);
  // Stream armed (M0AR, NDTR, CR with EN) -> TSIZE -> SPE -> CS0 low -> CSTART.
  const long m0ar = bus.index_of_write(kM0ar);
  const long ndtr = bus.index_of_write(kNdtr);
  const long en = bus.index_of_write(kCr);
  const long tsize = bus.index_of_write(kSpi + s::kCr2);
  const long spe = bus.index_of_write(kSpi + s::kCr1, 0);
  const long cs = bus.index_of_write(kBsrr);
  const long cstart = bus.index_of_write(kSpi + s::kCr1, 1);
  CHECK(m0ar >= 0);
  CHECK(m0ar < ndtr);
  CHECK(ndtr < en);
  CHECK(en < tsize);
  CHECK(tsize < spe);
  CHECK(spe < cs);
  CHECK(cs < cstart);
  UNSIGNED_LONGS_EQUAL(addr_of(&buffer[0][0]), bus.log(static_cast<std::size_t>(m0ar)).value);
  UNSIGNED_LONGS_EQUAL(4u, bus.log(static_cast<std::size_t>(ndtr)).value);
  UNSIGNED_LONGS_EQUAL(kSxCrRun, bus.log(static_cast<std::size_t>(en)).value);
  UNSIGNED_LONGS_EQUAL(4u, bus.log(static_cast<std::size_t>(tsize)).value);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi | s::kCr1Spe, bus.log(static_cast<std::size_t>(spe)).value);
  UNSIGNED_LONGS_EQUAL(kCs0Low, bus.log(static_cast<std::size_t>(cs)).value);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart, bus.log(static_cast<std::size_t>(cstart)).value);
  LONGS_EQUAL(7, static_cast<long>(bus.log_size()));  // and nothing else

  // ADC0's end: stream flags -> SPI flags -> SPE = 0 -> CS0 high, then ADC1's start, same order.
  bus.clear_log();
  CHECK(adc.advance() == Step::kNextDevice);
  const long dma_clear = bus.index_of_write(kLifcr);
  const long spi_clear = bus.index_of_write(kSpi + s::kIfcr);
  const long spe_off = bus.index_of_write(kSpi + s::kCr1, 0);
  const long cs0_high = bus.index_of_write(kBsrr, 0);
  const long m0ar1 = bus.index_of_write(kM0ar);
  const long en1 = bus.index_of_write(kCr);
  const long cs1_low = bus.index_of_write(kBsrr, 1);
  const long cstart1 = bus.index_of_write(kSpi + s::kCr1, 2);
  CHECK(dma_clear >= 0);
  CHECK(dma_clear < spi_clear);
  CHECK(spi_clear < spe_off);
  CHECK(spe_off < cs0_high);
  CHECK(cs0_high < m0ar1);
  CHECK(m0ar1 < en1);
  CHECK(en1 < cs1_low);
  CHECK(cs1_low < cstart1);
  UNSIGNED_LONGS_EQUAL(kStreamFlags, bus.log(static_cast<std::size_t>(dma_clear)).value);
  UNSIGNED_LONGS_EQUAL(s::kIfcrEotc | s::kIfcrTxtfc | s::kIfcrOvrc, bus.log(static_cast<std::size_t>(spi_clear)).value);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi, bus.log(static_cast<std::size_t>(spe_off)).value);
  UNSIGNED_LONGS_EQUAL(kCs0High, bus.log(static_cast<std::size_t>(cs0_high)).value);
  UNSIGNED_LONGS_EQUAL(addr_of(&buffer[1][0]), bus.log(static_cast<std::size_t>(m0ar1)).value);
  UNSIGNED_LONGS_EQUAL(kSxCrRun, bus.log(static_cast<std::size_t>(en1)).value);
  UNSIGNED_LONGS_EQUAL(kCs1Low, bus.log(static_cast<std::size_t>(cs1_low)).value);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi | s::kCr1Spe | s::kCr1Cstart, bus.log(static_cast<std::size_t>(cstart1)).value);

  // ADC1's end: the same four writes, CS1 high, nothing started.
  bus.clear_log();
  CHECK(adc.advance() == Step::kComplete);
  LONGS_EQUAL(4, static_cast<long>(bus.log_size()));
  UNSIGNED_LONGS_EQUAL(kLifcr, bus.log(0).addr);
  UNSIGNED_LONGS_EQUAL(kSpi + s::kIfcr, bus.log(1).addr);
  UNSIGNED_LONGS_EQUAL(kSpi + s::kCr1, bus.log(2).addr);
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi, bus.log(2).value);
  UNSIGNED_LONGS_EQUAL(kBsrr, bus.log(3).addr);
  UNSIGNED_LONGS_EQUAL(kCs1High, bus.log(3).value);
}

TEST(Ad7606Stm32Dma, PerTickTrafficIsOnlyThePerDeviceRegisters) {
  bus.clear_log();
  hw.sr_reads = 0;
  hw.idr_reads = 0;
  ad7606::Codes codes{};
  good_tick(codes);
  good_tick(codes);
  LONGS_EQUAL(2, adc.state().reads);
  // Written once by init(), never per tick.
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kCfg1));
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kCfg2));
  LONGS_EQUAL(0, bus.writes_to(kSpi + s::kIer));
  LONGS_EQUAL(0, bus.writes_to(kPar));
  LONGS_EQUAL(0, bus.writes_to(kFcr));
  LONGS_EQUAL(0, bus.writes_to(kMux));
  // Exactly one M0AR + NDTR + SxCR (+ TSIZE) per device: 2 ticks x 2 devices.
  LONGS_EQUAL(4, bus.writes_to(kM0ar));
  LONGS_EQUAL(4, bus.writes_to(kNdtr));
  LONGS_EQUAL(4, bus.writes_to(kCr));
  LONGS_EQUAL(4, bus.writes_to(kSpi + s::kCr2));
  for (std::size_t i = 0; i < 4; ++i) {
    UNSIGNED_LONGS_EQUAL(kSxCrRun, bus.log(static_cast<std::size_t>(bus.index_of_write(kCr, i))).value);
  }
  LONGS_EQUAL(4, bus.writes_to(kLifcr));            // once per completed device
  LONGS_EQUAL(4, bus.writes_to(kSpi + s::kIfcr));
  LONGS_EQUAL(12, bus.writes_to(kSpi + s::kCr1));  // SPE, CSTART, SPE = 0 per device
  LONGS_EQUAL(8, bus.writes_to(kBsrr));             // CS low, CS high per device
  LONGS_EQUAL(4 * 11, static_cast<long>(bus.log_size()));  // 7 writes to start a device, 4 to end it, nothing else
  LONGS_EQUAL(4, hw.sr_reads);   // EOT found on the first read after each TC
  LONGS_EQUAL(2, hw.idr_reads);  // BUSY once per begin()
  LONGS_EQUAL(4, hw.spi_dma.transfers());
}

TEST(Ad7606Stm32Dma, EveryAdvanceThatCompletesADeviceClearsTheStreamFlags) {
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK((bus.read32(kLisr) & d::kFlagTc) != 0u);  // ADC0's TC: the interrupt is pending
  bus.clear_log();
  CHECK(adc.advance() == Step::kNextDevice);
  // Cleared once, before ADC1's stream is enabled (which raises TC again).
  LONGS_EQUAL(1, bus.writes_to(kLifcr));
  UNSIGNED_LONGS_EQUAL(kStreamFlags, bus.peek(kLifcr));
  CHECK(bus.index_of_write(kLifcr) < bus.index_of_write(kCr));
  bus.clear_log();
  CHECK(adc.advance() == Step::kComplete);
  LONGS_EQUAL(1, bus.writes_to(kLifcr));
  UNSIGNED_LONGS_EQUAL(0u, bus.read32(kLisr) & kStreamFlags);  // nothing left to re-enter the interrupt
  // Re-entered anyway: nothing happens, the pair is still there for the tick.
  bus.clear_log();
  CHECK(adc.advance() == Step::kIdle);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  check_codes(codes);
}

TEST(Ad7606Stm32Dma, NoReadStartedIsSensorLoss) {
  bus.clear_log();
  ad7606::Codes codes{};
  fill(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  check_untouched(codes, 0x1234);
  LONGS_EQUAL(1, adc.state().not_ready);
  LONGS_EQUAL(0, adc.state().reads);
  CHECK(adc.advance() == Step::kIdle);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // nothing to cancel, nothing driven
  LONGS_EQUAL(0, hw.spi_dma.transfers());
}

TEST(Ad7606Stm32Dma, ACompletedPairIsTakenOnlyOnce) {
  ad7606::Codes codes{};
  good_tick(codes);
  // The next tick with no new read: loss, not the old words (still in the buffer).
  ad7606::Codes again{};
  fill(again, 0x1234);
  CHECK(adc.read(again) == ad7606::Status::kNotReady);
  check_untouched(again, 0x1234);
  UNSIGNED_LONGS_EQUAL(0x0065FF36u, buffer[0][0]);
  LONGS_EQUAL(1, adc.state().reads);
  LONGS_EQUAL(1, adc.state().not_ready);
  // A tick while ADC1 is still being read (its interrupt not yet taken): loss too, the read cancelled.
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == Step::kNextDevice);
  CHECK(adc.read(again) == ad7606::Status::kNotReady);
  check_untouched(again, 0x1234);
  LONGS_EQUAL(2, adc.state().not_ready);
  CHECK(hw.cs_high[1]);
  CHECK(adc.advance() == Step::kIdle);  // its late interrupt finds nothing to do
}

TEST(Ad7606Stm32Dma, BusyHighAtBeginIsStillBusy) {
  hw.busy = true;
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kStillBusy);
  LONGS_EQUAL(1, adc.state().busy_faults);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // no CS, no stream: a half-converted result is never read
  LONGS_EQUAL(0, hw.spi_dma.transfers());
  CHECK(adc.advance() == Step::kIdle);
  ad7606::Codes codes{};
  fill(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kStillBusy);
  check_untouched(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);  // reported once; then no read
  LONGS_EQUAL(1, adc.state().busy_faults);
  LONGS_EQUAL(1, adc.state().not_ready);
  // BUSY low at the next fall: reads normally.
  hw.busy = false;
  good_tick(codes);
}

TEST(Ad7606Stm32Dma, AReadStillRunningAtTheNextBeginIsCancelled) {
  hw.spi_dma.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK_FALSE(hw.cs_high[0]);
  CHECK((bus.read32(kCr) & d::kCrEn) != 0u);
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kNotReady);  // cancelled: this conversion is lost too
  UNSIGNED_LONGS_EQUAL(0u, bus.read32(kCr) & d::kCrEn);  // stream off
  LONGS_EQUAL(1, bus.writes_to(kCr));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(kCr));
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi, bus.peek(kSpi + s::kCr1));  // SPE = 0
  CHECK(hw.cs_high[0]);                                        // CS released
  CHECK(hw.cs_high[1]);
  LONGS_EQUAL(0, bus.writes_to(kM0ar));  // nothing new started
  LONGS_EQUAL(1, adc.state().not_ready);
  ad7606::Codes codes{};
  fill(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  check_untouched(codes, 0x1234);
  LONGS_EQUAL(1, adc.state().not_ready);  // counted where it happened, once
  // The next conversion reads normally again.
  hw.spi_dma.inject(dma::SpiRxDmaModel::Fault::kNone);
  good_tick(codes);
}

TEST(Ad7606Stm32Dma, TransferErrorIsBusErrorNotStaleData) {
  ad7606::Codes codes{};
  good_tick(codes);  // the buffer now holds valid-looking words
  hw.spi_dma.inject(dma::SpiRxDmaModel::Fault::kTransferError);
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == Step::kError);  // the tick runs, and gets no data
  LONGS_EQUAL(1, adc.state().bus_errors);
  CHECK(hw.cs_high[0]);
  CHECK(hw.cs_high[1]);
  UNSIGNED_LONGS_EQUAL(0u, bus.read32(kCr) & d::kCrEn);
  UNSIGNED_LONGS_EQUAL(0u, bus.read32(kLisr) & kStreamFlags);  // TEIF cleared: no re-entry
  LONGS_EQUAL(1, bus.writes_to(kM0ar));  // ADC1 never started
  LONGS_EQUAL(3, hw.spi_dma.transfers());  // the good pair + the failed ADC0
  fill(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
  check_untouched(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  LONGS_EQUAL(1, adc.state().bus_errors);
  LONGS_EQUAL(1, adc.state().reads);
  good_tick(codes);  // and recovers
}

TEST(Ad7606Stm32Dma, TransferErrorOnTheSecondDevice) {
  // The DMA may write ADC0's four words only: ADC1's M0AR is outside the mapped memory.
  hw.spi_dma.map_memory(&buffer[0][0], 4);
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == Step::kNextDevice);
  CHECK(adc.advance() == Step::kError);
  CHECK(hw.cs_high[0]);
  CHECK(hw.cs_high[1]);
  LONGS_EQUAL(1, adc.state().bus_errors);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
  LONGS_EQUAL(0, adc.state().reads);
}

TEST(Ad7606Stm32Dma, AStallKeepsAdvanceBusyAndTheTickCancelsIt) {
  hw.spi_dma.inject(dma::SpiRxDmaModel::Fault::kStall);
  CHECK(adc.begin() == ad7606::Status::kOk);
  bus.clear_log();
  for (int i = 0; i < 3; ++i) CHECK(adc.advance() == Step::kBusy);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // a poll with nothing done writes nothing
  CHECK_FALSE(hw.cs_high[0]);
  ad7606::Codes codes{};
  fill(codes, 0x1234);
  CHECK(adc.read(codes) == ad7606::Status::kNotReady);
  check_untouched(codes, 0x1234);
  LONGS_EQUAL(1, adc.state().not_ready);
  UNSIGNED_LONGS_EQUAL(0u, bus.read32(kCr) & d::kCrEn);  // stream stopped
  UNSIGNED_LONGS_EQUAL(kStreamFlags, bus.peek(kLifcr));  // its flags cleared
  UNSIGNED_LONGS_EQUAL(s::kCr1Ssi, bus.peek(kSpi + s::kCr1));
  CHECK(hw.cs_high[0]);
  CHECK(adc.advance() == Step::kIdle);
  hw.spi_dma.inject(dma::SpiRxDmaModel::Fault::kNone);
  good_tick(codes);
}

TEST(Ad7606Stm32Dma, SpiOverrunIsAnError) {
  hw.overrun_next = true;
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(hw.ovr);
  CHECK(adc.advance() == Step::kError);  // TC and EOT came, but a word was lost
  CHECK_FALSE(hw.ovr);                    // OVRC written
  CHECK(hw.cs_high[0]);
  CHECK(hw.cs_high[1]);
  LONGS_EQUAL(1, hw.spi_dma.transfers());  // ADC1 never started
  LONGS_EQUAL(1, adc.state().bus_errors);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
  good_tick(codes);
}

TEST(Ad7606Stm32Dma, EotThatNeverFollowsTheTcIsABoundedError) {
  Reader bounded{bus, buffer, 5};
  bounded.init();
  hw.eot_lost = true;
  CHECK(bounded.begin() == ad7606::Status::kOk);
  hw.sr_reads = 0;
  CHECK(bounded.advance() == Step::kError);
  LONGS_EQUAL(6, hw.sr_reads);  // the first read + max_eot_polls
  CHECK(hw.cs_high[0]);
  LONGS_EQUAL(1, bounded.state().bus_errors);
  ad7606::Codes codes{};
  CHECK(bounded.read(codes) == ad7606::Status::kBusError);
}

TEST(Ad7606Stm32Dma, AStreamStillEnabledIsNeverReprogrammed) {
  bus.write32(kCr, kSxCrRun);  // something else left the stream running
  bus.clear_log();
  CHECK(adc.begin() == ad7606::Status::kBusError);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));  // no M0AR / NDTR / CR, no CS
  CHECK(hw.cs_high[0]);
  LONGS_EQUAL(1, adc.state().bus_errors);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
}

TEST(Ad7606Stm32Dma, WrongDmamuxRequestNeverCompletes) {
  // The model moves data only for a stream routed to spi3_rx_dma (61): a
  // wiring with SPI2's request (39) stays busy, and the tick sees the loss.
  static constexpr ad7606::Stm32AdcWiring kMisrouted{r::spi::kSpi3, {kPortE, kPortE}, {15, 10}, kPortE, 11,
                                                     r::dma::kDma1, 0, r::dma::kReqSpi2Rx, 2, true, false};
  using Misrouted = ad7606::Stm32DmaReader<Bus, kMisrouted>;
  Misrouted wrong{bus, buffer};
  wrong.init();
  UNSIGNED_LONGS_EQUAL(39u, bus.peek(kMux));
  CHECK(wrong.begin() == ad7606::Status::kOk);
  CHECK(wrong.advance() == Misrouted::Step::kBusy);
  ad7606::Codes codes{};
  CHECK(wrong.read(codes) == ad7606::Status::kNotReady);
  LONGS_EQUAL(0, hw.spi_dma.transfers());
  CHECK(hw.cs_high[0]);
}

// The board's sensor source over the reader: a completed pair is a good
// sample; no completed pair is kAdcFault and read() false (the servo loop
// counts a sensor fault), never the previous sample's ADC values.
TEST(Ad7606Stm32Dma, BoardSensorSourceReportsLossAsAdcFault) {
  FixedEncoder e0, e1, e2;
  maglev::board::stm32h743::AmplifierBoardSensors<FixedEncoder, Reader> sensors{adc, e0, e1, e2};
  CHECK(adc.begin() == ad7606::Status::kOk);
  CHECK(adc.advance() == Step::kNextDevice);
  CHECK(adc.advance() == Step::kComplete);
  maglev::io::SensorSample sample{};
  CHECK_TRUE(sensors.read(sample));
  LONGS_EQUAL(101, sample.displacement_adc[0]);   // ADC0 V1
  LONGS_EQUAL(-404, sample.hall_adc[0]);          // ADC0 V4
  LONGS_EQUAL(8000, sample.coil_current_adc[7]);  // ADC1 V8
  UNSIGNED_LONGS_EQUAL(0u, sample.status_flags);
  // Next tick without a new DMA read (e.g. the stream never completed):
  maglev::io::SensorSample next{};
  CHECK_FALSE(sensors.read(next));
  CHECK(next.status_flags & maglev::io::kAdcFault);
  LONGS_EQUAL(0, next.displacement_adc[0]);  // nothing copied from the old buffer
  LONGS_EQUAL(0, next.coil_current_adc[7]);
}

// Other streams (the board uses DMA1 stream 0): the reader takes its stream's
// registers, flag bits (LISR / HISR at 0, 6, 16, 22; RM0433 §15.5.5..8) and
// DMAMUX1 channel (DMA1 stream n -> channel n, DMA2 stream n -> 8 + n; §17.3.2)
// from the wiring. On a plain register bus, the test plays the hardware's end
// of a transfer: EN cleared, the stream's flags set, SPI EOT. Addresses and bit
// positions are literals from the manual, independent of registers.hpp.
namespace {

// What the manual puts where for one stream.
struct StreamAt {
  r::Addr cr;          // SxCR (SxPAR at +0x08, SxFCR at +0x14)
  r::Addr isr;         // the ISR holding this stream's flags, and the controller's other one
  r::Addr other_isr;
  r::Addr ifcr;        // likewise for the clear registers
  r::Addr other_ifcr;
  unsigned shift;      // this stream's FEIF bit
  r::Addr mux;         // its DMAMUX1 channel's CxCR
};

constexpr ad7606::Stm32AdcWiring on_stream(r::Addr dma, std::uint8_t stream) {
  return {r::spi::kSpi3, {kPortE, kPortE}, {15, 10}, kPortE, 11, dma, stream, r::dma::kReqSpi3Rx, 2, true, false};
}

void transfer_ends(Bus& bus, const StreamAt& at, std::uint32_t flags) {
  bus.preset(at.cr, bus.peek(at.cr) & ~1u);  // the hardware clears EN
  bus.preset(at.isr, flags << at.shift);
}

template <ad7606::Stm32AdcWiring kOther>
void reads_its_own_stream(const StreamAt& at) {
  using R = ad7606::Stm32DmaReader<Bus, kOther>;
  Bus bus;
  std::uint32_t buffer[2][4]{};
  R adc{bus, buffer};
  adc.init();
  // init(): the stream off, its flags (and only its) cleared, its DMAMUX channel routed.
  UNSIGNED_LONGS_EQUAL(61u, bus.peek(at.mux));  // spi3_rx_dma
  LONGS_EQUAL(1, bus.writes_to(at.mux));
  LONGS_EQUAL(1, bus.writes_to(at.cr));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(at.cr));
  UNSIGNED_LONGS_EQUAL(0x40003C30u, bus.peek(at.cr + 0x08u));  // PAR = SPI3 RXDR
  LONGS_EQUAL(1, bus.writes_to(at.cr + 0x14u));                 // FCR: direct mode
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(at.cr + 0x14u));
  LONGS_EQUAL(1, bus.writes_to(at.ifcr));
  UNSIGNED_LONGS_EQUAL(0x3Du << at.shift, bus.peek(at.ifcr));
  LONGS_EQUAL(0, bus.writes_to(at.other_ifcr));
  LONGS_EQUAL(0, bus.writes_to(kMux));  // DMAMUX1 channel 0 (the board's stream) untouched
  LONGS_EQUAL(0, bus.writes_to(kCr));

  bus.preset(kSpi + s::kSr, s::kSrEot);  // EOT is there once the stream's TC is
  CHECK(adc.begin() == ad7606::Status::kOk);
  UNSIGNED_LONGS_EQUAL(kSxCrRun, bus.peek(at.cr));
  // Every other stream's flags, in both ISRs (this stream's positions in the
  // other one included): not ours, nothing happens.
  bus.clear_log();
  bus.preset(at.other_isr, 0xFFFFFFFFu);
  bus.preset(at.isr, ~(0x3Du << at.shift));
  CHECK(adc.advance() == R::Step::kBusy);
  LONGS_EQUAL(0, static_cast<long>(bus.log_size()));
  // Its TCIF: ADC0 done (its flags cleared in its IFCR only), ADC1 started.
  transfer_ends(bus, at, d::kFlagTc);
  CHECK(adc.advance() == R::Step::kNextDevice);
  LONGS_EQUAL(1, bus.writes_to(at.ifcr));
  UNSIGNED_LONGS_EQUAL(0x3Du << at.shift, bus.peek(at.ifcr));
  LONGS_EQUAL(0, bus.writes_to(at.other_ifcr));
  UNSIGNED_LONGS_EQUAL(kSxCrRun, bus.peek(at.cr));
  transfer_ends(bus, at, d::kFlagTc);
  CHECK(adc.advance() == R::Step::kComplete);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  // TEIF, even together with TCIF, and DMEIF: errors.
  CHECK(adc.begin() == ad7606::Status::kOk);
  transfer_ends(bus, at, d::kFlagTc | d::kFlagTe);
  CHECK(adc.advance() == R::Step::kError);
  CHECK(adc.read(codes) == ad7606::Status::kBusError);
  CHECK(adc.begin() == ad7606::Status::kOk);
  transfer_ends(bus, at, d::kFlagDme);
  CHECK(adc.advance() == R::Step::kError);
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(at.cr));  // stream off after the error
  LONGS_EQUAL(2, adc.state().bus_errors);
  LONGS_EQUAL(1, adc.state().reads);
}

}  // namespace

TEST_GROUP(Ad7606Stm32DmaOtherStreams){};

TEST(Ad7606Stm32DmaOtherStreams, Dma1Stream5IsHisrBits11To6AndDmamuxChannel5) {
  reads_its_own_stream<on_stream(r::dma::kDma1, 5)>(
      {0x40020088u, 0x40020004u, 0x40020000u, 0x4002000Cu, 0x40020008u, 6, 0x40020814u});
}

TEST(Ad7606Stm32DmaOtherStreams, Dma1Stream2IsLisrBits21To16) {
  reads_its_own_stream<on_stream(r::dma::kDma1, 2)>(
      {0x40020040u, 0x40020000u, 0x40020004u, 0x40020008u, 0x4002000Cu, 16, 0x40020808u});
}

TEST(Ad7606Stm32DmaOtherStreams, Dma1Stream7IsHisrBits27To22) {
  reads_its_own_stream<on_stream(r::dma::kDma1, 7)>(
      {0x400200B8u, 0x40020004u, 0x40020000u, 0x4002000Cu, 0x40020008u, 22, 0x4002081Cu});
}

TEST(Ad7606Stm32DmaOtherStreams, Dma2Stream1IsDmamuxChannel9) {
  reads_its_own_stream<on_stream(r::dma::kDma2, 1)>(
      {0x40020428u, 0x40020400u, 0x40020404u, 0x40020408u, 0x4002040Cu, 6, 0x40020824u});
}
