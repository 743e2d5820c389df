// Host build only: flash kept in a file, with the same rules as RamFlash
// (erased = 0xFF, one program per 32-byte word between erases), so the bench
// and stagectl sessions keep their configuration across runs.
#pragma once

#include <cstdio>
#include <string>

#include "maglev/persistence/flash.hpp"

namespace maglev::persistence {

class FileFlash final : public Flash {
 public:
  // Opens `path`, creating it (all erased) when missing or of the wrong size.
  FileFlash(const std::string& path, std::size_t sector_size, std::size_t sector_count);
  ~FileFlash();
  FileFlash(const FileFlash&) = delete;
  FileFlash& operator=(const FileFlash&) = delete;

  bool ok() const { return file_ != nullptr; }
  std::size_t sector_size() const override { return sector_size_; }
  std::size_t sector_count() const override { return sector_count_; }
  FlashError erase(std::size_t sector) override;
  FlashError program(std::size_t offset, const std::uint8_t* word) override;
  FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const override;

 private:
  std::FILE* file_ = nullptr;
  std::size_t sector_size_;
  std::size_t sector_count_;
};

}  // namespace maglev::persistence
