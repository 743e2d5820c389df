#include "maglev/modbus_tcp/tcp_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace maglev::modbus_tcp {

namespace {
bool set_nonblocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL, 0);
  return flags >= 0 && ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) == 0;
}
}  // namespace

TcpServer::TcpServer(maglev::modbus::RegisterServer& registers, const std::string& host, int port,
                     std::uint8_t unit_id, TcpServerLimits limits)
    : registers_(registers), unit_id_(unit_id), limits_(limits) {
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
  if (listen_fd_ < 0) {
    error_ = std::strerror(errno);
    return;
  }
  const int yes = 1;
  ::setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1 ||
      ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(listen_fd_, 16) != 0 ||
      !set_nonblocking(listen_fd_)) {
    error_ = "cannot listen on " + host + ":" + std::to_string(port) + ": " + std::strerror(errno);
    ::close(listen_fd_);
    listen_fd_ = -1;
    return;
  }
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  clients_.reserve(static_cast<std::size_t>(std::max(1, limits_.max_clients)));
}

std::uint64_t TcpServer::max_syscalls_per_poll() const {
  // poll; per client one recv, kMaxFramesPerClient sends and a close; then
  // kMaxAcceptsPerPoll accepts, each with two fcntl and at most two closes
  // (an evicted client and a refused or broken newcomer), plus the final
  // accept that finds none waiting.
  const std::uint64_t clients = static_cast<std::uint64_t>(std::max(1, limits_.max_clients));
  return 1 + clients * (1 + kMaxFramesPerClient + 1) + kMaxAcceptsPerPoll * (1 + 2 + 2) + 1;
}

TcpServer::~TcpServer() {
  for (const Client& c : clients_) ::close(c.fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
}

void TcpServer::accept_new(Clock::time_point now) {
  // At most a few accepts per call: a connection storm cannot take the tick.
  for (int i = 0; i < kMaxAcceptsPerPoll; ++i) {
    const int fd = ::accept(listen_fd_, nullptr, nullptr);
    ++syscalls_;
    if (fd < 0) return;  // EAGAIN: none waiting
    syscalls_ += 2;      // fcntl get + set
    if (!set_nonblocking(fd)) {
      ::close(fd);
      ++syscalls_;
      continue;
    }
    if (static_cast<int>(clients_.size()) >= limits_.max_clients) {
      // Full: evict the longest-silent client if it has been silent long
      // enough, else refuse the newcomer (idle connections never lock out a
      // live operator for longer than evict_after).
      auto oldest = clients_.end();
      for (auto it = clients_.begin(); it != clients_.end(); ++it) {
        if (it->answered == 0 && (oldest == clients_.end() || it->last_activity < oldest->last_activity)) oldest = it;
      }
      if (oldest != clients_.end() && now - oldest->last_activity >= limits_.evict_after) {
        ::close(oldest->fd);
        ++syscalls_;
        clients_.erase(oldest);
        ++stats_.evicted;
      } else {
        ::close(fd);
        ++syscalls_;
        ++stats_.refused;
        continue;
      }
    }
    Client c;
    c.fd = fd;
    c.last_activity = now;
    clients_.push_back(c);
    ++stats_.accepted;
  }
}

bool TcpServer::answer(Client& c, std::size_t frame_bytes) {
  std::uint8_t reply[kMaxAdu];
  const MbapAnswer a = mbap_answer(registers_, unit_id_, c.stream.data(), frame_bytes, reply);
  if (a.other_unit) {
    ++stats_.other_unit;
    return true;
  }
  if (a.reply_bytes == 0) return true;
  ++stats_.requests;
  // Non-blocking: a client that does not read its replies is dropped.
  ++syscalls_;
  return ::send(c.fd, reply, a.reply_bytes, MSG_NOSIGNAL | MSG_DONTWAIT) == static_cast<ssize_t>(a.reply_bytes);
}

bool TcpServer::serve(Client& c, Clock::time_point now, int* answered) {
  // One bounded read: whatever fits in the frame buffer.
  if (c.stream.free_bytes() > 0) {
    const ssize_t r = ::recv(c.fd, c.stream.free_space(), c.stream.free_bytes(), MSG_DONTWAIT);
    ++syscalls_;
    if (r == 0) return false;  // closed by the client
    if (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return false;
    if (r > 0) {
      if (c.stream.used() == 0) c.frame_started = now;
      c.stream.received(static_cast<std::size_t>(r));
      c.last_activity = now;
    }
  }
  for (int n = 0; n < kMaxFramesPerClient; ++n) {
    const MbapHead head = c.stream.head();
    if (head.verdict == MbapVerdict::kBroken) {
      ++stats_.bad_frames;
      return false;
    }
    if (head.verdict == MbapVerdict::kNeedMore) break;  // bounded by frame_timeout
    if (!answer(c, head.frame_bytes)) return false;
    ++*answered;
    ++c.answered;
    c.stream.pop(head.frame_bytes);
    c.frame_started = now;
  }
  if (c.stream.used() > 0 && now - c.frame_started > limits_.frame_timeout) {
    ++stats_.slow_closed;
    return false;
  }
  if (now - c.last_activity > limits_.idle_timeout) {
    ++stats_.idle_closed;
    return false;
  }
  return true;
}

int TcpServer::poll(int timeout_ms) {
  if (listen_fd_ < 0) return 0;
  pollfd fds[1 + 64];
  const std::size_t n = std::min<std::size_t>(clients_.size(), 64);
  fds[0] = {listen_fd_, POLLIN, 0};
  for (std::size_t i = 0; i < n; ++i) fds[1 + i] = {clients_[i].fd, POLLIN, 0};
  syscalls_ = 1;
  (void)::poll(fds, 1 + n, timeout_ms);
  const Clock::time_point now = Clock::now();
  int answered = 0;
  // Every client is visited each call (timeouts apply to silent ones too).
  for (std::size_t i = 0; i < clients_.size();) {
    if (serve(clients_[i], now, &answered)) {
      ++i;
    } else {
      ::close(clients_[i].fd);
      ++syscalls_;
      clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  if ((fds[0].revents & POLLIN) != 0) accept_new(now);
  stats_.max_poll_syscalls = std::max(stats_.max_poll_syscalls, syscalls_);
  return answered;
}

}  // namespace maglev::modbus_tcp
