// Independent watchdog IWDG1 (RM0433 §45), clocked by the ~32 kHz LSI.
//
// Start sequence (§45.3.2): KR = 0xCCCC starts the counter (and forces the
// LSI on), KR = 0x5555 unlocks PR/RLR, write PR and RLR, wait until SR
// (PVU/RVU/WVU) reads 0 -- the values crossed into the LSI domain -- then
// KR = 0xAAAA reloads the counter. A feed is KR = 0xAAAA.
// Timeout = 4 * 2^PR * (RLR + 1) / f_LSI.
//
// FeedGate: the watchdog is fed only when BOTH the servo loop and the
// communication loop have checked in since the last feed, so a hung Modbus or
// CAN task resets the board just like a hung servo interrupt does.
#pragma once

#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers::iwdg {

struct Timing {
  std::uint32_t pr;   // 0..6: divider 4 << pr
  std::uint32_t rlr;  // 0..4095
  bool valid;
};
constexpr Timing timing_for(std::uint32_t timeout_ms, std::uint32_t lsi_Hz = 32'000) {
  for (std::uint32_t pr = 0; pr <= 6; ++pr) {
    const std::uint64_t counts = static_cast<std::uint64_t>(timeout_ms) * lsi_Hz / (1000ull * (4u << pr));
    if (counts >= 1 && counts <= 4096) return Timing{pr, static_cast<std::uint32_t>(counts - 1), true};
  }
  return Timing{0, 0, false};
}

enum class Status : std::uint8_t { kOk = 0, kBadTimeout, kTimeout };

template <stm32h7::RegisterBus Bus>
class Watchdog {
 public:
  explicit Watchdog(Bus& bus, stm32h7::Addr base = stm32h7::iwdg::kIwdg1) : bus_(bus), base_(base) {}

  Status start(std::uint32_t timeout_ms, std::uint32_t lsi_Hz = 32'000) {
    namespace w = stm32h7::iwdg;
    const Timing t = timing_for(timeout_ms, lsi_Hz);
    if (!t.valid) return Status::kBadTimeout;
    bus_.write32(base_ + w::kKr, w::kKeyStart);
    bus_.write32(base_ + w::kKr, w::kKeyUnlock);
    bus_.write32(base_ + w::kPr, t.pr);
    bus_.write32(base_ + w::kRlr, t.rlr);
    if (!stm32h7::wait_for(bus_, base_ + w::kSr, 0x7u, 0u, 1'000'000)) return Status::kTimeout;
    bus_.write32(base_ + w::kKr, w::kKeyReload);
    return Status::kOk;
  }
  void feed() { bus_.write32(base_ + stm32h7::iwdg::kKr, stm32h7::iwdg::kKeyReload); }

 private:
  Bus& bus_;
  stm32h7::Addr base_;
};

// Both loops check in; service() feeds only if both did, then re-arms.
// servo_ran() is called from the servo ISR, so the flags are volatile and
// service() reads-then-clears each one individually (a check-in racing the
// clear is simply counted in the next window).
class FeedGate {
 public:
  void servo_ran() { servo_ = true; }
  void comms_ran() { comms_ = true; }
  template <typename Dog>
  bool service(Dog& dog) {
    if (!servo_ || !comms_) {
      ++withheld_;
      return false;
    }
    servo_ = false;
    comms_ = false;
    dog.feed();
    ++feeds_;
    return true;
  }
  std::uint32_t feeds() const { return feeds_; }
  std::uint32_t withheld() const { return withheld_; }

 private:
  volatile bool servo_ = false;
  volatile bool comms_ = false;
  std::uint32_t feeds_ = 0;
  std::uint32_t withheld_ = 0;
};

}  // namespace maglev::drivers::iwdg
