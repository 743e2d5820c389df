// maglev-modbus-serve: the real kernel (kernel::Controller<float>, not
// stepped: no plant attached, the stage stays where the sequencer leaves it)
// behind the bench Modbus TCP server. For stagectl sessions and tests without
// the HIL bench; `maglev-hil serve --modbus-tcp` is the same server with the
// plant running.
//   maglev-modbus-serve --tcp HOST:PORT --flash FILE [--port-file FILE] [--seconds S]
//   maglev-modbus-serve --rtu-pty BAUD --flash FILE [--port-file FILE] [--seconds S]
// --rtu-pty serves the firmware's RtuServer on a new pseudo-terminal (its
// slave path goes to --port-file): what the board's UART does, on the host.
#include <fcntl.h>
#include <poll.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "maglev/modbus/rtu_server.hpp"
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
  int rtu_baud = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    const std::string v = argv[i + 1];
    if (a == "--tcp") {
      const auto colon = v.rfind(':');
      host = v.substr(0, colon);
      port = std::atoi(v.c_str() + colon + 1);
    } else if (a == "--rtu-pty") {
      rtu_baud = std::atoi(v.c_str());
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
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  const auto running = [&] { return g_stop == 0 && (seconds <= 0.0 || std::chrono::steady_clock::now() < end); };
  if (rtu_baud > 0) {
    namespace mb = maglev::modbus;
    maglev::persistence::FileFlash flash_file(flash, maglev::modbus_tcp::kBenchFlashSector, 2);
    maglev::persistence::ConfigStore store(flash_file, 0, 1);
    mb::ControllerDevice<float> device(*controller, flash_file.ok() ? &store : nullptr);
    mb::RegisterServer registers(device, device.boot());
    mb::RtuServer rtu(registers, 1, static_cast<std::uint32_t>(rtu_baud));
    const int master = posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || grantpt(master) != 0 || unlockpt(master) != 0) {
      std::cerr << "maglev-modbus-serve: cannot open a pseudo-terminal\n";
      return 2;
    }
    const std::string slave = ptsname(master);
    const int s = open(slave.c_str(), O_RDWR | O_NOCTTY);  // raw line before any client opens it
    termios t{};
    tcgetattr(s, &t);
    cfmakeraw(&t);
    tcsetattr(s, TCSANOW, &t);
    if (!port_file.empty()) std::ofstream(port_file) << slave << "\n";
    std::cout << "serving Modbus RTU on " << slave << std::endl;
    const auto now_us = [] {
      return static_cast<std::uint32_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                            std::chrono::steady_clock::now().time_since_epoch())
                                            .count());
    };
    std::uint8_t buf[256];
    std::uint8_t tx[mb::kMaxRtuFrame];
    while (running()) {
      pollfd p{master, POLLIN, 0};
      if (::poll(&p, 1, 1) > 0 && (p.revents & POLLIN) != 0) {
        const ssize_t n = read(master, buf, sizeof buf);
        const std::uint32_t ts = now_us();
        for (ssize_t i = 0; i < n; ++i) rtu.receive(buf[i], ts);
      }
      const std::size_t len = rtu.poll(now_us(), tx);
      if (len > 0 && write(master, tx, len) != static_cast<ssize_t>(len)) break;
    }
    close(s);
    close(master);
    return 0;
  }
  maglev::modbus_tcp::BenchServer<float> server(*controller, host, port, flash);
  if (!server.ok()) {
    std::cerr << "maglev-modbus-serve: " << server.error() << "\n";
    return 2;
  }
  if (!port_file.empty()) std::ofstream(port_file) << server.port() << "\n";
  std::cout << "serving Modbus TCP on " << host << ":" << server.port() << std::endl;
  while (running()) server.poll(20);
  return 0;
}
