// libFuzzer target: the CAN FD frame decoder and its E2E check
// (firmware/can_link: check_frame, LinkReceiver::accept, the typed decoders,
// e2e_crc). Every frame a node receives goes through these.
//
// Input: a sequence of frames, each described by a control byte and the
// bytes it asks for (see next_frame). Because a random frame almost never
// carries a good E2E CRC, a control bit lets the harness fix the CRC up with
// the message's data ID, as a sender would, so the range checks, the counter
// logic and the typed decoders behind the CRC are reached too.
// Checked, beyond "no crash, no sanitizer report":
//   * LinkReceiver::accept agrees with the stateless check_frame (a frame
//     check_frame rejects is rejected for the same reason; an accepted one is
//     only ever refused for its counter) and counts every frame once;
//   * an accepted frame survives decode -> encode: the re-encoded frame
//     passes check_frame and carries the same raw signal values (a host
//     command's value slots beyond its field count are not part of the
//     command and are dropped);
//   * E2E: any single flipped bit of an accepted frame is rejected
//     (CRC-16/CCITT-FALSE detects every single-bit error).
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/e2e.hpp"
#include "maglev/can_link/receiver.hpp"

namespace {

using namespace maglev::can;

struct Cursor {
  const std::uint8_t* p;
  std::size_t n;
  std::uint8_t take() {
    if (n == 0) return 0;
    --n;
    return *p++;
  }
};

// Control byte: bits 0-3 catalog index (>= kMessageCount: an id from the
// input), bit 4 fix the E2E CRC, bit 5 the catalog's length (else a length
// byte), bit 6 flags from the input (else FD | BRS), bit 7 pass the message
// as `expected`.
struct Described {
  CanFrame frame{};
  const Message* expected = nullptr;
  std::uint8_t flip_bit = 0;
};

Described next_frame(Cursor& in) {
  Described d;
  const std::uint8_t ctl = in.take();
  const std::size_t sel = ctl & 0x0Fu;
  const Message* m = sel < kMessageCount ? &kCatalog[sel] : nullptr;
  CanFrame& f = d.frame;
  if (m != nullptr) {
    f.id = m->can_id;
  } else {
    f.id = static_cast<std::uint32_t>(in.take()) | (static_cast<std::uint32_t>(in.take()) << 8);
  }
  f.flags = (ctl & 0x40u) != 0 ? in.take() : static_cast<std::uint8_t>(kFlagFd | kFlagBrs);
  f.len = (ctl & 0x20u) != 0 && m != nullptr ? m->length : in.take();
  const std::size_t copy = f.len < kMaxCanFdPayload ? f.len : kMaxCanFdPayload;
  for (std::size_t i = 0; i < copy; ++i) f.data[i] = in.take();
  if ((ctl & 0x10u) != 0 && m != nullptr) e2e_protect(f.data, m->length, m->data_id, f.data[kE2eCounterByte]);
  if ((ctl & 0x80u) != 0 && m != nullptr) d.expected = m;
  d.flip_bit = in.take();
  return d;
}

// decode -> encode with the same counter, through the typed API.
CanFrame reencode(const Message& m, const CanFrame& f) {
  CanFrame g{};
  const std::uint8_t ctr = frame_counter(f);
  switch (static_cast<MessageKind>(&m - kCatalog.data())) {
    case MessageKind::kSync: {
      SyncFrame v{};
      decode_sync(f, v);
      encode_sync(v, ctr, g);
      break;
    }
    case MessageKind::kActuator: {
      maglev::io::ActuatorCommand v{};
      decode_actuator(f, v);
      encode_actuator(v, ctr, g);
      break;
    }
    case MessageKind::kSensor: {
      maglev::io::SensorSample v{};
      decode_sensor(f, v);
      encode_sensor(v, ctr, g);
      break;
    }
    case MessageKind::kCurrentMonitor: {
      CurrentMonitorFrame v{};
      decode_current_monitor(f, v);
      encode_current_monitor(v, ctr, g);
      break;
    }
    case MessageKind::kControllerStatus: {
      ControllerStatusFrame v{};
      decode_controller_status(f, v);
      encode_controller_status(v, ctr, g);
      break;
    }
    case MessageKind::kHeartbeatController:
    case MessageKind::kHeartbeatPlant: {
      HeartbeatFrame v{};
      decode_heartbeat(f, v);
      encode_heartbeat(static_cast<MessageKind>(&m - kCatalog.data()), v, ctr, g);
      break;
    }
    case MessageKind::kHostCommand: {
      HostCommandFrame v{};
      decode_host_command(f, v);
      encode_host_command(v, ctr, g);
      break;
    }
    case MessageKind::kHostCommandAck: {
      HostCommandAckFrame v{};
      decode_host_command_ack(f, v);
      encode_host_command_ack(v, ctr, g);
      break;
    }
    case MessageKind::kCount: __builtin_trap();
  }
  return g;
}

void check_round_trip(const Message& m, const CanFrame& f) {
  const CanFrame g = reencode(m, f);
  if (g.id != f.id || g.len != f.len || frame_counter(g) != frame_counter(f)) __builtin_trap();
  if (check_frame(g, &m, nullptr) != RxStatus::kOk) __builtin_trap();
  std::int64_t a[kMaxSignals + 2];
  std::int64_t b[kMaxSignals + 2];
  unpack_raw(m, f.data, a);
  unpack_raw(m, g.data, b);
  std::size_t compared = m.signal_count;
  if (&m == &message(MessageKind::kHostCommand)) {
    // command_code, axis, command_seq, then only the command's own fields.
    const HostCommandSpec* spec = host_command_spec(static_cast<HostCommandCode>(a[2]));
    if (spec == nullptr) __builtin_trap();  // check_frame let an unknown code through
    compared = 5 + spec->field_count;
    for (std::size_t i = compared; i < m.signal_count; ++i) {
      if (b[i] != 0) __builtin_trap();  // unused slots go out as 0.0
    }
  }
  for (std::size_t i = 1; i < compared; ++i) {  // 0 is the CRC: it covers the dropped bits too
    if (a[i] != b[i]) __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Cursor in{data, size};
  LinkReceiver rx;
  std::uint32_t frames = 0;
  while (in.n > 0 && frames < 64) {
    const Described d = next_frame(in);
    const CanFrame& f = d.frame;
    const Message* found = nullptr;
    const RxStatus stateless = check_frame(f, d.expected, &found);
    const RxStatus st = rx.accept(f, d.expected);
    ++frames;
    if (stateless != RxStatus::kOk) {
      if (st != stateless) __builtin_trap();
      continue;
    }
    if (found == nullptr || found->length != f.len) __builtin_trap();
    if (st == RxStatus::kOk) {
      if (rx.last_message() != found) __builtin_trap();
    } else if (st != RxStatus::kRepeated && st != RxStatus::kOutOfOrder && st != RxStatus::kSequenceJump) {
      __builtin_trap();
    }
    check_round_trip(*found, f);
    CanFrame flipped = f;
    const std::size_t bit = d.flip_bit % (static_cast<std::size_t>(f.len) * 8u);
    flipped.data[bit / 8u] = static_cast<std::uint8_t>(flipped.data[bit / 8u] ^ (1u << (bit % 8u)));
    if (check_frame(flipped, found, nullptr) == RxStatus::kOk) __builtin_trap();
  }
  if (rx.stats().accepted + rx.stats().rejected_total() != frames) __builtin_trap();
  return 0;
}
