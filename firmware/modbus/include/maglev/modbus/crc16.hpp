// Modbus RTU CRC-16: polynomial 0x8005 reflected (0xA001), initial 0xFFFF,
// transmitted low byte first. Bitwise: 8 shifts per byte is ~100 cycles/byte on
// a Cortex-M7, negligible at 115200 baud, and saves the 512-byte table.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::modbus {

constexpr std::uint16_t crc16(const std::uint8_t* data, std::size_t len, std::uint16_t crc = 0xFFFF) {
  for (std::size_t i = 0; i < len; ++i) {
    crc = static_cast<std::uint16_t>(crc ^ data[i]);
    for (int b = 0; b < 8; ++b) {
      crc = (crc & 1u) != 0 ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001u) : static_cast<std::uint16_t>(crc >> 1);
    }
  }
  return crc;
}

}  // namespace maglev::modbus
