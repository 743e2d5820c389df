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
  // Opens `path`; creates it (all erased: first boot) only when it does not
  // exist. A file of another size is refused untouched (ok() false, error()
  // says why). Every erase and program is fsync'ed.
  FileFlash(const std::string& path, std::size_t sector_size, std::size_t sector_count);
  ~FileFlash();
  FileFlash(const FileFlash&) = delete;
  FileFlash& operator=(const FileFlash&) = delete;

  bool ok() const { return file_ != nullptr; }
  const std::string& error() const { return error_; }
  std::size_t sector_size() const override { return sector_size_; }
  std::size_t sector_count() const override { return sector_count_; }
  FlashError erase(std::size_t sector) override;
  FlashError program(std::size_t offset, const std::uint8_t* word) override;
  FlashError read(std::size_t offset, std::uint8_t* out, std::size_t len) const override;

 private:
  bool sync();
  std::FILE* file_ = nullptr;
  std::string error_;
  std::size_t sector_size_;
  std::size_t sector_count_;
};

}  // namespace maglev::persistence
