// The flash the configuration lives in, as small as persistence needs it:
// sector erase, 32-byte flash-word programming (the STM32H7's 256-bit word
// with ECC: a word is programmed once between erases), and read.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::persistence {

inline constexpr std::size_t kFlashWordBytes = 32;

enum class FlashError : std::uint8_t {
  kOk,
  kOutOfRange,
  kMisaligned,   // offset not on a 32-byte flash word
  kNotErased,    // programming a word that is not all 0xFF (ECC flash forbids it)
  kFailed,       // hardware/power failure
};

class Flash {
 public:
  virtual std::size_t sector_size() const = 0;
  virtual std::size_t sector_count() const = 0;
  virtual FlashError erase(std::size_t sector) = 0;
  // Program one flash word (kFlashWordBytes) at `offset` (absolute, aligned).
  virtual FlashError program(std::size_t offset, const std::uint8_t* word) = 0;
  virtual FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const = 0;

 protected:
  Flash() = default;
  Flash(const Flash&) = default;
  Flash& operator=(const Flash&) = default;
  ~Flash() = default;
};

// Flash in caller-owned RAM (tests, the QEMU image). Enforces the same rules
// as the real part: erased = 0xFF, one program per word between erases.
class RamFlash final : public Flash {
 public:
  RamFlash(std::uint8_t* storage, std::size_t sector_size, std::size_t sector_count);
  std::size_t sector_size() const override { return sector_size_; }
  std::size_t sector_count() const override { return sector_count_; }
  FlashError erase(std::size_t sector) override;
  FlashError program(std::size_t offset, const std::uint8_t* word) override;
  FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const override;
  std::uint8_t* data() { return storage_; }

 private:
  std::uint8_t* storage_;
  std::size_t sector_size_;
  std::size_t sector_count_;
};

}  // namespace maglev::persistence
