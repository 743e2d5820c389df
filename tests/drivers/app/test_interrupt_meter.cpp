// app::InterruptMeter: the board's whole interrupt chain per tick (the
// AD7606 DMA bodies with on_tick() inside, then the DAC chain's SPI1 bodies),
// summed per tick and closed at the head of the next chain.
#include <CppUTest/TestHarness.h>

#include <cstdint>

#include "maglev/app/interrupt_meter.hpp"

using maglev::app::InterruptMeter;

TEST_GROUP(InterruptMeter){};

TEST(InterruptMeter, SumsEveryBodyOfATickAndClosesItAtTheNextChain) {
  InterruptMeter m;
  // Tick 1: BUSY fell (100), ADC0 done (150), ADC1 done + on_tick (6 000),
  // four SPI1 frames (200 each).
  m.begin_tick();
  m.add(1000, 1100);
  m.add(2000, 2150);
  m.add(3000, 9000);
  for (std::uint32_t k = 0; k < 4; ++k) m.add(10000 + 300 * k, 10200 + 300 * k);
  LONGS_EQUAL(0, m.state().ticks);  // not closed until the next chain begins
  LONGS_EQUAL(0, m.state().max_cycles);
  m.begin_tick();
  LONGS_EQUAL(1, m.state().ticks);
  LONGS_EQUAL(100 + 150 + 6000 + 800, m.state().last_cycles);
  LONGS_EQUAL(7050, m.state().max_cycles);
  // Tick 2, shorter: last follows it, max keeps the longest.
  m.add(0, 5000);
  m.begin_tick();
  LONGS_EQUAL(5000, m.state().last_cycles);
  LONGS_EQUAL(7050, m.state().max_cycles);
  LONGS_EQUAL(2, m.state().ticks);
}

TEST(InterruptMeter, TheCycleCounterWrapsInsideABody) {
  InterruptMeter m;
  m.begin_tick();
  m.add(0xFFFFFF00u, 0x00000100u);  // DWT CYCCNT wraps every 8.9 s at 480 MHz
  m.begin_tick();
  LONGS_EQUAL(0x200, m.state().last_cycles);
}

TEST(InterruptMeter, BodiesBeforeTheFirstChainAreNotATick) {
  InterruptMeter m;
  m.add(0, 50);  // an SPI1 body of a write started before metering began
  m.begin_tick();
  LONGS_EQUAL(0, m.state().ticks);
  LONGS_EQUAL(0, m.state().max_cycles);
}
