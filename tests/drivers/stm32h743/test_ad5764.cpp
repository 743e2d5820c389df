// AD5764 chain: datasheet command words, daisy-chain order, LDAC, SDO echo.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/ad5764.hpp"
#include "maglev/drivers/ad5764_model.hpp"
#include "maglev/drivers/fake_bus.hpp"

using namespace maglev::drivers;

TEST_GROUP(Ad5764CommandWord){};

TEST(Ad5764CommandWord, DataRegisterWriteLayout) {
  // DB23 R/W=0, DB22=0, REG=010 (bits 21..19), A=000 (DAC A), data 0x1234.
  UNSIGNED_LONGS_EQUAL(0x101234u, ad5764::command_word(false, ad5764::Register::kData, 0, 0x1234));
  // DAC D (A=011), read bit set.
  UNSIGNED_LONGS_EQUAL(0x930000u, ad5764::command_word(true, ad5764::Register::kData, 3, 0));
}

TEST(Ad5764CommandWord, OtherRegistersAndFunctionCodes) {
  UNSIGNED_LONGS_EQUAL(0x1C0000u, ad5764::command_word(false, ad5764::Register::kCoarseGain, ad5764::kAddressAllDacs, 0));
  UNSIGNED_LONGS_EQUAL(0x210080u, ad5764::command_word(false, ad5764::Register::kFineGain, 1, 0x80));
  UNSIGNED_LONGS_EQUAL(0x2A0000u, ad5764::command_word(false, ad5764::Register::kOffset, 2, 0));
  UNSIGNED_LONGS_EQUAL(0x050000u, ad5764::command_word(false, ad5764::Register::kFunction, ad5764::kFunctionLoad, 0));
  UNSIGNED_LONGS_EQUAL(0x040000u, ad5764::command_word(false, ad5764::Register::kFunction, ad5764::kFunctionClear, 0));
}

TEST(Ad5764CommandWord, TwosComplementCodes) {
  UNSIGNED_LONGS_EQUAL(0x108000u, ad5764::data_word(0, -32768));  // -10 V
  UNSIGNED_LONGS_EQUAL(0x10FFFFu, ad5764::data_word(0, -1));
  UNSIGNED_LONGS_EQUAL(0x117FFFu, ad5764::data_word(1, 32767));   // +10 V - 1 LSB
}

TEST_GROUP(Ad5764Chain) {
  FakeSpiMaster<> spi;
  FakeOutputPin<> ldac;
  ad5764::ChainModel<2> model;
  ad5764::Chain<2> dac{spi, 0, ldac};
  ad5764::Chain<2>* chain = &dac;
  void setup() override {
    spi.attach(0, &model);
    ldac.set_hook(&ad5764::ChainModel<2>::ldac_hook, &model);
    chain->init();
  }
};

TEST(Ad5764Chain, FourFramesOf48BitsLastDeviceFirst) {
  const std::int16_t codes[8] = {100, -1, 32767, -32768, 1, 2, 3, 4};
  CHECK(chain->write_codes(codes) == ad5764::Status::kOk);
  LONGS_EQUAL(4, spi.transfer_count());
  // Each frame: two 24-bit words; word 0 goes to the LAST device (coils 5..8).
  const std::uint32_t expected[4][2] = {{0x100001u, 0x100064u},
                                        {0x110002u, 0x11FFFFu},
                                        {0x120003u, 0x127FFFu},
                                        {0x130004u, 0x138000u}};
  for (std::size_t f = 0; f < 4; ++f) {
    LONGS_EQUAL(24, spi.record(f).word_bits);
    LONGS_EQUAL(2, spi.record(f).words);
    UNSIGNED_LONGS_EQUAL(expected[f][0], spi.word(f, 0));
    UNSIGNED_LONGS_EQUAL(expected[f][1], spi.word(f, 1));
  }
}

TEST(Ad5764Chain, BitLevelModelDecodesEveryCoilIntoItsDevice) {
  const std::int16_t codes[8] = {100, -1, 32767, -32768, 1, 2, 3, -3000};
  CHECK(chain->write_codes(codes) == ad5764::Status::kOk);
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(codes[j], model.dac_register(j / 4, j % 4));
  LONGS_EQUAL(0, model.malformed_frames());
  LONGS_EQUAL(0, model.non_data_writes());
  DOUBLES_EQUAL(10.0 * 32767.0 / 32768.0, model.output_V(0, 2), 1e-12);
  DOUBLES_EQUAL(-10.0, model.output_V(0, 3), 1e-12);
}

TEST(Ad5764Chain, OutputsChangeOnlyOnTheLdacPulse) {
  const std::int16_t first[8] = {10, 20, 30, 40, 50, 60, 70, 80};
  chain->write_codes(first);
  const std::uint32_t frame[2] = {ad5764::data_word(0, -5), ad5764::data_word(0, 7)};
  chain->write_frame(frame);
  LONGS_EQUAL(-5, model.input_register(0, 0));  // loaded into the input register ...
  LONGS_EQUAL(7, model.input_register(1, 0));
  LONGS_EQUAL(10, model.dac_register(0, 0));    // ... but not yet on the output
  LONGS_EQUAL(50, model.dac_register(1, 0));
  LONGS_EQUAL(1, model.ldac_pulses());
  // LDAC idles high and pulses low once per update: history = init high, low, high.
  LONGS_EQUAL(3, ldac.writes());
  CHECK_TRUE(ldac.history(0));
  CHECK_FALSE(ldac.history(1));
  CHECK_TRUE(ldac.history(2));
}

TEST(Ad5764Chain, SdoEchoMatchesPreviousFrame) {
  const std::int16_t codes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  chain->write_codes(codes);
  chain->write_codes(codes);
  LONGS_EQUAL(0, chain->state().link_mismatches);
  LONGS_EQUAL(2, chain->state().writes);
}

TEST(Ad5764Chain, BrokenLinkIsDetectedAndBusErrorSkipsLdac) {
  FakeSpiMaster<> dead_spi;  // no model: MISO stuck at 0
  FakeOutputPin<> pin;
  ad5764::Chain<2> c(dead_spi, 0, pin);
  c.init();
  const std::int16_t codes[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  CHECK(c.write_codes(codes) == ad5764::Status::kLinkMismatch);
  LONGS_EQUAL(3, c.state().link_mismatches);  // frames 2..4 should have echoed frames 1..3
  dead_spi.fail_next_transfer();
  const std::size_t ldac_writes = pin.writes();
  CHECK(c.write_codes(codes) == ad5764::Status::kBusError);
  LONGS_EQUAL(ldac_writes, pin.writes());  // no LDAC pulse on a partial update
  LONGS_EQUAL(1, c.state().bus_errors);
}

TEST(Ad5764Chain, WriteZeroLoadsMidscaleZero) {
  const std::int16_t codes[8] = {1000, 2000, 3000, 4000, 5000, 6000, 7000, 8000};
  chain->write_codes(codes);
  chain->write_zero();
  for (std::size_t j = 0; j < 8; ++j) LONGS_EQUAL(0, model.dac_register(j / 4, j % 4));
}
