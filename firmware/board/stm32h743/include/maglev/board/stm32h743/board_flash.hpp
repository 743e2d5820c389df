// persistence::Flash over the STM32H743 embedded flash (drivers/flash): the
// two configuration sectors (linker/stm32h743.ld: bank 2 sectors 0 and 1,
// __config_bank_a_start / __config_bank_b_start) appear to ConfigStore as
// sectors 0 (bank A) and 1 (bank B) of one 2 x 128 KB device; offsets are
// sector * 128 KB + offset in the sector.
//
// Reads go through the bus (memory-mapped flash). After an erase or program
// the D-cache lines of the sector are invalidated (hook; flash is cacheable)
// so ConfigStore reads back what the array holds, not stale cache lines.
// The configuration sectors are in flash bank 2 and the code runs from bank 1
// (and ITCM): the servo interrupt keeps running during an erase
// (read-while-write across banks, RM0433 §4.3.7).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/drivers/flash.hpp"
#include "maglev/persistence/flash.hpp"
#include "maglev/stm32h7/register_bus.hpp"
#include "maglev/stm32h7/registers.hpp"

namespace maglev::board::stm32h743 {

template <stm32h7::RegisterBus Bus>
class BoardFlash final : public persistence::Flash {
 public:
  using InvalidateFn = void (*)(stm32h7::Addr start, std::size_t bytes);

  BoardFlash(Bus& bus, drivers::flash::Flash<Bus>& flash, stm32h7::Addr bank_a, stm32h7::Addr bank_b,
             InvalidateFn invalidate_fn = nullptr)
      : bus_(bus), flash_(flash), sector_{bank_a, bank_b}, invalidate_(invalidate_fn) {}

  std::size_t sector_size() const override { return stm32h7::memory::kFlashSectorBytes; }
  std::size_t sector_count() const override { return 2; }

  persistence::FlashError erase(std::size_t sector) override {
    if (sector >= 2) return persistence::FlashError::kOutOfRange;
    const drivers::flash::Status s = flash_.erase_sector(sector_[sector]);
    invalidate(sector_[sector], sector_size());
    return map(s);
  }

  persistence::FlashError program(std::size_t offset, const std::uint8_t* word) override {
    stm32h7::Addr address = 0;
    if (!to_address(offset, persistence::kFlashWordBytes, address)) return persistence::FlashError::kOutOfRange;
    if (offset % persistence::kFlashWordBytes != 0) return persistence::FlashError::kMisaligned;
    // ECC flash: a word is programmed once between erases.
    for (std::size_t i = 0; i < persistence::kFlashWordBytes; i += 4) {
      if (bus_.read32(address + static_cast<stm32h7::Addr>(i)) != 0xFFFFFFFFu) return persistence::FlashError::kNotErased;
    }
    std::uint32_t words[drivers::flash::kWordsPerFlashWord];
    for (std::size_t w = 0; w < drivers::flash::kWordsPerFlashWord; ++w) {
      words[w] = static_cast<std::uint32_t>(word[4 * w]) | (static_cast<std::uint32_t>(word[4 * w + 1]) << 8) |
                 (static_cast<std::uint32_t>(word[4 * w + 2]) << 16) |
                 (static_cast<std::uint32_t>(word[4 * w + 3]) << 24);
    }
    const drivers::flash::Status s = flash_.program_flash_word(address, words);
    invalidate(address, persistence::kFlashWordBytes);
    return map(s);
  }

  persistence::FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const override {
    stm32h7::Addr address = 0;
    if (!to_address(offset, len, address)) return persistence::FlashError::kOutOfRange;
    // Whole aligned 32-bit reads (the AXI flash interface), bytes picked out.
    std::size_t i = 0;
    while (i < len) {
      const stm32h7::Addr a = address + static_cast<stm32h7::Addr>(i);
      const stm32h7::Addr aligned = a & ~stm32h7::Addr{3};
      const std::uint32_t v = bus_.read32(aligned);
      for (stm32h7::Addr b = a - aligned; b < 4 && i < len; ++b, ++i) {
        out[i] = static_cast<std::uint8_t>(v >> (8u * b));
      }
    }
    return persistence::FlashError::kOk;
  }

 private:
  bool to_address(std::size_t offset, std::size_t len, stm32h7::Addr& address) const {
    const std::size_t sector = offset / sector_size();
    const std::size_t within = offset % sector_size();
    if (sector >= 2 || within + len > sector_size()) return false;
    address = sector_[sector] + static_cast<stm32h7::Addr>(within);
    return true;
  }
  void invalidate(stm32h7::Addr a, std::size_t n) const {
    if (invalidate_ != nullptr) invalidate_(a, n);
  }
  static persistence::FlashError map(drivers::flash::Status s) {
    switch (s) {
      case drivers::flash::Status::kOk: return persistence::FlashError::kOk;
      case drivers::flash::Status::kBadAddress: return persistence::FlashError::kOutOfRange;
      case drivers::flash::Status::kStrobeError: return persistence::FlashError::kNotErased;
      default: return persistence::FlashError::kFailed;
    }
  }

  Bus& bus_;
  drivers::flash::Flash<Bus>& flash_;
  stm32h7::Addr sector_[2];
  InvalidateFn invalidate_;
};

}  // namespace maglev::board::stm32h743
