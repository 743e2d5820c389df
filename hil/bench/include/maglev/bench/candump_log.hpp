// The bench's CAN traffic as a candump log (the format `candump -l` writes
// and `canplayer`, python-can's CanutilsLogReader and can-utils' log2asc
// read): one frame per line,
//   (SECONDS.MICROSECONDS) IFACE ID#DATA          classical CAN
//   (SECONDS.MICROSECONDS) IFACE ID##FDATA        CAN FD, F = flags nibble
// ID: 3 hex digits (11-bit) or 8 (29-bit), DATA: 2 upper-case hex digits per
// byte. Timestamps are the bench's simulated time, so a lockstep run's log
// is the same file every time.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "maglev/can_port/can_port.hpp"

namespace maglev::bench {

// One log line (without the newline) for `frame` seen at time_us on iface.
std::string format_candump_line(std::uint64_t time_us, const std::string& iface, const can::CanFrame& frame);

class CandumpLogWriter {
 public:
  CandumpLogWriter() = default;
  CandumpLogWriter(const CandumpLogWriter&) = delete;
  CandumpLogWriter& operator=(const CandumpLogWriter&) = delete;
  ~CandumpLogWriter();

  // false: *error says why (nothing is open).
  bool open(const std::string& path, std::string iface, std::string* error);
  bool is_open() const { return f_ != nullptr; }
  // Error frames are not data and are not logged (candump -l logs them only
  // with -e; the bench's buses never carry them).
  void write(std::uint64_t time_us, const can::CanFrame& frame);
  // Flushes and closes; false when any write failed (*error says so).
  bool close(std::string* error);
  std::uint64_t frames() const { return frames_; }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  std::string iface_;
  std::uint64_t frames_ = 0;
  bool failed_ = false;
};

}  // namespace maglev::bench
