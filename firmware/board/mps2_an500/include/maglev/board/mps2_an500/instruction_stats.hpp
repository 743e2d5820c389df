// Per-tick instruction statistics (min / mean / max, the tick of the max) and
// the line the QEMU images print for them:
//   <line> <label>: ticks=N min=A mean=B.b max=C (tick T)
// (kernel replay: step_instructions; whole servo tick: servo_tick_instructions
// and its breakdown). The ctests parse these lines (tests/target/bitexact).
#pragma once

#include <cstdint>

#include "maglev/board/mps2_an500/instruction_counter.hpp"
#include "maglev/board/mps2_an500/semihosting.hpp"

namespace maglev::board::mps2_an500::icount {

struct TickStats {
  std::uint64_t count = 0;
  std::uint64_t sum = 0;
  std::uint64_t min = ~std::uint64_t{0};
  std::uint64_t max = 0;
  std::uint32_t max_tick = 0;
  void add(std::uint64_t v, std::uint32_t tick) {
    ++count;
    sum += v;
    if (v < min) min = v;
    if (v > max) {
      max = v;
      max_tick = tick;
    }
  }
};

// Counts in SysTick units, printed in instructions (cal).
inline void print_tick_stats(const char* line, const char* label, const TickStats& s, const Calibration& cal) {
  semihost_write(line);
  semihost_write(" ");
  semihost_write(label);
  semihost_write(": ticks=");
  semihost_write_unsigned(s.count);
  if (s.count == 0U) {
    semihost_write("\n");
    return;
  }
  semihost_write(" min=");
  semihost_write_unsigned(cal.instructions(s.min));
  semihost_write(" mean=");
  // mean with one decimal: instructions(sum) over count, computed in tenths.
  const std::uint64_t span = cal.nop_counts - cal.empty_counts;
  const std::uint64_t net = s.sum - s.count * cal.empty_counts;
  const std::uint64_t tenths = cal.valid() ? (net * kCalibrationNops * 10U + span * s.count / 2U) / (span * s.count) : 0U;
  semihost_write_unsigned(tenths / 10U);
  semihost_write_char('.');
  semihost_write_unsigned(tenths % 10U);
  semihost_write(" max=");
  semihost_write_unsigned(cal.instructions(s.max));
  semihost_write(" (tick ");
  semihost_write_unsigned(s.max_tick);
  semihost_write(")\n");
}

}  // namespace maglev::board::mps2_an500::icount
