// Modbus RTU server (serial line framing) over the transport-free
// RegisterServer. The UART driver feeds received bytes with a microsecond
// timestamp; a frame ends at 3.5 character times of silence (Modbus over
// Serial Line V1.02, 2.5.1.1): 3.5 * 11 bits / baud, fixed at 1750 us above
// 19200 baud. Heap-free: two static 256-byte buffers (frame being received,
// frame ready to process) owned by the object.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/modbus/register_server.hpp"

namespace maglev::modbus {

inline constexpr std::size_t kMaxRtuFrame = 256;

constexpr std::uint32_t rtu_silence_us(std::uint32_t baud) {
  // 11 bits per character: start + 8 data + parity (or 2nd stop) + stop.
  return baud > 19200 ? 1750u : static_cast<std::uint32_t>((3'500'000ull * 11u + baud - 1u) / baud);
}

struct RtuStats {
  std::uint32_t frames = 0;         // frames addressed to us (or broadcast) with a good CRC
  std::uint32_t crc_errors = 0;
  std::uint32_t short_frames = 0;   // fewer than 4 bytes
  std::uint32_t overruns = 0;       // more than 256 bytes before a silence
  std::uint32_t other_unit = 0;     // good frame for another unit
};

class RtuServer {
 public:
  RtuServer(RegisterServer& registers, std::uint8_t unit_id, std::uint32_t baud);

  // One received byte and the time it arrived (any 32-bit microsecond clock;
  // wrap-around is fine).
  void receive(std::uint8_t byte, std::uint32_t timestamp_us);
  // Call from the UART idle/timer path. When a complete frame is waiting (a
  // silence of t3.5 since its last byte at `now_us`), processes it and writes
  // the reply ADU to `tx` (>= kMaxRtuFrame bytes). Returns its length, 0 for
  // no reply (bad CRC, other unit, broadcast, nothing pending).
  std::size_t poll(std::uint32_t now_us, std::uint8_t* tx);

  // Process one whole ADU (address .. CRC) at once; what poll() does per frame.
  std::size_t process_frame(const std::uint8_t* frame, std::size_t len, std::uint8_t* tx);

  const RtuStats& stats() const { return stats_; }
  std::uint32_t silence_us() const { return silence_us_; }

 private:
  RegisterServer& registers_;
  std::uint8_t unit_id_;
  std::uint32_t silence_us_;
  std::uint8_t rx_[kMaxRtuFrame];
  std::size_t rx_len_ = 0;
  bool rx_overrun_ = false;
  std::uint32_t last_byte_us_ = 0;
  std::uint8_t ready_[kMaxRtuFrame];
  std::size_t ready_len_ = 0;
  bool has_ready_ = false;
  RtuStats stats_;
};

}  // namespace maglev::modbus
