// maglev-can-interop: glue between our codec and can-utils, used inside the
// test VM (and usable by hand on any SocketCAN host).
//   print-sensor SEED COUNTER          cansend argument of our sensor frame
//   check-candump DBC SEED COUNTER     read `candump -L` lines on stdin, decode
//                                      the frame with the DBC (not the codec),
//                                      compare with the expected sample
//   receive-sensor IFACE SEED COUNTER  receive one frame with our SocketCAN
//                                      port + LinkReceiver, compare
// Exit 0 = values match.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include "../can/dbc_reader.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/receiver.hpp"
#include "maglev/socketcan/socketcan_port.hpp"

using namespace maglev;
using namespace maglev::can;

namespace {
io::SensorSample sample_from_seed(unsigned seed) {
  std::mt19937 rng(seed);
  io::SensorSample s{};
  for (auto& c : s.interferometer_counts) c = static_cast<std::uint32_t>(rng());
  for (auto& c : s.displacement_adc) c = static_cast<std::int16_t>(rng());
  for (auto& c : s.hall_adc) c = static_cast<std::int16_t>(rng());
  s.status_flags = static_cast<std::uint16_t>(rng() & 0xFF);
  return s;
}

int print_sensor(unsigned seed, unsigned counter) {
  CanFrame f{};
  encode_sensor(sample_from_seed(seed), static_cast<std::uint8_t>(counter), f);
  std::printf("%03X##%X", f.id, f.flags & (kFlagBrs | kFlagEsi));
  for (int i = 0; i < f.len; ++i) std::printf("%02X", f.data[i]);
  std::printf("\n");
  return 0;
}

int check_candump(const std::string& dbc_path, unsigned seed, unsigned counter) {
  const auto dbc = test::parse_dbc(dbc_path);
  const auto s = sample_from_seed(seed);
  std::string line;
  int frames = 0;
  while (std::getline(std::cin, line)) {
    // "(1700000000.123456) vcan0 030##1AABB..."
    std::istringstream in(line);
    std::string ts, iface, frame;
    if (!(in >> ts >> iface >> frame)) continue;
    const auto sep = frame.find("##");
    if (sep == std::string::npos) {
      std::fprintf(stderr, "not an FD frame: %s\n", line.c_str());
      return 1;
    }
    const auto id = static_cast<std::uint32_t>(std::stoul(frame.substr(0, sep), nullptr, 16));
    const std::string hex = frame.substr(sep + 3);  // skip the flags nibble
    std::uint8_t data[64] = {};
    const int len = static_cast<int>(hex.size() / 2);
    for (int i = 0; i < len && i < 64; ++i) data[i] = static_cast<std::uint8_t>(std::stoul(hex.substr(static_cast<std::size_t>(2 * i), 2), nullptr, 16));
    const auto it = dbc.find(id);
    if (it == dbc.end() || it->second.length != len) {
      std::fprintf(stderr, "id %03X len %d not in the DBC\n", id, len);
      return 1;
    }
    int bad = 0;
    for (const auto& sig : it->second.signals) {
      const double got = test::dbc_decode(sig, data);
      double want_raw = 0;
      bool known = true;
      if (sig.name == "e2e_counter") want_raw = counter;
      else if (sig.name == "status_flags") want_raw = s.status_flags;
      else if (sig.name.rfind("interferometer_count_", 0) == 0) want_raw = s.interferometer_counts[static_cast<std::size_t>(sig.name.back() - '0')];
      else if (sig.name.rfind("displacement_adc_", 0) == 0) want_raw = s.displacement_adc[static_cast<std::size_t>(sig.name.back() - '0')];
      else if (sig.name.rfind("hall_adc_", 0) == 0) want_raw = s.hall_adc[static_cast<std::size_t>(sig.name.back() - '0')];
      else known = false;  // e2e_crc: checked by the codec below
      if (!known) continue;
      const double want = want_raw * sig.factor + sig.offset;
      const bool ok = std::fabs(got - want) <= std::fabs(want) * 1e-12 + 1e-12;
      std::printf("  %-24s %.9g %s\n", sig.name.c_str(), got, ok ? "ok" : "MISMATCH");
      if (!ok) ++bad;
    }
    CanFrame f{};
    f.id = id;
    f.len = static_cast<std::uint8_t>(len);
    f.flags = kFlagFd | kFlagBrs;
    for (int i = 0; i < len; ++i) f.data[i] = data[i];
    if (check_frame(f, &message(MessageKind::kSensor), nullptr) != RxStatus::kOk) {
      std::fprintf(stderr, "E2E check failed on the candump frame\n");
      ++bad;
    }
    ++frames;
    if (bad != 0) return 1;
  }
  if (frames != 1) {
    std::fprintf(stderr, "expected 1 frame from candump, got %d\n", frames);
    return 1;
  }
  std::printf("candump frame decoded with the DBC: all signals match\n");
  return 0;
}

int receive_sensor(const std::string& iface, unsigned seed, unsigned counter) {
  std::string err;
  auto port = SocketCanPort::open(iface, {}, &err);
  if (!port) {
    std::fprintf(stderr, "open %s: %s\n", iface.c_str(), err.c_str());
    return 1;
  }
  std::printf("ready\n");
  std::fflush(stdout);
  CanFrame f{};
  if (port->receive(f, 10'000'000) != PortStatus::kOk) {
    std::fprintf(stderr, "no frame received\n");
    return 1;
  }
  LinkReceiver rx;
  const RxStatus st = rx.accept(f, &message(MessageKind::kSensor));
  if (st != RxStatus::kOk) {
    std::fprintf(stderr, "rejected: %s\n", to_string(st));
    return 1;
  }
  io::SensorSample got{};
  decode_sensor(f, got);
  const auto want = sample_from_seed(seed);
  bool ok = frame_counter(f) == counter && got.status_flags == want.status_flags;
  for (int i = 0; i < 3; ++i) ok = ok && got.interferometer_counts[i] == want.interferometer_counts[i];
  for (int i = 0; i < 3; ++i) ok = ok && got.displacement_adc[i] == want.displacement_adc[i];
  for (int i = 0; i < 4; ++i) ok = ok && got.hall_adc[i] == want.hall_adc[i];
  std::printf("frame from cansend (flags 0x%02X) decoded by our receiver: %s\n", f.flags, ok ? "match" : "MISMATCH");
  return ok ? 0 : 1;
}
}  // namespace

int main(int argc, char** argv) {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "print-sensor" && argc == 4) return print_sensor(static_cast<unsigned>(std::atoi(argv[2])), static_cast<unsigned>(std::atoi(argv[3])));
  if (cmd == "check-candump" && argc == 5) return check_candump(argv[2], static_cast<unsigned>(std::atoi(argv[3])), static_cast<unsigned>(std::atoi(argv[4])));
  if (cmd == "receive-sensor" && argc == 5) return receive_sensor(argv[2], static_cast<unsigned>(std::atoi(argv[3])), static_cast<unsigned>(std::atoi(argv[4])));
  std::fprintf(stderr, "usage: maglev-can-interop print-sensor SEED COUNTER | check-candump DBC SEED COUNTER | receive-sensor IFACE SEED COUNTER\n");
  return 2;
}
