// MBAP framing of the bench's Modbus TCP server, without sockets: bytes in,
// frames (or a verdict) out, and the reply to one complete frame. TcpServer
// (tcp_server.hpp) feeds each client's bytes through one MbapStream; the
// fuzzer (tests/fuzz/mbap_fuzz.cpp) feeds it arbitrary streams in arbitrary
// segments. Keeping it free of I/O is what lets the framing be fuzzed at
// millions of inputs per minute.
//
// MBAP rules (ours, stricter than the spec allows but never looser):
//   transaction id (2, echoed), protocol id (2, must be 0),
//   length (2, big endian, = unit id + PDU bytes, 2..kMaxAduBytes - 6),
//   unit id (1), PDU (length - 1 bytes).
// A header that breaks them can never be resynchronised on a byte stream, so
// the server closes that connection (MbapVerdict::kBroken).
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/modbus/register_server.hpp"

namespace maglev::modbus_tcp {

inline constexpr std::size_t kMbapHeaderBytes = 7;  // transaction(2) protocol(2) length(2) unit(1)
inline constexpr std::size_t kMaxAduBytes = 260;    // MBAP 7 + PDU 253

enum class MbapVerdict : std::uint8_t {
  kNeedMore,  // the frame at the head is not complete yet (wait for bytes)
  kFrame,     // a complete frame of frame_bytes is at the head
  kBroken,    // the header breaks the MBAP rules: close the connection
};

struct MbapHead {
  MbapVerdict verdict = MbapVerdict::kNeedMore;
  std::size_t frame_bytes = 0;  // kFrame only: MBAP header + PDU
};

// What the first `used` bytes of a client's stream hold.
MbapHead mbap_head(const std::uint8_t* buf, std::size_t used);

// One client's receive buffer: exactly one maximal ADU, so one read is
// bounded and a client cannot make the server buffer more than that.
class MbapStream {
 public:
  std::uint8_t* free_space() { return buf_ + used_; }
  std::size_t free_bytes() const { return kMaxAduBytes - used_; }
  // n bytes were written at free_space() (n <= free_bytes()).
  void received(std::size_t n);
  MbapHead head() const { return mbap_head(buf_, used_); }
  const std::uint8_t* data() const { return buf_; }
  std::size_t used() const { return used_; }
  // Drops the complete frame at the head (frame_bytes from head()).
  void pop(std::size_t frame_bytes);

 private:
  std::uint8_t buf_[kMaxAduBytes] = {};
  std::size_t used_ = 0;
};

struct MbapAnswer {
  bool other_unit = false;     // addressed to another unit: not ours, no reply
  std::size_t reply_bytes = 0;  // 0: no reply
};

// Answers one complete frame (frame_bytes from mbap_head) through the
// register map. Unit ids answered: unit_id, 0xFF (the usual TCP "any unit")
// and 0 (Modbus/TCP has no broadcast, so 0 is answered like our own unit:
// a write always gets its reply). reply must hold kMaxAduBytes; the reply
// echoes transaction id, protocol id and unit id.
MbapAnswer mbap_answer(maglev::modbus::RegisterServer& registers, std::uint8_t unit_id, const std::uint8_t* frame,
                       std::size_t frame_bytes, std::uint8_t* reply);

}  // namespace maglev::modbus_tcp
