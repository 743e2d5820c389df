// Quadrature counters: encoder-mode registers, 16-bit extension across wraps,
// latched signal loss.
#include <CppUTest/TestHarness.h>

#include <cstdint>

#include "maglev/drivers/fake_bus.hpp"
#include "maglev/drivers/quadrature_encoder.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;

TEST_GROUP(CounterExtender16){};

TEST(CounterExtender16, CrossesWrapsUpAndDown) {
  CounterExtender16 e;
  e.reset(0);
  UNSIGNED_LONGS_EQUAL(0x7000u, e.update(0x7000));
  UNSIGNED_LONGS_EQUAL(0xE000u, e.update(0xE000));
  UNSIGNED_LONGS_EQUAL(0x15000u, e.update(0x5000));  // wrapped 0xFFFF -> 0: +0x7000
  UNSIGNED_LONGS_EQUAL(0xE000u, e.update(0xE000));   // back across the wrap
  UNSIGNED_LONGS_EQUAL(0x7000u, e.update(0x7000));
  UNSIGNED_LONGS_EQUAL(0x0u, e.update(0x0000));
  UNSIGNED_LONGS_EQUAL(0xFFFF9000u, e.update(0x9000));  // below zero: wraps as a 32-bit counter
}

TEST(CounterExtender16, LongWalkMatchesA64BitReference) {
  CounterExtender16 e;
  e.reset(0);
  std::int64_t truth = 0;
  std::uint32_t lcg = 12345u;
  for (int i = 0; i < 20000; ++i) {
    lcg = lcg * 1664525u + 1013904223u;
    // Steps up to +-16383 counts, biased forward: many wraps of 16 bits.
    const std::int32_t step = static_cast<std::int32_t>(lcg >> 17) - 16383 + 3000;
    truth += step;
    const std::uint32_t got = e.update(static_cast<std::uint16_t>(static_cast<std::uint64_t>(truth) & 0xFFFFu));
    if (got != static_cast<std::uint32_t>(static_cast<std::uint64_t>(truth))) {
      FAIL("extension diverged from the reference count");
    }
  }
  CHECK(truth > 50'000'000);  // crossed > 760 16-bit wraps
}

TEST_GROUP(QuadratureEncoder) {
  r::FakeRegisterBus<> bus;
  FakeInputPin loss{true};  // loss output active LOW: high = beam OK
};

TEST(QuadratureEncoder, Tim2EncoderMode32Bit) {
  QuadratureEncoder<r::FakeRegisterBus<>> enc(bus, {r::tim::kTim2, true, 1, false}, loss);
  enc.init();
  UNSIGNED_LONGS_EQUAL(3u, bus.peek(r::tim::kTim2 + r::tim::kSmcr));      // SMS = 011
  UNSIGNED_LONGS_EQUAL(0x1111u, bus.peek(r::tim::kTim2 + r::tim::kCcmr1));  // CC1S=CC2S=01, IC1F=IC2F=0001
  UNSIGNED_LONGS_EQUAL(0xFFFFFFFFu, bus.peek(r::tim::kTim2 + r::tim::kArr));
  UNSIGNED_LONGS_EQUAL(0u, bus.peek(r::tim::kTim2 + r::tim::kDier));  // no extension interrupts needed
  const std::size_t last = bus.log_size() - 1;
  UNSIGNED_LONGS_EQUAL(r::tim::kTim2 + r::tim::kCr1, bus.log(last).addr);
  UNSIGNED_LONGS_EQUAL(1u, bus.log(last).value);
  bus.preset(r::tim::kTim2 + r::tim::kCnt, 0xFFFFFFF0u);
  UNSIGNED_LONGS_EQUAL(0xFFFFFFF0u, enc.update());
}

TEST(QuadratureEncoder, Tim3SixteenBitExtendedWithQuarterPointInterrupts) {
  QuadratureEncoder<r::FakeRegisterBus<>> enc(bus, {r::tim::kTim3, false, 1, false}, loss);
  enc.init();
  UNSIGNED_LONGS_EQUAL(0xFFFFu, bus.peek(r::tim::kTim3 + r::tim::kArr));
  UNSIGNED_LONGS_EQUAL(0x4000u, bus.peek(r::tim::kTim3 + r::tim::kCcr3));
  UNSIGNED_LONGS_EQUAL(0xC000u, bus.peek(r::tim::kTim3 + r::tim::kCcr4));
  UNSIGNED_LONGS_EQUAL(0x19u, bus.peek(r::tim::kTim3 + r::tim::kDier));  // UIE | CC3IE | CC4IE
  // Count down through zero: quarter-point IRQs keep the extension exact.
  const std::uint16_t path[] = {0xC000, 0x8000, 0x4000, 0x0000};
  for (std::uint16_t c : path) {
    bus.preset(r::tim::kTim3 + r::tim::kCnt, c);
    bus.preset(r::tim::kTim3 + r::tim::kSr, 0x19u);
    enc.on_timer_irq();
    UNSIGNED_LONGS_EQUAL(0u, bus.peek(r::tim::kTim3 + r::tim::kSr));  // flags cleared (rc_w0)
  }
  UNSIGNED_LONGS_EQUAL(0xFFFF0000u, enc.update());  // -65536 after one full turn down
}

TEST(QuadratureEncoder, SignalLossIsLatchedUntilCleared) {
  QuadratureEncoder<r::FakeRegisterBus<>> enc(bus, {r::tim::kTim5, true, 1, false}, loss);
  enc.init();
  enc.update();
  CHECK_FALSE(enc.signal_lost());
  loss.set(false);  // electronics report loss
  enc.update();
  CHECK_TRUE(enc.signal_lost());
  loss.set(true);  // beam back: still not referenced
  enc.update();
  CHECK_TRUE(enc.signal_lost());
  enc.clear_signal_loss();
  enc.update();
  CHECK_FALSE(enc.signal_lost());
}
