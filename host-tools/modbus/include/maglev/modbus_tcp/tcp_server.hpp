// libmodbus TCP server adapter for the bench: serves the SAME register map
// through the same maglev::modbus::RegisterServer the firmware's RTU server
// drives (one implementation of the map semantics, two transports).
// libmodbus does the listening, accepting and MBAP framing; the request PDU
// goes to RegisterServer::handle_pdu and the reply is written back with the
// request's transaction id.
//
// Single-threaded: call poll(timeout_ms) from the bench loop next to the servo
// loop; it handles at most the requests already waiting and returns.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "maglev/modbus/register_server.hpp"

typedef struct _modbus modbus_t;  // NOLINT: libmodbus' own opaque type

namespace maglev::modbus_tcp {

class TcpServer {
 public:
  // Listens on host:port (port 0: an ephemeral port, see port()). Serves unit
  // `unit_id` and 0xFF (the usual TCP "any unit"); other units get no reply.
  TcpServer(maglev::modbus::RegisterServer& registers, const std::string& host, int port, std::uint8_t unit_id = 1,
            int max_clients = 4);
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  bool ok() const { return listen_fd_ >= 0; }
  int port() const { return port_; }
  const std::string& error() const { return error_; }
  // Wait up to timeout_ms for activity, then serve every ready socket once.
  // Returns the number of requests answered.
  int poll(int timeout_ms);
  std::size_t clients() const { return clients_.size(); }

 private:
  bool serve_one(int fd);

  maglev::modbus::RegisterServer& registers_;
  modbus_t* ctx_ = nullptr;
  int listen_fd_ = -1;
  int port_ = 0;
  std::uint8_t unit_id_;
  int max_clients_;
  std::vector<int> clients_;
  std::string error_;
};

}  // namespace maglev::modbus_tcp
