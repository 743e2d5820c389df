// STM32H743 embedded flash: sector erase and 256-bit flash-word programming
// (RM0433 §4.3.8-§4.3.10, registers §4.9), for the two configuration banks
// (linker/stm32h743.ld: two 128 KB sectors, __config_bank_a/b_start).
//
// Facts encoded here:
//   * 2 banks x 8 sectors x 128 KB; each bank has its own KEYR/CR/SR/CCR
//     (bank 2 = bank 1 + 0x100).
//   * Unlock: write 0x45670123 then 0xCDEF89AB to FLASH_KEYRx; any other
//     sequence locks CRx until reset, so we check LOCK after.
//   * Programming granularity is a 256-bit flash word (32 bytes, 8 x 32-bit
//     writes to consecutive addresses). With PG set the data goes into the
//     write buffer; the write starts by itself once the buffer is full and
//     QW (queue wait) stays set until it completed.
//   * PSIZE = x32 (10): matches our 32-bit AXI writes and is allowed over the
//     whole 1.62..3.6 V range (x64 would need VDD >= 2.7 V everywhere).
//   * Erase: SER + SNB + PSIZE, then START; wait QW = 0.
//   * Errors in SRx (WRPERR, PGSERR, STRBERR, INCERR, OPERR) are checked after
//     each operation and cleared in CCRx (same bit positions).
// After an erase/program the caller must invalidate the D-cache lines of the
// sector before reading it back (flash reads go through the AXI cache).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::drivers::flash {

enum class Status : std::uint8_t {
  kOk = 0,
  kBadAddress,
  kLocked,            // the unlock sequence did not clear LOCK
  kTimeout,           // QW/BSY never cleared
  kWriteProtected,    // WRPERR
  kSequenceError,     // PGSERR
  kStrobeError,       // STRBERR: flash word written twice without erase
  kInconsistency,     // INCERR: non-consecutive addresses inside one flash word
  kOperationError,    // OPERR
};

inline constexpr std::uint32_t kPsizeX32 = 2;
inline constexpr std::uint32_t kWordsPerFlashWord = stm32h7::memory::kFlashWordBytes / 4;

struct Location {
  int bank;    // 0 or 1
  int sector;  // 0..7
  bool valid;
};
constexpr Location locate(stm32h7::Addr address) {
  if (address < stm32h7::memory::kFlashBank1 || address >= stm32h7::memory::kFlashBank1 + 0x200000u) {
    return Location{0, 0, false};
  }
  const std::uint32_t offset = static_cast<std::uint32_t>(address - stm32h7::memory::kFlashBank1);
  return Location{static_cast<int>(offset / 0x100000u),
                  static_cast<int>((offset % 0x100000u) / stm32h7::memory::kFlashSectorBytes), true};
}

template <stm32h7::RegisterBus Bus>
class Flash {
 public:
  explicit Flash(Bus& bus, std::uint32_t max_polls = 2'000'000) : bus_(bus), max_polls_(max_polls) {}

  Status erase_sector(stm32h7::Addr sector_start) {
    namespace f = stm32h7::flash;
    const Location loc = locate(sector_start);
    if (!loc.valid || (sector_start - stm32h7::memory::kFlashBank1) % stm32h7::memory::kFlashSectorBytes != 0) {
      return Status::kBadAddress;
    }
    const stm32h7::Addr bank = bank_base(loc.bank);
    Status s = prepare(bank);
    if (s != Status::kOk) return s;
    const std::uint32_t cr = stm32h7::field(kPsizeX32, f::kCrPsizeShift) | f::kCrSer |
                             stm32h7::field(static_cast<std::uint32_t>(loc.sector), f::kCrSnbShift);
    bus_.write32(bank + f::kCr, cr);
    bus_.write32(bank + f::kCr, cr | f::kCrStart);
    s = finish(bank);
    stm32h7::modify32(bus_, bank + f::kCr, f::kCrSer | f::kCrSnbMask | f::kCrStart, 0u);
    lock(bank);
    return s;
  }

