// Host-only: a CanPort that host code may own through a base pointer
// (std::unique_ptr<OwnedCanPort>). Target code never uses this header.
#pragma once

#include "maglev/can_port/can_port.hpp"

namespace maglev::can {

class OwnedCanPort : public CanPort {
 public:
  OwnedCanPort() = default;
  OwnedCanPort(const OwnedCanPort&) = delete;
  OwnedCanPort& operator=(const OwnedCanPort&) = delete;
  virtual ~OwnedCanPort() = default;
  // Human-readable transport name, e.g. "socketcan:vcan0", "virtual:bench".
  virtual const char* name() const = 0;
};

}  // namespace maglev::can
