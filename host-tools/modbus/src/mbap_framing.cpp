#include "maglev/modbus_tcp/mbap_framing.hpp"

#include <cstring>

namespace maglev::modbus_tcp {

MbapHead mbap_head(const std::uint8_t* buf, std::size_t used) {
  if (used < kMbapHeaderBytes) return {};
  const std::uint16_t protocol = static_cast<std::uint16_t>((buf[2] << 8) | buf[3]);
  const std::size_t len = static_cast<std::size_t>((buf[4] << 8) | buf[5]);  // unit + PDU
  if (protocol != 0 || len < 2 || len > kMaxAduBytes - 6) return {MbapVerdict::kBroken, 0};
  const std::size_t frame = 6 + len;
  if (used < frame) return {};  // wait for the rest (the server bounds the wait)
  return {MbapVerdict::kFrame, frame};
}

void MbapStream::received(std::size_t n) { used_ += n <= free_bytes() ? n : free_bytes(); }

void MbapStream::pop(std::size_t frame_bytes) {
  if (frame_bytes > used_) frame_bytes = used_;
  std::memmove(buf_, buf_ + frame_bytes, used_ - frame_bytes);
  used_ -= frame_bytes;
}

MbapAnswer mbap_answer(maglev::modbus::RegisterServer& registers, std::uint8_t unit_id, const std::uint8_t* frame,
                       std::size_t frame_bytes, std::uint8_t* reply) {
  const std::uint8_t unit = frame[6];
  if (unit != unit_id && unit != 0xFF && unit != 0) return {true, 0};
  // Modbus/TCP has no broadcast: unit 0 is answered like our own unit.
  const std::size_t pdu =
      registers.handle_pdu(frame + kMbapHeaderBytes, frame_bytes - kMbapHeaderBytes, reply + kMbapHeaderBytes, false);
  if (pdu == 0) return {};
  std::memcpy(reply, frame, 4);  // transaction id, protocol id
  const std::size_t len = pdu + 1;
  reply[4] = static_cast<std::uint8_t>(len >> 8);
  reply[5] = static_cast<std::uint8_t>(len & 0xFF);
  reply[6] = unit;
  return {false, kMbapHeaderBytes + pdu};
}

}  // namespace maglev::modbus_tcp
