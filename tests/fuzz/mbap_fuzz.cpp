// libFuzzer target: the Modbus TCP server's MBAP framing (MbapStream,
// mbap_head, mbap_answer in host-tools/modbus mbap_framing.hpp) -- the code
// TcpServer::serve/answer run on every byte a TCP client sends.
//
// Input: byte 0 chooses how the stream is cut into reads, the rest is the
// byte stream a client sends. The stream is served twice, the way
// TcpServer::serve does (one bounded read per poll, at most
// kMaxFramesPerClient frames per poll), once with reads as large as the
// buffer allows and once with the reads byte 0 chooses. Checked:
//   * framing does not depend on how TCP segments the stream: both passes
//     see the same frames and the same verdict (closed as broken at the same
//     byte, or the same bytes left pending);
//   * every frame obeys the MBAP rules (protocol 0, length field = bytes
//     after it, 8..260 bytes) and the buffer never holds more than one ADU;
//   * a reply echoes transaction id, protocol id and unit, its length field
//     counts its bytes, it fits one ADU; another unit's frame gets none.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "maglev_test/fuzz_device.hpp"
#include "maglev/modbus_tcp/mbap_framing.hpp"
#include "maglev/modbus_tcp/tcp_server.hpp"

namespace {

using namespace maglev::modbus;
using namespace maglev::modbus_tcp;

constexpr std::uint8_t kUnitId = 17;

using maglev::test::FuzzDevice;  // tests/support/include/maglev_test/fuzz_device.hpp

FuzzDevice g_device;
RegisterServer g_registers(g_device, ConfigImage::defaults());

struct Outcome {
  std::vector<std::vector<std::uint8_t>> frames;
  bool broken = false;
  std::size_t consumed = 0;  // stream bytes read from the "socket"
  std::size_t pending = 0;   // bytes left in the buffer at the end
};

void check_reply(const std::uint8_t* frame, const MbapAnswer& a, const std::uint8_t* reply) {
  const std::uint8_t unit = frame[6];
  const bool ours = unit == kUnitId || unit == 0xFF || unit == 0;
  if (a.other_unit != !ours) __builtin_trap();
  if (!ours && a.reply_bytes != 0) __builtin_trap();  // another unit's frame is never answered
  if (a.reply_bytes == 0) return;
  if (a.reply_bytes < kMbapHeaderBytes + 1 || a.reply_bytes > kMaxAduBytes) __builtin_trap();
  if (std::memcmp(reply, frame, 4) != 0) __builtin_trap();  // transaction + protocol id echoed
  const std::size_t len = static_cast<std::size_t>((reply[4] << 8) | reply[5]);
  if (len + 6 != a.reply_bytes || reply[6] != unit) __builtin_trap();
}

// Serves `stream` the way TcpServer::serve does; read_size(i) is the size of
// the i-th read the socket delivers (capped by the free buffer).
template <class ReadSize>
Outcome serve(const std::uint8_t* stream, std::size_t size, ReadSize read_size, bool answer) {
  Outcome out;
  MbapStream s;
  std::size_t polls = 0;
  while (true) {
    bool progress = false;
    if (s.free_bytes() > 0 && out.consumed < size) {
      std::size_t n = read_size(polls);
      if (n > s.free_bytes()) n = s.free_bytes();
      if (n > size - out.consumed) n = size - out.consumed;
      std::memcpy(s.free_space(), stream + out.consumed, n);
      s.received(n);
      out.consumed += n;
      progress = n > 0;
    }
    ++polls;
    if (s.used() > kMaxAduBytes) __builtin_trap();
    for (int f = 0; f < TcpServer::kMaxFramesPerClient; ++f) {
      const MbapHead h = s.head();
      if (h.verdict == MbapVerdict::kBroken) {
        out.broken = true;
        out.pending = s.used();
        return out;
      }
      if (h.verdict == MbapVerdict::kNeedMore) break;
      const std::uint8_t* fr = s.data();
      const std::size_t len = static_cast<std::size_t>((fr[4] << 8) | fr[5]);
      if (h.frame_bytes < kMbapHeaderBytes + 1 || h.frame_bytes > kMaxAduBytes || h.frame_bytes > s.used() ||
          fr[2] != 0 || fr[3] != 0 || len + 6 != h.frame_bytes) {
        __builtin_trap();
      }
      if (answer) {
        std::uint8_t reply[kMaxAduBytes];
        check_reply(fr, mbap_answer(g_registers, kUnitId, fr, h.frame_bytes, reply), reply);
      }
      out.frames.emplace_back(fr, fr + h.frame_bytes);
      s.pop(h.frame_bytes);
      progress = true;
    }
    if (!progress) break;  // socket drained and nothing left to frame
  }
  out.pending = s.used();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t cut = data[0];
  const std::uint8_t* stream = data + 1;
  const std::size_t n = size - 1;
  const Outcome whole = serve(stream, n, [](std::size_t) { return kMaxAduBytes; }, true);
  // Reads of 1..16 bytes (or 1..255 for odd cut values), in a sequence that
  // the cut byte seeds: small reads split headers and PDUs everywhere.
  std::uint32_t lcg = cut;
  const Outcome cut_up = serve(
      stream, n,
      [&](std::size_t) {
        lcg = lcg * 1664525u + 1013904223u;
        return static_cast<std::size_t>(1 + ((lcg >> 16) % ((cut & 1u) != 0 ? 255u : 16u)));
      },
      false);
  // Same frames, same verdict. (Once broken, how far past the broken header
  // the socket was read depends on the read sizes: not compared.)
  if (whole.broken != cut_up.broken || whole.frames != cut_up.frames) __builtin_trap();
  if (!whole.broken && (whole.pending != cut_up.pending || whole.consumed != cut_up.consumed)) __builtin_trap();
  // What the framing accepted plus what is pending is all that was read.
  std::size_t framed = 0;
  for (const auto& f : whole.frames) framed += f.size();
  if (framed + whole.pending != whole.consumed) __builtin_trap();
  if (!whole.broken && whole.consumed != n) __builtin_trap();  // a healthy stream is read to its end
  return 0;
}
