// Host-only SocketCAN transport: one CAN_RAW socket bound to an interface
// (vcan0, can0), CAN FD frames enabled (CAN_RAW_FD_FRAMES), optional ID
// filters (CAN_RAW_FILTER), error frames delivered (CAN_RAW_ERR_FILTER) and
// counted in counters().error_frames, receive timeouts via poll(2).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "maglev/can_port/host_can_port.hpp"

namespace maglev::can {

struct SocketCanFilter {
  std::uint32_t id;
  std::uint32_t mask;  // received if (frame.id & mask) == (id & mask)
};

struct SocketCanOptions {
  std::vector<SocketCanFilter> filters;  // empty = receive everything
  bool fd_frames = true;                 // CAN_RAW_FD_FRAMES
  bool receive_error_frames = true;      // CAN_RAW_ERR_FILTER = all error classes
  bool receive_own = false;              // CAN_RAW_RECV_OWN_MSGS
};

class SocketCanPort final : public OwnedCanPort {
 public:
  // nullptr on failure; *error (if given) says why (errno text).
  static std::unique_ptr<SocketCanPort> open(const std::string& ifname, const SocketCanOptions& opt = {},
                                             std::string* error = nullptr);
  ~SocketCanPort() override;
  PortStatus send(const CanFrame& frame) override;
  PortStatus receive(CanFrame& frame, std::uint32_t timeout_us) override;
  const PortCounters& counters() const override { return counters_; }
  const char* name() const override { return name_.c_str(); }
  int fd() const { return fd_; }
  // Last error frame's CAN ID bits (CAN_ERR_* class), 0 if none yet.
  std::uint32_t last_error_class() const { return last_error_class_; }

 private:
  SocketCanPort(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
  int fd_;
  std::string name_;
  PortCounters counters_{};
  std::uint32_t last_error_class_ = 0;
};

}  // namespace maglev::can
