// Modbus TCP server for the bench: serves the SAME register map through the
// same maglev::modbus::RegisterServer the firmware's RTU server drives (one
// implementation of the map semantics, two transports).
//
// It runs in the bench's real-time thread, between servo ticks, so it must
// never wait on a client (docs/RELIABILITY.md "Modbus TCP"):
//   * every socket is non-blocking; poll() reads what has arrived into a
//     per-client buffer and answers only COMPLETE frames (MBAP framing is
//     ours: protocol id 0, length 2..254, the unit id, then the PDU; the
//     framing itself, without sockets, is mbap_framing.hpp);
//   * a frame that breaks the MBAP rules closes that connection;
//   * a partial frame older than frame_timeout (a client that sends a byte a
//     second, or announces 100 bytes and sends 3) closes the connection;
//   * a connection silent for idle_timeout is closed;
//   * at most max_clients connections: a new one evicts the longest-silent
//     client that has never had a request answered and has been silent for
//     evict_after (a connection flood cannot push out a working operator),
//     else it is refused;
//   * per poll(): at most kMaxFramesPerClient frames per client and one
//     bounded read per client -- the work per call is bounded;
//   * a reply that cannot be sent at once (the client does not read) closes
//     the connection.
// Unit ids: the server's own, 0xFF (the usual TCP "any unit") and 0 are
// answered; Modbus/TCP has no broadcast, so unit 0 is answered like the
// server's own unit (a write always gets its reply). Other units: no reply.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "maglev/modbus/register_server.hpp"
#include "maglev/modbus_tcp/mbap_framing.hpp"

namespace maglev::modbus_tcp {

struct TcpServerLimits {
  int max_clients = 8;
  std::chrono::milliseconds idle_timeout{10000};
  std::chrono::milliseconds frame_timeout{1000};
  std::chrono::milliseconds evict_after{1000};
};

struct TcpServerStats {
  std::uint64_t requests = 0;         // frames answered
  std::uint64_t accepted = 0;         // connections accepted
  std::uint64_t refused = 0;          // connections refused (full)
  std::uint64_t evicted = 0;          // silent clients dropped for a new one
  std::uint64_t idle_closed = 0;      // idle_timeout
  std::uint64_t slow_closed = 0;      // partial frame older than frame_timeout
  std::uint64_t bad_frames = 0;       // MBAP rules broken: connection closed
  std::uint64_t other_unit = 0;       // frames for another unit: no reply
  // The most system calls one poll() made: the work per call, counted
  // rather than timed, so that a loaded machine cannot blur it.
  std::uint64_t max_poll_syscalls = 0;
};

class TcpServer {
 public:
  static constexpr int kMaxFramesPerClient = 4;
  static constexpr int kMaxAcceptsPerPoll = 4;
  static constexpr std::size_t kMaxAdu = kMaxAduBytes;  // MBAP 7 + PDU 253

  // Listens on host:port (port 0: an ephemeral port, see port()).
  TcpServer(maglev::modbus::RegisterServer& registers, const std::string& host, int port, std::uint8_t unit_id = 1,
            TcpServerLimits limits = TcpServerLimits{});
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  bool ok() const { return listen_fd_ >= 0; }
  int port() const { return port_; }
  const std::string& error() const { return error_; }
  // Waits up to timeout_ms for activity (0: not at all), then serves what has
  // arrived. Never blocks on a client. Returns the number of requests answered.
  int poll(int timeout_ms);
  std::size_t clients() const { return clients_.size(); }
  const TcpServerStats& stats() const { return stats_; }
  const TcpServerLimits& limits() const { return limits_; }
  // The bound on stats().max_poll_syscalls that the limits imply.
  std::uint64_t max_syscalls_per_poll() const;

 private:
  using Clock = std::chrono::steady_clock;
  struct Client {
    int fd = -1;
    MbapStream stream;  // received bytes, at most one maximal ADU
    Clock::time_point last_activity{};
    Clock::time_point frame_started{};  // first byte of the pending partial frame
    std::uint64_t answered = 0;         // requests answered on this connection
  };
  void accept_new(Clock::time_point now);
  // false: close this client.
  bool serve(Client& c, Clock::time_point now, int* answered);
  bool answer(Client& c, std::size_t frame_bytes);

  maglev::modbus::RegisterServer& registers_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::uint8_t unit_id_;
  TcpServerLimits limits_;
  std::vector<Client> clients_;
  TcpServerStats stats_{};
  std::uint64_t syscalls_ = 0;  // in the current poll()
  std::string error_;
};

}  // namespace maglev::modbus_tcp
