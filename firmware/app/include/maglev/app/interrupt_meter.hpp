// The servo's whole interrupt work per tick, in CPU cycles (issue 16, item 3:
// the 20 kHz budget is 25 % of the period for ALL of it).
//
// On the production board a tick is a chain of interrupts, not one: BUSY
// fell (EXTI) starts ADC0's DMA read, DMA1 stream 0 moves to ADC1 and then
// runs ServoLoop::on_tick(), and SPI1's end-of-transfer interrupt writes the
// DAC chain's four frames after it. ServoState::max_cycles times on_tick()
// alone; this meter sums every body of the chain: each handler reads the
// cycle counter (DWT CYCCNT) at its entry and exit and add()s the
// difference, and begin_tick() at the head of the next chain (BUSY fell)
// closes the previous tick's sum. Not counted: the exception entry / exit
// (~12 cycles each on the M7, 8 per tick) and the counter reads themselves.
//
// Every metered handler runs at the tick's NVIC priority, so they never
// preempt one another and the sum needs no lock; the Modbus thread reads
// the two 32-bit results with single loads.
#pragma once

#include <cstdint>

namespace maglev::app {

struct InterruptMeterState {
  std::uint32_t last_cycles = 0;  // the last complete tick's chain
  std::uint32_t max_cycles = 0;   // the longest since boot
  std::uint32_t ticks = 0;        // complete ticks summed
};

class InterruptMeter {
 public:
  // Head of a tick's chain: the previous chain is complete.
  void begin_tick() {
    if (open_) {
      state_.last_cycles = sum_;
      if (sum_ > state_.max_cycles) state_.max_cycles = sum_;
      ++state_.ticks;
    }
    sum_ = 0;
    open_ = true;
  }
  // One handler body (cycle counter difference, wrap-safe in uint32).
  void add(std::uint32_t start_cycles, std::uint32_t end_cycles) { sum_ += end_cycles - start_cycles; }

  const InterruptMeterState& state() const { return state_; }

 private:
  InterruptMeterState state_{};
  std::uint32_t sum_ = 0;
  bool open_ = false;
};

}  // namespace maglev::app
