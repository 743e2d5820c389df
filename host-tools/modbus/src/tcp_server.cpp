#include "maglev/modbus_tcp/tcp_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace maglev::modbus_tcp {

TcpServer::TcpServer(maglev::modbus::RegisterServer& registers, const std::string& host, int port,
                     std::uint8_t unit_id, int max_clients)
    : registers_(registers), unit_id_(unit_id), max_clients_(max_clients) {
  // libmodbus' modbus_tcp_listen() does not report the bound port, and port 0
  // (ephemeral) is what tests need; so the listen socket is ours and libmodbus
  // receives on the accepted sockets (modbus_set_socket + modbus_receive).
  ctx_ = modbus_new_tcp(host.c_str(), port);
  if (ctx_ == nullptr) {
    error_ = "modbus_new_tcp failed";
    return;
  }
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
      ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 || ::listen(listen_fd_, 4) != 0) {
    error_ = "cannot listen on " + host + ":" + std::to_string(port) + ": " + std::strerror(errno);
    ::close(listen_fd_);
    listen_fd_ = -1;
    return;
  }
  socklen_t len = sizeof addr;
  ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

TcpServer::~TcpServer() {
  for (int fd : clients_) ::close(fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  if (ctx_ != nullptr) modbus_free(ctx_);
}

namespace {
// Function codes whose request length libmodbus 3.1.6 derives correctly; for
// any other code modbus_receive() reads only MBAP + function code and leaves
// the rest in the socket, so those are framed by the MBAP length instead.
bool libmodbus_frames(std::uint8_t fc) {
  return (fc >= 0x01 && fc <= 0x06) || fc == 0x0F || fc == 0x10 || fc == 0x11 || fc == 0x16 || fc == 0x17;
}
bool read_all(int fd, std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const ssize_t r = ::recv(fd, p, n, 0);
    if (r <= 0) return false;
    p += r;
    n -= static_cast<std::size_t>(r);
  }
  return true;
}
}  // namespace

bool TcpServer::serve_one(int fd) {
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  std::uint8_t peek[8];
  if (::recv(fd, peek, sizeof peek, MSG_PEEK | MSG_DONTWAIT) <= 0) return false;
  int rc = 0;
  if (libmodbus_frames(peek[7])) {
    modbus_set_socket(ctx_, fd);
    rc = modbus_receive(ctx_, query);
  } else {
    // MBAP: transaction(2) protocol(2) length(2) unit(1); length counts unit + PDU.
    if (!read_all(fd, query, 7)) return false;
    const std::size_t len = static_cast<std::size_t>((query[4] << 8) | query[5]);
    if (len < 2 || len > MODBUS_TCP_MAX_ADU_LENGTH - 6u || !read_all(fd, query + 7, len - 1)) return false;
    rc = static_cast<int>(6 + len);
  }
  if (rc <= 0) return rc == 0;  // 0: ignored (other unit, per libmodbus); -1: connection closed or bad frame
  const int header = modbus_get_header_length(ctx_);  // 7: MBAP incl. unit id
  const std::uint8_t unit = query[header - 1];
  if (unit != unit_id_ && unit != 0xFF && unit != 0) return true;
  std::uint8_t reply[MODBUS_TCP_MAX_ADU_LENGTH];
  const std::size_t pdu =
      registers_.handle_pdu(query + header, static_cast<std::size_t>(rc - header), reply + header, unit == 0);
  if (pdu == 0) return true;
  std::memcpy(reply, query, 4);  // transaction id, protocol id
  const std::size_t len = pdu + 1;
  reply[4] = static_cast<std::uint8_t>(len >> 8);
  reply[5] = static_cast<std::uint8_t>(len & 0xFF);
  reply[6] = unit;
  const std::size_t total = static_cast<std::size_t>(header) + pdu;
  return ::send(fd, reply, total, MSG_NOSIGNAL) == static_cast<ssize_t>(total);
}

int TcpServer::poll(int timeout_ms) {
  if (listen_fd_ < 0) return 0;
  std::vector<pollfd> fds;
  fds.push_back({listen_fd_, POLLIN, 0});
  for (int fd : clients_) fds.push_back({fd, POLLIN, 0});
  if (::poll(fds.data(), fds.size(), timeout_ms) <= 0) return 0;
  int served = 0;
  std::vector<int> closed;
  for (std::size_t i = 1; i < fds.size(); ++i) {
    if ((fds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
    if (serve_one(fds[i].fd)) {
      ++served;
    } else {
      closed.push_back(fds[i].fd);
    }
  }
  for (int fd : closed) {
    ::close(fd);
    clients_.erase(std::remove(clients_.begin(), clients_.end(), fd), clients_.end());
  }
  if ((fds[0].revents & POLLIN) != 0) {
    const int fd = ::accept(listen_fd_, nullptr, nullptr);
    if (fd >= 0) {
      if (static_cast<int>(clients_.size()) >= max_clients_) {
        ::close(fd);
      } else {
        clients_.push_back(fd);
      }
    }
  }
  return served;
}

}  // namespace maglev::modbus_tcp
