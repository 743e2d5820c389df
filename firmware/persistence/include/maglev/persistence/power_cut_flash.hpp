// Flash that loses power after `budget` erase/program operations: the
// brown-out during a configuration save (persistence tests, the fault
// campaign). The operation that meets the cut is TORN: a program writes only
// the first half of its word with garbage in the second; an erase erases
// only half the sector. Everything after the cut fails. Heap-free.
#pragma once

#include <cstring>

#include "maglev/persistence/flash.hpp"

namespace maglev::persistence {

class PowerCutFlash final : public Flash {
 public:
  PowerCutFlash(RamFlash& inner, long budget) : inner_(inner), budget_(budget) {}
  std::size_t sector_size() const override { return inner_.sector_size(); }
  std::size_t sector_count() const override { return inner_.sector_count(); }
  FlashError erase(std::size_t sector) override {
    if (dead_) return FlashError::kFailed;
    ++ops;
    if (budget_-- == 0) {
      dead_ = true;
      std::memset(inner_.data() + sector * inner_.sector_size(), 0xFF, inner_.sector_size() / 2);
      return FlashError::kFailed;
    }
    return inner_.erase(sector);
  }
  FlashError program(std::size_t offset, const std::uint8_t* word) override {
    if (dead_) return FlashError::kFailed;
    ++ops;
    if (budget_-- == 0) {
      dead_ = true;
      std::uint8_t torn[kFlashWordBytes];
      for (std::size_t i = 0; i < sizeof torn; ++i) torn[i] = i < 16 ? word[i] : static_cast<std::uint8_t>(0x5A ^ i);
      inner_.program(offset, torn);
      return FlashError::kFailed;
    }
    return inner_.program(offset, word);
  }
  FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const override {
    return inner_.read(offset, out, len);
  }
  bool dead() const { return dead_; }
  long ops = 0;  // operations attempted, the torn one included

 private:
  RamFlash& inner_;
  long budget_;
  bool dead_ = false;
};

}  // namespace maglev::persistence
