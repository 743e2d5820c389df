#include "maglev/can_port/open_can_port.hpp"

#include "maglev/virtual_can/virtual_can.hpp"

namespace maglev::can {

std::unique_ptr<OwnedCanPort> open_can_port(const std::string& name, std::string* error,
                                            const SocketCanOptions& socketcan_options) {
  if (name == "virtual" || name.rfind("virtual:", 0) == 0) {
    const std::string bus = name == "virtual" ? std::string("default") : name.substr(8);
    if (bus.empty()) {
      if (error != nullptr) *error = "empty virtual bus name";
      return nullptr;
    }
    return VirtualBus::get(bus)->open_endpoint();
  }
  if (name.empty()) {
    if (error != nullptr) *error = "empty CAN port name";
    return nullptr;
  }
  return SocketCanPort::open(name, socketcan_options, error);
}

}  // namespace maglev::can
