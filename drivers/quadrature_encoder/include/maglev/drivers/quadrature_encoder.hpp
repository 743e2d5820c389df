// Quadrature inputs from the interferometer electronics (A/B per axis plus a
// measurement-signal-loss line), counted by STM32 timers in encoder mode 3
// (x4: both edges of TI1 and TI2, RM0433 §38.3.20 "Encoder interface mode"):
//   SMCR.SMS = 011, CCMR1.CC1S = CC2S = 01 (IC1 on TI1, IC2 on TI2) with the
//   input filter IC1F/IC2F, CCER polarity non-inverted, ARR = full range.
// TIM2 and TIM5 have 32-bit counters: their CNT is the count. The third axis
// sits on a 16-bit timer (TIM3) and is extended to 32 bits in software.
//
// 16-bit extension: extended += (int16_t)(cnt - last_cnt). That is exact as
// long as the counter moves by less than 32768 counts between two calls of
// update(). At 0.618 nm per count and the 2.5 kHz servo rate that alone would
// cap the speed at ~50 mm/s, so the board also calls update() from the
// timer's own interrupts at four points of the 16-bit range (update event at
// the wrap, CC3 at 0x4000, CC4 at 0xC000 -- channels 3/4 are free in encoder
// mode): consecutive calls are then <= 0x4000 counts apart plus the
// interrupt latency, whatever the speed, as long as all callers run at the
// same interrupt priority (they do: the servo priority).
//
// Signal loss: the electronics' loss output (active level configurable) is
// sampled every update and LATCHED: a count after a beam interruption is no
// longer referenced to home, so the flag stays until clear_signal_loss()
// (after re-homing).
#pragma once

#include <cstdint>

#include "maglev/drivers/bus.hpp"
#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers {

// Pure 16 -> 32-bit extender (no hardware), so the arithmetic is testable alone.
class CounterExtender16 {
 public:
  void reset(std::uint16_t hardware_count, std::uint32_t extended = 0) {
    last_ = hardware_count;
    extended_ = extended;
  }
  std::uint32_t update(std::uint16_t hardware_count) {
    const auto delta = static_cast<std::int16_t>(static_cast<std::uint16_t>(hardware_count - last_));
    last_ = hardware_count;
    extended_ += static_cast<std::uint32_t>(static_cast<std::int32_t>(delta));
    return extended_;
  }
  std::uint32_t value() const { return extended_; }

 private:
  std::uint16_t last_ = 0;
  std::uint32_t extended_ = 0;
};

struct QuadratureConfig {
  stm32h7::Addr timer;      // stm32h7::tim::kTim2 ...
  bool counter_32bit;       // TIM2/TIM5: true; TIM3/TIM4/TIM1/TIM8: false
  std::uint8_t input_filter;  // ICxF code, 0..15 (1 = fCK_INT, N = 2)
  bool loss_active_high;
};

// LossPin: the loss line's pin type. InputPin (the interface) by default;
// the board names its concrete (final) pin so the per-tick read is a direct,
// inlined register load instead of a virtual call.
template <stm32h7::RegisterBus Bus, typename LossPin = InputPin>
class QuadratureEncoder {
 public:
  QuadratureEncoder(Bus& bus, const QuadratureConfig& config, LossPin& signal_loss)
      : bus_(bus), config_(config), loss_(signal_loss) {}

  void init() {
    namespace t = stm32h7::tim;
    const stm32h7::Addr b = config_.timer;
    const std::uint32_t f = config_.input_filter & 0xFu;
    bus_.write32(b + t::kCr1, 0u);
    bus_.write32(b + t::kSmcr, t::kSmsEncoderMode3);
    bus_.write32(b + t::kCcmr1, stm32h7::field(1u, 0) | stm32h7::field(f, 4) | stm32h7::field(1u, 8) |
                                    stm32h7::field(f, 12));
    bus_.write32(b + t::kCcer, 0u);  // CC1P = CC2P = 0: non-inverted, rising-edge reference
    bus_.write32(b + t::kPsc, 0u);
    bus_.write32(b + t::kArr, config_.counter_32bit ? 0xFFFFFFFFu : 0xFFFFu);
    if (!config_.counter_32bit) {
      // Extension points: update at the wrap, CC3/CC4 at the quarter points.
      bus_.write32(b + t::kCcr3, 0x4000u);
      bus_.write32(b + t::kCcr4, 0xC000u);
      bus_.write32(b + t::kDier, stm32h7::bit(0) | stm32h7::bit(3) | stm32h7::bit(4));
    }
    bus_.write32(b + t::kCnt, 0u);
    bus_.write32(b + t::kCr1, t::kCr1Cen);
    extender_.reset(0, 0);
    signal_lost_ = false;
  }

  // Read the count (and sample the loss line). Call from the servo ISR and,
  // for a 16-bit timer, from its UIF/CC3IF/CC4IF interrupt (on_timer_irq()).
  std::uint32_t update() {
    const std::uint32_t cnt = bus_.read32(config_.timer + stm32h7::tim::kCnt);
    if (loss_.read() == config_.loss_active_high) signal_lost_ = true;
    if (config_.counter_32bit) return cnt;
    return extender_.update(static_cast<std::uint16_t>(cnt & 0xFFFFu));
  }

  // The 16-bit timer's interrupt: clear the flags (rc_w0), then extend.
  void on_timer_irq() {
    bus_.write32(config_.timer + stm32h7::tim::kSr, 0u);
    (void)update();
  }

  bool signal_lost() const { return signal_lost_; }
  void clear_signal_loss() { signal_lost_ = false; }

 private:
  Bus& bus_;
  QuadratureConfig config_;
  LossPin& loss_;
  CounterExtender16 extender_{};
  bool signal_lost_ = false;
};

}  // namespace maglev::drivers
