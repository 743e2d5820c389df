// Instructions counted with SysTick under QEMU `-icount shift=N` (the
// virtual clock advances exactly 2^N ns per guest instruction and SysTick,
// processor clock source, counts that virtual time): the kernel replay's
// instructions-per-step() and the lab tools' tick cost (docs/PERFORMANCE.md,
// docs/LAB-TOOLS.md). Meaningful only under -icount.
#pragma once

#include <cstdint>

namespace maglev::board::mps2_an500::icount {

// Under `-icount shift=N` QEMU's virtual clock advances exactly 2^N ns per guest
// instruction and SysTick (processor clock source) counts that virtual time, so
// SysTick counts are proportional to instructions executed. The ratio is
// calibrated below on a block of exactly kCalibrationNops NOPs.
struct SysTick {
  volatile std::uint32_t csr;
  volatile std::uint32_t rvr;
  volatile std::uint32_t cvr;
  volatile std::uint32_t calib;
};
inline SysTick& systick() { return *reinterpret_cast<SysTick*>(0xE000E010U); }
inline constexpr std::uint32_t kSysTickMask = 0x00FFFFFFU;

inline void systick_start() {
  systick().csr = 0U;
  systick().rvr = kSysTickMask;
  systick().cvr = 0U;
  systick().csr = 0x5U;  // CLKSOURCE = processor clock, ENABLE, no interrupt
}

inline std::uint32_t systick_now() {
  __asm__ volatile("" ::: "memory");
  const std::uint32_t v = systick().cvr;
  __asm__ volatile("" ::: "memory");
  return v;
}
// SysTick counts down and wraps at 24 bits.
inline std::uint32_t systick_elapsed(std::uint32_t start, std::uint32_t end) {
  return (start - end) & kSysTickMask;
}

inline constexpr std::uint32_t kCalibrationNops = 4096;
__attribute__((noinline)) inline std::uint32_t measure_empty() {
  const std::uint32_t t0 = systick_now();
  const std::uint32_t t1 = systick_now();
  return systick_elapsed(t0, t1);
}
__attribute__((noinline)) inline std::uint32_t measure_nops() {
  const std::uint32_t t0 = systick_now();
  __asm__ volatile(".rept 4096\n\tnop\n\t.endr" ::: "memory");
  const std::uint32_t t1 = systick_now();
  return systick_elapsed(t0, t1);
}

// counts -> instructions: (counts - empty) * nops / (nop_counts - empty), rounded.
struct Calibration {
  std::uint64_t empty_counts = 0;
  std::uint64_t nop_counts = 0;
  bool valid() const { return nop_counts > empty_counts; }
  std::uint64_t instructions(std::uint64_t counts) const {
    if (!valid() || counts <= empty_counts) return 0;
    const std::uint64_t span = nop_counts - empty_counts;
    return ((counts - empty_counts) * kCalibrationNops + span / 2U) / span;
  }
};

// SysTick started and the ratio calibrated; the first runs only warm QEMU's
// translation cache, the last one counts.
inline Calibration start_and_calibrate() {
  systick_start();
  Calibration cal;
  for (int i = 0; i < 4; ++i) {
    cal.empty_counts = measure_empty();
    cal.nop_counts = measure_nops();
  }
  return cal;
}

}  // namespace maglev::board::mps2_an500::icount
