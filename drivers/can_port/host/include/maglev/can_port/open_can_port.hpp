// Host-only: pick a transport by name (command-line convention --can NAME).
//   "virtual"            in-process virtual bus named "default"
//   "virtual:<bus>"      in-process virtual bus <bus> (endpoints in one process)
//   anything else        a SocketCAN interface, e.g. "vcan0", "can0"
#pragma once

#include <memory>
#include <string>

#include "maglev/can_port/host_can_port.hpp"
#include "maglev/socketcan/socketcan_port.hpp"

namespace maglev::can {

// nullptr on failure, *error says why.
std::unique_ptr<OwnedCanPort> open_can_port(const std::string& name, std::string* error = nullptr,
                                            const SocketCanOptions& socketcan_options = {});

}  // namespace maglev::can
