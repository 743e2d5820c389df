// The one CAN transport interface. Every transport implements it: the STM32
// FDCAN driver (board), SocketCAN (host), the in-process virtual bus (host).
// The codec in firmware/can_link never sees a transport; the lockstep and
// real-time loops only see this interface.
//
// Heap-free, exception-free, RTTI-free: compiles for arm-none-eabi. The
// destructor is protected and non-virtual so no deleting destructor (and so
// no operator delete) is ever pulled into a target image; host code that owns
// ports through a pointer uses maglev::can::OwnedCanPort (host_can_port.hpp).
// Concrete transports should be declared `final`.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::can {

inline constexpr std::size_t kMaxCanFdPayload = 64;

// CanFrame::flags. The low three bits are Linux's canfd_frame.flags bits on
// purpose (CANFD_BRS 0x01, CANFD_ESI 0x02, CANFD_FDF 0x04), so SocketCAN maps
// them 1:1; the FDCAN driver maps them to its TX/RX buffer element bits.
enum CanFrameFlag : std::uint8_t {
  kFlagBrs = 0x01,          // bit-rate switch: data phase at the data bit rate
  kFlagEsi = 0x02,          // error state indicator (transmitter error passive)
  kFlagFd = 0x04,           // FD format (FDF). Clear = classical CAN 2.0 frame
  kFlagExtendedId = 0x40,   // 29-bit identifier (ours; the catalog uses 11-bit)
  kFlagErrorFrame = 0x80,   // receive only: an error frame/condition report, not data
};

struct CanFrame {
  std::uint32_t id;   // 11-bit (or 29-bit with kFlagExtendedId), no flag bits
  std::uint8_t len;   // payload bytes: 0..8, 12, 16, 20, 24, 32, 48, 64
  std::uint8_t flags; // CanFrameFlag
  std::uint8_t data[kMaxCanFdPayload];
};

enum class PortStatus : std::uint8_t {
  kOk = 0,
  kTimeout,      // receive: nothing arrived in time
  kTxFull,       // send: transmit queue/mailboxes full, frame not queued
  kBusOff,       // controller is bus-off
  kBadFrame,     // send: len/flags not transmittable (e.g. len 13, FD len on a classical port)
  kIoError,      // anything else from the hardware/OS
  kClosed,       // port not open / peer gone
};

// Monotonic counters; they wrap at 2^32. A transport increments only what it
// can observe (e.g. virtual bus never sees bus errors).
struct PortCounters {
  std::uint32_t tx_frames = 0;     // frames accepted by send()
  std::uint32_t rx_frames = 0;     // data frames returned by receive()
  std::uint32_t tx_errors = 0;     // send() returned non-kOk
  std::uint32_t rx_timeouts = 0;   // receive() returned kTimeout
  std::uint32_t rx_overruns = 0;   // frames lost because the RX queue overflowed
  std::uint32_t error_frames = 0;  // bus error frames / error-state changes observed
  std::uint32_t rx_errors = 0;     // receive() returned an error other than timeout
};

class CanPort {
 public:
  // Queue one frame. Never blocks longer than the transmit path needs.
  virtual PortStatus send(const CanFrame& frame) = 0;
  // Wait up to timeout_us microseconds for one data frame (0 = poll). Error
  // frames are counted in counters().error_frames and not returned.
  virtual PortStatus receive(CanFrame& frame, std::uint32_t timeout_us) = 0;
  virtual const PortCounters& counters() const = 0;

 protected:
  CanPort() = default;
  ~CanPort() = default;
  CanPort(const CanPort&) = default;
  CanPort& operator=(const CanPort&) = default;
};

// Valid CAN FD data lengths (DLC 0..15 -> bytes).
inline constexpr std::uint8_t kDlcToLen[16] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};

constexpr std::uint8_t len_to_dlc(std::uint8_t len) {
  for (std::uint8_t dlc = 0; dlc < 16; ++dlc) {
    if (kDlcToLen[dlc] >= len) return dlc;
  }
  return 15;
}
constexpr bool is_valid_fd_len(std::uint8_t len) { return kDlcToLen[len_to_dlc(len)] == len; }

}  // namespace maglev::can
