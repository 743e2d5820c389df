// maglev-modbus-serve: the real kernel (kernel::Controller<float>, not
// stepped: no plant attached, the stage stays where the sequencer leaves it)
// behind the bench Modbus TCP server. For stagectl sessions and tests without
// the HIL bench; `maglev-hil serve --modbus-tcp` is the same server with the
// plant running.
//   maglev-modbus-serve --tcp HOST:PORT --flash FILE [--port-file FILE] [--seconds S]
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "maglev/modbus_tcp/bench_server.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  std::string host = "127.0.0.1";
  int port = 1502;
  std::string flash = "maglev-flash.bin";
  std::string port_file;
  double seconds = 0.0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const std::string v = argv[i + 1];
    if (a == "--tcp") {
      const auto colon = v.rfind(':');
      host = v.substr(0, colon);
      port = std::atoi(v.c_str() + colon + 1);
    } else if (a == "--flash") {
      flash = v;
    } else if (a == "--port-file") {
      port_file = v;
    } else if (a == "--seconds") {
      seconds = std::atof(v.c_str());
    } else {
      std::cerr << "usage: maglev-modbus-serve --tcp HOST:PORT --flash FILE [--port-file FILE] [--seconds S]\n";
      return 1;
    }
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  auto controller = std::make_unique<maglev::kernel::Controller<float>>();
  maglev::modbus_tcp::BenchServer<float> server(*controller, host, port, flash);
  if (!server.ok()) {
    std::cerr << "maglev-modbus-serve: " << server.error() << "\n";
    return 2;
  }
  if (!port_file.empty()) std::ofstream(port_file) << server.port() << "\n";
  std::cout << "serving Modbus TCP on " << host << ":" << server.port() << std::endl;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (g_stop == 0 && (seconds <= 0.0 || std::chrono::steady_clock::now() < end)) server.poll(20);
  return 0;
}
