// Reset and fault handling for the QEMU mps2-an500 board.
//
// Reset_Handler (src/startup.cpp): FPU access on (CPACR CP10/CP11), copy
// .data from its load image, zero .bss, run .preinit_array/.init_array
// (static constructors), call main(), then report main's return value as the
// semihosting exit status. Any fault prints its name and the stacked PC and
// exits with kFaultExitCode, so a crashing test image fails its ctest.
#pragma once

#include <cstdint>

namespace maglev::board::mps2_an500 {

// QEMU exit status of an image that took a fault / called abort().
inline constexpr int kFaultExitCode = 125;

// Linker-script symbols (linker/mps2-an500.ld) exposed for self-checks.
struct DataImage {
  const std::uint8_t* ram_begin;   // __data_start__
  const std::uint8_t* ram_end;     // __data_end__
  const std::uint8_t* load_begin;  // __data_load__ (flash copy)
};
DataImage data_image();

}  // namespace maglev::board::mps2_an500
