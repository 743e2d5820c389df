// AD7606 pair: read sequence on BUSY low, DOUTA channel order, two's
// complement, channel map, CONVST timer registers.
#include <CppUTest/TestHarness.h>

#include "maglev/board/stm32h743/amplifier_board_io.hpp"
#include "maglev/drivers/ad7606.hpp"
#include "maglev/drivers/ad7606_model.hpp"
#include "maglev/drivers/convst_timer.hpp"
#include "maglev/drivers/fake_bus.hpp"
#include "maglev/stm32h7/register_bus.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;

TEST_GROUP(Ad7606) {
  FakeSpiMaster<> spi;
  FakeInputPin busy{false};
  ad7606::DeviceModel adc0;
  ad7606::DeviceModel adc1;
  const std::uint8_t cs[2] = {2, 3};
  ad7606::Adc adc{spi, cs, busy};
  void setup() override {
    spi.attach(2, &adc0);
    spi.attach(3, &adc1);
  }
};

TEST(Ad7606, ReadsBothDevicesV1ToV8InOrder) {
  for (std::size_t ch = 0; ch < 8; ++ch) {
    const int n = static_cast<int>(ch) + 1;
    adc0.set_code(ch, static_cast<std::int16_t>(100 * n));
    adc1.set_code(ch, static_cast<std::int16_t>(-1000 * n));
  }
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  for (std::size_t ch = 0; ch < 8; ++ch) {
    const int n = static_cast<int>(ch) + 1;
    LONGS_EQUAL(100 * n, codes.channel[0][ch]);
    LONGS_EQUAL(-1000 * n, codes.channel[1][ch]);
  }
  // One CS frame per device, 128 SCLKs each (4 x 32-bit words), device 0 first.
  LONGS_EQUAL(2, spi.transfer_count());
  LONGS_EQUAL(2, spi.record(0).device);
  LONGS_EQUAL(3, spi.record(1).device);
  LONGS_EQUAL(32, spi.record(0).word_bits);
  LONGS_EQUAL(4, spi.record(0).words);
  LONGS_EQUAL(128, adc0.last_frame_bits());
  LONGS_EQUAL(128, adc1.last_frame_bits());
}

TEST(Ad7606, TwosComplementFullScale) {
  adc0.set_input_V(0, 10.0);   // clips to +FS - 1 LSB
  adc0.set_input_V(1, -10.0);  // -FS
  adc0.set_input_V(2, -5.0);   // 0xC000
  adc0.set_input_V(3, 0.0003); // 1 LSB = 305 uV -> code 1
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kOk);
  LONGS_EQUAL(32767, codes.channel[0][0]);
  LONGS_EQUAL(-32768, codes.channel[0][1]);
  UNSIGNED_LONGS_EQUAL(0xC000u, static_cast<std::uint16_t>(codes.channel[0][2]));
  LONGS_EQUAL(1, codes.channel[0][3]);
  DOUBLES_EQUAL(-5.0, ad7606::code_to_V(codes.channel[0][2]), 1e-12);
}

TEST(Ad7606, BusyHighMeansNoReadAndAFault) {
  busy.set(true);
  ad7606::Codes codes{};
  CHECK(adc.read(codes) == ad7606::Status::kStillBusy);
  LONGS_EQUAL(0, spi.transfer_count());
  LONGS_EQUAL(1, adc.state().busy_faults);
}

TEST(Ad7606, ChannelMapFillsTheSensorSample) {
  for (std::size_t ch = 0; ch < 8; ++ch) {
    adc0.set_code(ch, static_cast<std::int16_t>(ch + 1));
    adc1.set_code(ch, static_cast<std::int16_t>(ch + 11));
  }
  ad7606::Codes codes{};
  adc.read(codes);
  maglev::io::SensorSample s{};
  maglev::board::stm32h743::map_to_sample(codes, s);
  LONGS_EQUAL(1, s.displacement_adc[0]);
  LONGS_EQUAL(3, s.displacement_adc[2]);
  LONGS_EQUAL(4, s.hall_adc[0]);  // A.Bx on ADC0 V4
  LONGS_EQUAL(7, s.hall_adc[3]);  // B.By on ADC0 V7
  LONGS_EQUAL(11, s.coil_current_adc[0]);
  LONGS_EQUAL(18, s.coil_current_adc[7]);
}

TEST(Ad7606, ConvstTimerFor2500HzAt240MHz) {
  constexpr ConvstTiming t = convst_timing(240'000'000, 2500, 1000);
  LONGS_EQUAL(1, t.psc);       // 96000 ticks do not fit 16 bits: /2
  LONGS_EQUAL(47999, t.arr);   // 120 MHz / 48000 = 2500 Hz exactly
  LONGS_EQUAL(120, t.ccr);     // 1 us high at 120 MHz
  r::FakeRegisterBus<> bus;
  start_convst_timer(bus, r::tim::kTim8, t);
  UNSIGNED_LONGS_EQUAL(1u, bus.peek(r::tim::kTim8 + r::tim::kPsc));
  UNSIGNED_LONGS_EQUAL(47999u, bus.peek(r::tim::kTim8 + r::tim::kArr));
  UNSIGNED_LONGS_EQUAL(120u, bus.peek(r::tim::kTim8 + r::tim::kCcr1));
  UNSIGNED_LONGS_EQUAL(0x68u, bus.peek(r::tim::kTim8 + r::tim::kCcmr1));  // OC1M=0110, OC1PE
  UNSIGNED_LONGS_EQUAL(0x8000u, bus.peek(r::tim::kTim8 + r::tim::kBdtr));
  // The counter is enabled last, after UG loaded the preloads.
  const std::size_t last = bus.log_size() - 1;
  UNSIGNED_LONGS_EQUAL(r::tim::kTim8 + r::tim::kCr1, bus.log(last).addr);
  UNSIGNED_LONGS_EQUAL(0x81u, bus.log(last).value);
  UNSIGNED_LONGS_EQUAL(r::tim::kTim8 + r::tim::kEgr, bus.log(last - 1).addr);
}
