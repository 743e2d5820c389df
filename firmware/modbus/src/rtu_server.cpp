#include "maglev/modbus/rtu_server.hpp"

#include "maglev/modbus/crc16.hpp"

namespace maglev::modbus {

RtuServer::RtuServer(RegisterServer& registers, std::uint8_t unit_id, std::uint32_t baud)
    : registers_(registers), unit_id_(unit_id), silence_us_(rtu_silence_us(baud)), rx_{}, ready_{} {}

void RtuServer::receive(std::uint8_t byte, std::uint32_t timestamp_us) {
  if ((rx_len_ > 0 || rx_overrun_) && timestamp_us - last_byte_us_ >= silence_us_) {
    // The silence before this byte closed the previous frame. If poll() has
    // not taken the previous ready frame yet, the older one is dropped: a
    // server that slow could not have answered it in time anyway.
    if (!rx_overrun_) {
      for (std::size_t i = 0; i < rx_len_; ++i) ready_[i] = rx_[i];
      ready_len_ = rx_len_;
      has_ready_ = true;
    }
    rx_len_ = 0;
    rx_overrun_ = false;
  }
  last_byte_us_ = timestamp_us;
  if (rx_overrun_) return;
  if (rx_len_ >= kMaxRtuFrame) {
    rx_overrun_ = true;
    rx_len_ = 0;
    ++stats_.overruns;
    return;
  }
  rx_[rx_len_++] = byte;
}

std::size_t RtuServer::poll(std::uint32_t now_us, std::uint8_t* tx) {
  if (has_ready_) {
    has_ready_ = false;
    return process_frame(ready_, ready_len_, tx);
  }
  if ((rx_len_ > 0 || rx_overrun_) && now_us - last_byte_us_ >= silence_us_) {
    const bool overrun = rx_overrun_;
    const std::size_t len = rx_len_;
    rx_len_ = 0;
    rx_overrun_ = false;
    if (overrun) return 0;
    return process_frame(rx_, len, tx);
  }
  return 0;
}

std::size_t RtuServer::process_frame(const std::uint8_t* frame, std::size_t len, std::uint8_t* tx) {
  if (len < 4) {
    ++stats_.short_frames;
    return 0;
  }
  // CRC over the whole frame including its CRC is zero when intact.
  if (crc16(frame, len) != 0) {
    ++stats_.crc_errors;
    return 0;
  }
  const std::uint8_t unit = frame[0];
  const bool broadcast = unit == 0;
  if (!broadcast && unit != unit_id_) {
    ++stats_.other_unit;
    return 0;
  }
  ++stats_.frames;
  const std::size_t pdu_len = registers_.handle_pdu(frame + 1, len - 3, tx + 1, broadcast);
  if (pdu_len == 0 || broadcast) return 0;
  tx[0] = unit_id_;
  const std::uint16_t crc = crc16(tx, pdu_len + 1);
  tx[pdu_len + 1] = static_cast<std::uint8_t>(crc & 0xFF);
  tx[pdu_len + 2] = static_cast<std::uint8_t>(crc >> 8);
  return pdu_len + 3;
}

}  // namespace maglev::modbus
