#include "maglev/socketcan/socketcan_port.hpp"

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace maglev::can {

namespace {
std::int64_t now_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}
bool fail(std::string* error, const char* what) {
  if (error != nullptr) *error = std::string(what) + ": " + std::strerror(errno);
  return false;
}
}  // namespace

std::unique_ptr<SocketCanPort> SocketCanPort::open(const std::string& ifname, const SocketCanOptions& opt,
                                                   std::string* error) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    fail(error, "socket(PF_CAN)");
    return nullptr;
  }
  auto bail = [&](const char* what) -> std::unique_ptr<SocketCanPort> {
    fail(error, what);
    ::close(fd);
    return nullptr;
  };
  const int fd_on = opt.fd_frames ? 1 : 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &fd_on, sizeof fd_on) != 0) {
    return bail("setsockopt(CAN_RAW_FD_FRAMES)");
  }
  if (!opt.filters.empty()) {
    std::vector<can_filter> f(opt.filters.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      f[i].can_id = opt.filters[i].id;
      f[i].can_mask = opt.filters[i].mask | CAN_EFF_FLAG | CAN_RTR_FLAG;  // standard data frames only
    }
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, f.data(),
                     static_cast<socklen_t>(f.size() * sizeof(can_filter))) != 0) {
      return bail("setsockopt(CAN_RAW_FILTER)");
    }
  }
  if (opt.receive_error_frames) {
    const can_err_mask_t err_mask = CAN_ERR_MASK;
    if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0) {
      return bail("setsockopt(CAN_RAW_ERR_FILTER)");
    }
  }
  const int own = opt.receive_own ? 1 : 0;
  if (::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_RECV_OWN_MSGS, &own, sizeof own) != 0) {
    return bail("setsockopt(CAN_RAW_RECV_OWN_MSGS)");
  }
  const unsigned index = ::if_nametoindex(ifname.c_str());
  if (index == 0) return bail("if_nametoindex");
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) return bail("bind");
  return std::unique_ptr<SocketCanPort>(new SocketCanPort(fd, "socketcan:" + ifname));
}

SocketCanPort::~SocketCanPort() {
  if (fd_ >= 0) ::close(fd_);
}

PortStatus SocketCanPort::send(const CanFrame& frame) {
  const bool fd = (frame.flags & kFlagFd) != 0;
  if (!is_valid_fd_len(frame.len) || (!fd && frame.len > CAN_MAX_DLEN)) {
    ++counters_.tx_errors;
    return PortStatus::kBadFrame;
  }
  canfd_frame out{};
  out.can_id = frame.id | ((frame.flags & kFlagExtendedId) != 0 ? CAN_EFF_FLAG : 0u);
  out.len = frame.len;
  out.flags = static_cast<std::uint8_t>(frame.flags & (CANFD_BRS | CANFD_ESI));
  std::memcpy(out.data, frame.data, frame.len);
  const std::size_t size = fd ? CANFD_MTU : CAN_MTU;
  const ssize_t n = ::write(fd_, &out, size);
  if (n != static_cast<ssize_t>(size)) {
    ++counters_.tx_errors;
    if (n < 0 && (errno == ENOBUFS || errno == EAGAIN)) return PortStatus::kTxFull;
    if (n < 0 && errno == EINVAL) return PortStatus::kBadFrame;  // e.g. FD frame on MTU-16 iface
    return PortStatus::kIoError;
  }
  ++counters_.tx_frames;
  return PortStatus::kOk;
}

PortStatus SocketCanPort::receive(CanFrame& frame, std::uint32_t timeout_us) {
  const std::int64_t deadline = now_us() + timeout_us;
  for (;;) {
    const std::int64_t left_us = deadline - now_us();
    pollfd p{fd_, POLLIN, 0};
    // poll has ms resolution: round up so a short timeout still waits.
    const int ms = left_us <= 0 ? 0 : static_cast<int>((left_us + 999) / 1000);
    const int r = ::poll(&p, 1, ms);
    if (r < 0) {
      if (errno == EINTR) continue;
      ++counters_.rx_errors;
      return PortStatus::kIoError;
    }
    if (r == 0) {
      ++counters_.rx_timeouts;
      return PortStatus::kTimeout;
    }
    canfd_frame in{};
    const ssize_t n = ::read(fd_, &in, sizeof in);
    if (n != static_cast<ssize_t>(CANFD_MTU) && n != static_cast<ssize_t>(CAN_MTU)) {
      ++counters_.rx_errors;
      return PortStatus::kIoError;
    }
    if ((in.can_id & CAN_ERR_FLAG) != 0) {
      ++counters_.error_frames;
      last_error_class_ = in.can_id & CAN_ERR_MASK;
      if ((in.can_id & CAN_ERR_BUSOFF) != 0) return PortStatus::kBusOff;
      continue;  // error frames are counted, never returned as data
    }
    const bool is_fd = n == static_cast<ssize_t>(CANFD_MTU);
    frame.id = in.can_id & ((in.can_id & CAN_EFF_FLAG) != 0 ? CAN_EFF_MASK : CAN_SFF_MASK);
    frame.len = in.len;
    // Kernels >= 5.14 set CANFD_FDF on received FD frames; older ones do not,
    // so the MTU of the read decides.
    frame.flags = static_cast<std::uint8_t>((in.flags & (CANFD_BRS | CANFD_ESI | 0x04)) |
                                            (is_fd ? kFlagFd : 0) |
                                            ((in.can_id & CAN_EFF_FLAG) != 0 ? kFlagExtendedId : 0));
    std::memcpy(frame.data, in.data, in.len <= 64 ? in.len : 64);
    ++counters_.rx_frames;
    return PortStatus::kOk;
  }
}

}  // namespace maglev::can
