#include "maglev/kernel_replay/semihost_file.hpp"

#include <cstring>

namespace maglev::kernel_replay {
namespace {

// Semihosting operation numbers (Arm "Semihosting for AArch32 and AArch64").
enum class Op : std::uint32_t { kOpen = 0x01, kClose = 0x02, kWrite = 0x05, kRead = 0x06, kFlen = 0x0C };

// M-profile trap: BKPT 0xAB, operation in r0, parameter block in r1, result in r0.
std::uint32_t call(Op op, const void* parameter) {
  register std::uint32_t r0 __asm__("r0") = static_cast<std::uint32_t>(op);
  register const void* r1 __asm__("r1") = parameter;
  __asm__ volatile("bkpt #0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

std::uint32_t address_of(const void* p) { return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(p)); }

}  // namespace

int semihost_open(const char* path, OpenMode mode) {
  const std::uint32_t block[3] = {address_of(path), static_cast<std::uint32_t>(mode),
                                  static_cast<std::uint32_t>(std::strlen(path))};
  return static_cast<int>(call(Op::kOpen, block));
}

bool semihost_close(int handle) {
  const std::uint32_t block[1] = {static_cast<std::uint32_t>(handle)};
  return call(Op::kClose, block) == 0U;
}

bool semihost_read(int handle, void* buffer, std::size_t bytes) {
  // SYS_READ returns the number of bytes NOT read.
  const std::uint32_t block[3] = {static_cast<std::uint32_t>(handle), address_of(buffer),
                                  static_cast<std::uint32_t>(bytes)};
  return call(Op::kRead, block) == 0U;
}

bool semihost_write_file(int handle, const void* buffer, std::size_t bytes) {
  // SYS_WRITE returns the number of bytes NOT written.
  const std::uint32_t block[3] = {static_cast<std::uint32_t>(handle), address_of(buffer),
                                  static_cast<std::uint32_t>(bytes)};
  return call(Op::kWrite, block) == 0U;
}

long semihost_file_length(int handle) {
  const std::uint32_t block[1] = {static_cast<std::uint32_t>(handle)};
  return static_cast<long>(static_cast<std::int32_t>(call(Op::kFlen, block)));
}

int split_words(char* p, const char** words, int max_words) {
  int n = 0;
  while (*p != '\0' && n < max_words) {
    while (*p == ' ') ++p;
    if (*p == '\0') break;
    words[n++] = p;
    while (*p != '\0' && *p != ' ') ++p;
    if (*p == ' ') *p++ = '\0';
  }
  return n;
}

}  // namespace maglev::kernel_replay
