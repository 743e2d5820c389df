// End-to-end protection, AUTOSAR E2E Profile 5 style (see docs/CAN.md):
//   byte 0..1  CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection,
//              no final XOR), little endian
//   byte 2     8-bit sequence counter, +1 per transmission, wraps 255 -> 0
//   CRC input: data[2 .. len-1] (counter + payload), then the message's
//              16-bit data ID, low byte then high byte. The data ID is never
//              sent: a frame routed to the wrong decoder fails its CRC even if
//              it has the right length.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace maglev::can {

inline constexpr std::size_t kE2eCrcByte = 0;
inline constexpr std::size_t kE2eCounterByte = 2;
inline constexpr std::size_t kE2eHeaderBytes = 3;

namespace detail {
constexpr std::array<std::uint16_t, 256> make_crc16_table() {
  std::array<std::uint16_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i << 8;
    for (int b = 0; b < 8; ++b) {
      c = (c & 0x8000u) != 0 ? ((c << 1) ^ 0x1021u) : (c << 1);
    }
    t[i] = static_cast<std::uint16_t>(c & 0xFFFFu);
  }
  return t;
}
inline constexpr std::array<std::uint16_t, 256> kCrc16Table = make_crc16_table();
}  // namespace detail

inline constexpr std::uint16_t kCrc16Init = 0xFFFF;

// CRC-16/CCITT-FALSE; chainable (pass the previous result as init).
constexpr std::uint16_t crc16_ccitt(const std::uint8_t* data, std::size_t n,
                                    std::uint16_t init = kCrc16Init) {
  std::uint16_t crc = init;
  for (std::size_t i = 0; i < n; ++i) {
    const auto idx = static_cast<std::uint8_t>((crc >> 8) ^ data[i]);
    crc = static_cast<std::uint16_t>((crc << 8) ^ detail::kCrc16Table[idx]);
  }
  return crc;
}

// The E2E CRC of a frame of `len` bytes protected with `data_id`.
constexpr std::uint16_t e2e_crc(const std::uint8_t* data, std::size_t len, std::uint16_t data_id) {
  std::uint16_t crc = crc16_ccitt(data + kE2eCounterByte, len - kE2eCounterByte);
  const std::uint8_t id_bytes[2] = {static_cast<std::uint8_t>(data_id & 0xFFu),
                                    static_cast<std::uint8_t>(data_id >> 8)};
  return crc16_ccitt(id_bytes, 2, crc);
}

// Writes the counter and then the CRC into an already packed frame.
constexpr void e2e_protect(std::uint8_t* data, std::size_t len, std::uint16_t data_id,
                           std::uint8_t counter) {
  data[kE2eCounterByte] = counter;
  const std::uint16_t crc = e2e_crc(data, len, data_id);
  data[kE2eCrcByte] = static_cast<std::uint8_t>(crc & 0xFFu);
  data[kE2eCrcByte + 1] = static_cast<std::uint8_t>(crc >> 8);
}

constexpr bool e2e_crc_ok(const std::uint8_t* data, std::size_t len, std::uint16_t data_id) {
  const auto sent = static_cast<std::uint16_t>(data[kE2eCrcByte] | (data[kE2eCrcByte + 1] << 8));
  return sent == e2e_crc(data, len, data_id);
}

}  // namespace maglev::can
