// Arm semihosting for the QEMU mps2-an500 board: console output and the exit
// status QEMU returns to the shell. Needs
//   qemu-system-arm -M mps2-an500 -semihosting-config enable=on,target=native
// Without a debugger/QEMU attached the BKPT traps (HardFault): only use this
// on the QEMU board, never on the STM32H743.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::board::mps2_an500 {

// SYS_WRITE0: write a NUL-terminated string to the host console.
void semihost_write(const char* text);
// SYS_WRITEC: one character.
void semihost_write_char(char character);
// Decimal / hexadecimal formatting without printf (no stdio, no heap).
void semihost_write_unsigned(std::uint64_t value);
void semihost_write_signed(std::int64_t value);
void semihost_write_hex(std::uint64_t value, unsigned digits);

// SYS_GET_CMDLINE: QEMU returns "<kernel path> <-append arguments>".
// Copies at most capacity-1 characters plus NUL; returns false on error.
bool semihost_command_line(char* buffer, std::size_t capacity);

// SYS_EXIT_EXTENDED with ADP_Stopped_ApplicationExit: QEMU exits with
// exit_code (0..255) as its own process status. Never returns.
[[noreturn]] void semihost_exit(int exit_code);

}  // namespace maglev::board::mps2_an500
