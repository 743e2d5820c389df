// Arm semihosting file I/O for the mps2-an500 replay image (SYS_OPEN, SYS_READ,
// SYS_WRITE, SYS_FLEN, SYS_CLOSE). QEMU with target=native executes them on
// the host file system, relative to QEMU's working directory.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::kernel_replay {

enum class OpenMode : std::uint32_t { kReadBinary = 1, kWriteBinary = 5 };

// Returns the host handle, or -1.
int semihost_open(const char* path, OpenMode mode);
bool semihost_close(int handle);
// Reads exactly `bytes` bytes; false on error or short read (end of file).
bool semihost_read(int handle, void* buffer, std::size_t bytes);
// Writes exactly `bytes` bytes; false on error.
bool semihost_write_file(int handle, const void* buffer, std::size_t bytes);
// File length in bytes, or -1.
long semihost_file_length(int handle);
// Splits the semihosting command line in place at spaces into at most
// max_words words; returns how many.
int split_words(char* text, const char** words, int max_words);

}  // namespace maglev::kernel_replay
