#include "maglev/file_flash/file_flash.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

namespace maglev::persistence {

FileFlash::FileFlash(const std::string& path, std::size_t sector_size, std::size_t sector_count)
    : sector_size_(sector_size), sector_count_(sector_count) {
  const long total = static_cast<long>(sector_size * sector_count);
  file_ = std::fopen(path.c_str(), "r+b");
  if (file_ != nullptr) {
    // An existing file of another size is not our flash (a truncated copy, a
    // wrong path, an unrelated file): refuse it and leave it untouched --
    // never "first boot" over somebody's data.
    std::fseek(file_, 0, SEEK_END);
    const long size = std::ftell(file_);
    if (size != total) {
      std::fclose(file_);
      file_ = nullptr;
      error_ = path + ": " + std::to_string(size) + " bytes, a flash file has " + std::to_string(total) +
               " (left untouched; give a new path to start from defaults)";
    }
    return;
  }
  if (errno != ENOENT) {
    error_ = path + ": " + std::strerror(errno);
    return;
  }
  // A new file: all erased (first boot), made durable before use.
  file_ = std::fopen(path.c_str(), "w+b");
  if (file_ == nullptr) {
    error_ = path + ": " + std::strerror(errno);
    return;
  }
  const std::vector<std::uint8_t> erased(sector_size * sector_count, 0xFF);
  if (std::fwrite(erased.data(), 1, erased.size(), file_) != erased.size() || !sync()) {
    error_ = path + ": cannot initialize: " + std::strerror(errno);
    std::fclose(file_);
    file_ = nullptr;
  }
}

bool FileFlash::sync() {
  // fflush hands the data to the kernel; fsync makes it survive a power cut.
  return std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
}

FileFlash::~FileFlash() {
  if (file_ != nullptr) std::fclose(file_);
}

FlashError FileFlash::erase(std::size_t sector) {
  if (file_ == nullptr) return FlashError::kFailed;
  if (sector >= sector_count_) return FlashError::kOutOfRange;
  const std::vector<std::uint8_t> erased(sector_size_, 0xFF);
  std::fseek(file_, static_cast<long>(sector * sector_size_), SEEK_SET);
  if (std::fwrite(erased.data(), 1, erased.size(), file_) != erased.size()) return FlashError::kFailed;
  return sync() ? FlashError::kOk : FlashError::kFailed;
}

FlashError FileFlash::program(std::size_t offset, const std::uint8_t* word) {
  if (file_ == nullptr) return FlashError::kFailed;
  if (offset % kFlashWordBytes != 0) return FlashError::kMisaligned;
  if (offset + kFlashWordBytes > sector_size_ * sector_count_) return FlashError::kOutOfRange;
  std::uint8_t current[kFlashWordBytes];
  if (read(offset, current, kFlashWordBytes) != FlashError::kOk) return FlashError::kFailed;
  for (std::uint8_t b : current) {
    if (b != 0xFF) return FlashError::kNotErased;
  }
  std::fseek(file_, static_cast<long>(offset), SEEK_SET);
  if (std::fwrite(word, 1, kFlashWordBytes, file_) != kFlashWordBytes) return FlashError::kFailed;
  return sync() ? FlashError::kOk : FlashError::kFailed;
}

FlashError FileFlash::read(std::size_t offset, std::uint8_t* out, std::size_t len) const {
  if (file_ == nullptr) return FlashError::kFailed;
  if (offset + len > sector_size_ * sector_count_) return FlashError::kOutOfRange;
  std::fseek(file_, static_cast<long>(offset), SEEK_SET);
  return std::fread(out, 1, len, file_) == len ? FlashError::kOk : FlashError::kFailed;
}

}  // namespace maglev::persistence
