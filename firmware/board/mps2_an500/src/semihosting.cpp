#include "maglev/board/mps2_an500/semihosting.hpp"

namespace maglev::board::mps2_an500 {
namespace {

// Semihosting operation numbers (Arm "Semihosting for AArch32 and AArch64").
enum class SemihostOp : std::uint32_t {
  kWriteC = 0x03,
  kWrite0 = 0x04,
  kGetCmdline = 0x15,
  kExit = 0x18,
  kExitExtended = 0x20,
};
// angel_SWIreason_ReportException reason: the application exited normally.
constexpr std::uint32_t kAdpStoppedApplicationExit = 0x20026U;

// M-profile semihosting trap: BKPT 0xAB, op in r0, parameter in r1, result r0.
std::uint32_t semihost_call(SemihostOp op, const void* parameter) {
  register std::uint32_t r0 __asm__("r0") = static_cast<std::uint32_t>(op);
  register const void* r1 __asm__("r1") = parameter;
  __asm__ volatile("bkpt #0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace

void semihost_write(const char* text) { semihost_call(SemihostOp::kWrite0, text); }

void semihost_write_char(char character) { semihost_call(SemihostOp::kWriteC, &character); }

void semihost_write_unsigned(std::uint64_t value) {
  char digits[21];
  std::size_t index = sizeof(digits) - 1U;
  digits[index] = '\0';
  do {
    --index;
    digits[index] = static_cast<char>('0' + static_cast<int>(value % 10U));
    value /= 10U;
  } while (value != 0U && index > 0U);
  semihost_write(&digits[index]);
}

void semihost_write_signed(std::int64_t value) {
  if (value < 0) {
    semihost_write_char('-');
    // Two's complement magnitude; correct for INT64_MIN too.
    semihost_write_unsigned(~static_cast<std::uint64_t>(value) + 1U);
  } else {
    semihost_write_unsigned(static_cast<std::uint64_t>(value));
  }
}

void semihost_write_hex(std::uint64_t value, unsigned digits) {
  char text[19] = {'0', 'x'};
  if (digits > 16U) {
    digits = 16U;
  }
  for (unsigned i = 0; i < digits; ++i) {
    const unsigned shift = 4U * (digits - 1U - i);
    const auto nibble = static_cast<unsigned>((value >> shift) & 0xFU);
    text[2U + i] = "0123456789abcdef"[nibble];
  }
  text[2U + digits] = '\0';
  semihost_write(text);
}

bool semihost_command_line(char* buffer, std::size_t capacity) {
  if (buffer == nullptr || capacity == 0U) {
    return false;
  }
  struct {
    char* data;
    std::size_t length;
  } block{buffer, capacity};
  const std::uint32_t result = semihost_call(SemihostOp::kGetCmdline, &block);
  if (result != 0U) {
    buffer[0] = '\0';
    return false;
  }
  buffer[block.length < capacity ? block.length : capacity - 1U] = '\0';
  return true;
}

void semihost_exit(int exit_code) {
  const std::uint32_t block[2] = {kAdpStoppedApplicationExit, static_cast<std::uint32_t>(exit_code)};
  semihost_call(SemihostOp::kExitExtended, block);
  // Hosts without SYS_EXIT_EXTENDED: plain SYS_EXIT only says success/failure.
  semihost_call(SemihostOp::kExit,
                reinterpret_cast<const void*>(exit_code == 0 ? kAdpStoppedApplicationExit : 0x20023U));
  for (;;) {
  }
}

}  // namespace maglev::board::mps2_an500