  // Program one 256-bit flash word at a 32-byte-aligned address.
  Status program_flash_word(stm32h7::Addr address, const std::uint32_t (&words)[kWordsPerFlashWord]) {
    namespace f = stm32h7::flash;
    const Location loc = locate(address);
    if (!loc.valid || address % stm32h7::memory::kFlashWordBytes != 0) return Status::kBadAddress;
    const stm32h7::Addr bank = bank_base(loc.bank);
    Status s = prepare(bank);
    if (s != Status::kOk) return s;
    bus_.write32(bank + f::kCr, stm32h7::field(kPsizeX32, f::kCrPsizeShift) | f::kCrPg);
    stm32h7::barrier(bus_);
    for (std::uint32_t i = 0; i < kWordsPerFlashWord; ++i) bus_.write32(address + 4u * i, words[i]);
    stm32h7::barrier(bus_);  // the 8th write fills the buffer and starts the program
    s = finish(bank);
    stm32h7::modify32(bus_, bank + f::kCr, f::kCrPg, 0u);
    lock(bank);
    return s;
  }

  // Program `bytes` bytes (padded with 0xFF to whole flash words).
  Status program(stm32h7::Addr address, const std::uint8_t* data, std::size_t bytes) {
    for (std::size_t offset = 0; offset < bytes; offset += stm32h7::memory::kFlashWordBytes) {
      std::uint32_t words[kWordsPerFlashWord];
      for (std::uint32_t w = 0; w < kWordsPerFlashWord; ++w) {
        std::uint32_t v = 0;
        for (std::uint32_t b = 0; b < 4; ++b) {
          const std::size_t i = offset + 4u * w + b;
          v |= static_cast<std::uint32_t>(i < bytes ? data[i] : 0xFFu) << (8u * b);
        }
        words[w] = v;
      }
      const Status s = program_flash_word(address + offset, words);
      if (s != Status::kOk) return s;
    }
    return Status::kOk;
  }

 private:
  static constexpr stm32h7::Addr bank_base(int bank) {
    return stm32h7::flash::kBase + (bank == 0 ? 0u : stm32h7::flash::kBank2Offset);
  }
  Status prepare(stm32h7::Addr bank) {
    namespace f = stm32h7::flash;
    if (!stm32h7::wait_for(bus_, bank + f::kSr, f::kSrQw | f::kSrBsy, 0u, max_polls_)) return Status::kTimeout;
    if ((bus_.read32(bank + f::kCr) & f::kCrLock) != 0) {
      bus_.write32(bank + f::kKeyr, f::kKey1);
      bus_.write32(bank + f::kKeyr, f::kKey2);
      if ((bus_.read32(bank + f::kCr) & f::kCrLock) != 0) return Status::kLocked;
    }
    bus_.write32(bank + f::kCcr, f::kSrAllErrors | f::kSrEop);  // start from clean flags
    return Status::kOk;
  }
  Status finish(stm32h7::Addr bank) {
    namespace f = stm32h7::flash;
    if (!stm32h7::wait_for(bus_, bank + f::kSr, f::kSrQw, 0u, max_polls_)) return Status::kTimeout;
    const std::uint32_t sr = bus_.read32(bank + f::kSr);
    bus_.write32(bank + f::kCcr, f::kSrAllErrors | f::kSrEop);
    if ((sr & f::kSrWrperr) != 0) return Status::kWriteProtected;
    if ((sr & f::kSrPgserr) != 0) return Status::kSequenceError;
    if ((sr & f::kSrStrberr) != 0) return Status::kStrobeError;
    if ((sr & f::kSrIncerr) != 0) return Status::kInconsistency;
    if ((sr & f::kSrOperr) != 0) return Status::kOperationError;
    return Status::kOk;
  }
  void lock(stm32h7::Addr bank) { stm32h7::modify32(bus_, bank + stm32h7::flash::kCr, 0u, stm32h7::flash::kCrLock); }

  Bus& bus_;
  std::uint32_t max_polls_;
};

}  // namespace maglev::drivers::flash
