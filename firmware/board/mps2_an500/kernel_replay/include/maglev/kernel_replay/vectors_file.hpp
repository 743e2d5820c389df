// Opening a kernel vectors file (replay_format.hpp) on the target through
// semihosting, checked the same way by every image that reads one (the
// kernel replay, the whole servo tick): header decoded (magic, version,
// record sizes) and the file exactly header + profile + ticks x record long.
// On kOk the handle is positioned after the header (at the profile, if any).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/kernel_replay/replay_format.hpp"
#include "maglev/kernel_replay/semihost_file.hpp"

namespace maglev::kernel_replay {

enum class VectorsOpen : std::uint8_t { kOk = 0, kCannotOpen, kCannotReadHeader, kBadHeader, kBadLength };

inline const char* to_string(VectorsOpen e) {
  switch (e) {
    case VectorsOpen::kOk: return "ok";
    case VectorsOpen::kCannotOpen: return "cannot open the vectors file";
    case VectorsOpen::kCannotReadHeader: return "cannot read the header";
    case VectorsOpen::kBadHeader: return "bad header (magic, version or record sizes differ from this image)";
    case VectorsOpen::kBadLength: return "vectors file length does not match its header";
  }
  return "?";
}

inline VectorsOpen open_vectors(const char* path, int* handle, InputHeader* header) {
  *handle = semihost_open(path, OpenMode::kReadBinary);
  if (*handle < 0) return VectorsOpen::kCannotOpen;
  const long length = semihost_file_length(*handle);
  std::uint8_t header_bytes[kHeaderBytes];
  if (!semihost_read(*handle, header_bytes, sizeof(header_bytes))) return VectorsOpen::kCannotReadHeader;
  if (!decode_header(header_bytes, header)) return VectorsOpen::kBadHeader;
  const auto expected_length = static_cast<long>(kHeaderBytes + header->profile_bytes +
                                                 static_cast<std::size_t>(header->tick_count) * kInputRecordBytes);
  return length == expected_length ? VectorsOpen::kOk : VectorsOpen::kBadLength;
}

}  // namespace maglev::kernel_replay
