// Everything the bench needs to serve a running kernel over Modbus TCP, in
// one object: flash in a file (FileFlash), the config store, the controller
// binding, the register server and the libmodbus TCP adapter.
//
//   kernel::Controller<float> controller;
//   modbus_tcp::BenchServer<float> modbus(controller, "127.0.0.1", 1502, "stage-flash.bin");
//   while (running) { controller.step(...); modbus.poll(0); }
//
// Construction loads the configuration from the flash file and applies it to
// the controller (boot). poll() never blocks longer than timeout_ms.
#pragma once

#include <string>

#include "maglev/modbus/controller_binding.hpp"
#include "maglev/modbus_tcp/tcp_server.hpp"
#include "maglev/file_flash/file_flash.hpp"

namespace maglev::modbus_tcp {

// Flash geometry of the file: two 128 KiB sectors, like two STM32H7 sectors.
inline constexpr std::size_t kBenchFlashSector = 128 * 1024;

template <typename Scalar>
class BenchServer {
 public:
  BenchServer(kernel::Controller<Scalar>& controller, const std::string& host, int port,
              const std::string& flash_path, std::uint8_t unit_id = 1)
      : flash_(flash_path, kBenchFlashSector, 2),
        store_(flash_, 0, 1),
        device_(controller, flash_.ok() ? &store_ : nullptr),
        registers_(device_, device_.boot()),
        tcp_(registers_, host, port, unit_id) {}

  bool ok() const { return flash_.ok() && tcp_.ok(); }
  std::string error() const { return flash_.ok() ? tcp_.error() : "flash file refused: " + flash_.error(); }
  int port() const { return tcp_.port(); }
  int poll(int timeout_ms) { return tcp_.poll(timeout_ms); }
  const TcpServer& tcp() const { return tcp_; }
  modbus::RegisterServer& registers() { return registers_; }

 private:
  persistence::FileFlash flash_;
  persistence::ConfigStore store_;
  modbus::ControllerDevice<Scalar> device_;
  modbus::RegisterServer registers_;
  TcpServer tcp_;
};

}  // namespace maglev::modbus_tcp
