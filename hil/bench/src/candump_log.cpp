#include "maglev/bench/candump_log.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace maglev::bench {

namespace {
constexpr char kHex[] = "0123456789ABCDEF";
// The FD flags nibble: Linux's canfd_frame.flags bits, which CanFrame::flags
// uses on purpose (can_port.hpp). Only BRS and ESI: the "##" already says FD,
// and a FDF bit in the nibble is newer than Debian 12's can-utils and kernel.
constexpr std::uint8_t kFdNibbleMask = can::kFlagBrs | can::kFlagEsi;
}  // namespace

std::string format_candump_line(std::uint64_t time_us, const std::string& iface, const can::CanFrame& frame) {
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "(%010llu.%06llu) ", static_cast<unsigned long long>(time_us / 1000000u),
                static_cast<unsigned long long>(time_us % 1000000u));
  std::string line = stamp;
  line += iface;
  line += ' ';
  const bool extended = (frame.flags & can::kFlagExtendedId) != 0;
  const int digits = extended ? 8 : 3;
  const std::uint32_t id = frame.id & (extended ? 0x1FFFFFFFu : 0x7FFu);
  for (int d = digits - 1; d >= 0; --d) line += kHex[(id >> (4 * d)) & 0xFu];
  line += '#';
  if ((frame.flags & can::kFlagFd) != 0) {
    line += '#';
    line += kHex[frame.flags & kFdNibbleMask];
  }
  const std::uint8_t len = frame.len <= can::kMaxCanFdPayload ? frame.len : can::kMaxCanFdPayload;
  for (std::uint8_t i = 0; i < len; ++i) {
    line += kHex[frame.data[i] >> 4];
    line += kHex[frame.data[i] & 0xFu];
  }
  return line;
}

CandumpLogWriter::~CandumpLogWriter() {
  std::string ignored;
  (void)close(&ignored);
}

bool CandumpLogWriter::open(const std::string& path, std::string iface, std::string* error) {
  std::string ignored;
  (void)close(&ignored);
  // Like --out: the log may go into the run's not yet created directory.
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  f_ = std::fopen(path.c_str(), "w");
  if (f_ == nullptr) {
    *error = "cannot write CAN log " + path + ": " + std::strerror(errno);
    return false;
  }
  path_ = path;
  iface_ = std::move(iface);
  frames_ = 0;
  failed_ = false;
  return true;
}

void CandumpLogWriter::write(std::uint64_t time_us, const can::CanFrame& frame) {
  if (f_ == nullptr || (frame.flags & can::kFlagErrorFrame) != 0) return;
  const std::string line = format_candump_line(time_us, iface_, frame);
  if (std::fputs(line.c_str(), f_) < 0 || std::fputc('\n', f_) == EOF) failed_ = true;
  ++frames_;
}

bool CandumpLogWriter::close(std::string* error) {
  if (f_ == nullptr) return true;
  const bool closed = std::fclose(f_) == 0;
  f_ = nullptr;
  if (failed_ || !closed) {
    *error = "writing CAN log " + path_ + " failed";
    return false;
  }
  return true;
}

}  // namespace maglev::bench
