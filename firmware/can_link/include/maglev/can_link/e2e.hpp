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

// Slicing-by-8 tables (4 KiB, const: flash on the board). kCrc16Slice[k][b] is
// the CRC register after byte b followed by k zero bytes, starting from 0:
// the CRC is linear, so 8 bytes d0..d7 entered with register c are
// slice[7][d0 ^ c_hi] ^ slice[6][d1 ^ c_lo] ^ slice[5][d2] ^ ... ^ slice[0][d7]
// -- the byte-wise loop's result, 8 independent lookups instead of a chain.
constexpr std::array<std::array<std::uint16_t, 256>, 8> make_crc16_slices() {
  std::array<std::array<std::uint16_t, 256>, 8> t{};
  t[0] = make_crc16_table();
  for (std::size_t k = 1; k < 8; ++k) {
    for (std::size_t i = 0; i < 256; ++i) {
      const std::uint16_t prev = t[k - 1][i];
      t[k][i] = static_cast<std::uint16_t>((prev << 8) ^ t[0][prev >> 8]);
    }
  }
  return t;
}
inline constexpr std::array<std::array<std::uint16_t, 256>, 8> kCrc16Slice = make_crc16_slices();

// The byte-wise definition (one table lookup per byte); the reference that
// crc16_ccitt's slicing must equal (can_codec_test).
constexpr std::uint16_t crc16_ccitt_bytewise(const std::uint8_t* data, std::size_t n, std::uint16_t init) {
  std::uint16_t crc = init;
  for (std::size_t i = 0; i < n; ++i) {
    const auto idx = static_cast<std::uint8_t>((crc >> 8) ^ data[i]);
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrc16Table[idx]);
  }
  return crc;
}
}  // namespace detail

inline constexpr std::uint16_t kCrc16Init = 0xFFFF;

// CRC-16/CCITT-FALSE; chainable (pass the previous result as init). Eight
// bytes per step through the slicing tables (the servo path checks and
// encodes ~4 frames of 20-64 bytes per tick), the tail byte-wise; equal to
// detail::crc16_ccitt_bytewise for every input.
constexpr std::uint16_t crc16_ccitt(const std::uint8_t* data, std::size_t n,
                                    std::uint16_t init = kCrc16Init) {
  std::uint16_t crc = init;
  const auto& t = detail::kCrc16Slice;
  while (n >= 8) {
    crc = static_cast<std::uint16_t>(
        t[7][static_cast<std::uint8_t>(data[0] ^ (crc >> 8))] ^ t[6][static_cast<std::uint8_t>(data[1] ^ (crc & 0xFFu))] ^
        t[5][data[2]] ^ t[4][data[3]] ^ t[3][data[4]] ^ t[2][data[5]] ^ t[1][data[6]] ^ t[0][data[7]]);
    data += 8;
    n -= 8;
  }
  return detail::crc16_ccitt_bytewise(data, n, crc);
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
