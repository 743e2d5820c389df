#include "maglev/can_link/codec.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <utility>

#include "maglev/can_link/e2e.hpp"

namespace maglev::can {

const char* to_string(RxStatus s) {
  switch (s) {
    case RxStatus::kOk: return "ok";
    case RxStatus::kUnknownId: return "unknown_id";
    case RxStatus::kWrongLength: return "wrong_length";
    case RxStatus::kWrongFormat: return "wrong_format";
    case RxStatus::kBadCrc: return "bad_crc";
    case RxStatus::kRepeated: return "repeated";
    case RxStatus::kOutOfOrder: return "out_of_order";
    case RxStatus::kSequenceJump: return "sequence_jump";
    case RxStatus::kOutOfRange: return "out_of_range";
    case RxStatus::kCount: break;
  }
  return "?";
}

namespace {
// n (1..8) bytes from p as a little-endian word: the Intel layout's byte
// order, on any host.
inline std::uint64_t load_le(const std::uint8_t* p, std::uint32_t n) {
  std::uint64_t w = 0;
  for (std::uint32_t k = n; k-- > 0;) w = (w << 8) | p[k];
  return w;
}
inline void store_le(std::uint8_t* p, std::uint32_t n, std::uint64_t w) {
  for (std::uint32_t k = 0; k < n; ++k) {
    p[k] = static_cast<std::uint8_t>(w & 0xFFu);
    w >>= 8;
  }
}
// Bytes a signal spans (9 only for a 64-bit signal off a byte boundary).
inline std::uint32_t span_bytes(const Signal& s) { return (s.start_bit % 8u + s.length_bits + 7u) / 8u; }
inline std::uint64_t field_mask(const Signal& s) {
  return s.length_bits < 64 ? (std::uint64_t{1} << s.length_bits) - 1u : ~std::uint64_t{0};
}
// A signal of a whole frame (kMaxCanFdPayload bytes behind data): one
// unaligned 8-byte load when the 8 bytes from its first byte are inside the
// frame (every signal of the catalog's frames up to byte 56), else
// read_signal. Same value as read_signal, bit for bit.
__attribute__((always_inline)) inline std::int64_t read_frame_signal(const Signal& s, const std::uint8_t* data) {
  const std::uint32_t first = s.start_bit / 8u;
  const std::uint32_t off = s.start_bit % 8u;
  if (std::endian::native == std::endian::little && first + 8u <= kMaxCanFdPayload && off + s.length_bits <= 64u) {
    std::uint64_t w;
    std::memcpy(&w, data + first, sizeof w);
    std::uint64_t v = (w >> off) & field_mask(s);
    if (s.is_signed && s.length_bits < 64 && ((v >> (s.length_bits - 1u)) & 1u) != 0) {
      v |= ~std::uint64_t{0} << s.length_bits;  // sign-extend
    }
    return static_cast<std::int64_t>(v);
  }
  return read_signal(s, data);
}
// unpack_raw on a whole frame.
inline void unpack_frame(const Message& m, const CanFrame& f, std::int64_t* raw) {
  for (std::size_t i = 0; i < m.signal_count; ++i) raw[i] = read_frame_signal(m.signals[i], f.data);
}
}  // namespace

std::int64_t read_signal(const Signal& s, const std::uint8_t* data) {
  // The bytes the signal spans as one word, shifted and masked: bit-exact
  // with the DBC Intel layout; the HIL bench decodes ~50 signals per servo
  // tick, so this is hot.
  std::uint64_t v = 0;
  const std::uint32_t n = span_bytes(s);
  if (n <= 8u) {
    v = (load_le(data + s.start_bit / 8u, n) >> (s.start_bit % 8u)) & field_mask(s);
  } else {
    // A 64-bit signal across 9 bytes: byte-wise (up to 8 bits per step).
    std::uint32_t i = 0;
    while (i < s.length_bits) {
      const std::uint32_t bit = s.start_bit + i;
      const std::uint32_t off = bit % 8u;
      const std::uint32_t take = (8u - off) < (s.length_bits - i) ? (8u - off) : (s.length_bits - i);
      const std::uint32_t chunk = (static_cast<std::uint32_t>(data[bit / 8u]) >> off) & ((1u << take) - 1u);
      v |= static_cast<std::uint64_t>(chunk) << i;
      i += take;
    }
  }
  if (s.is_signed && s.length_bits < 64 && ((v >> (s.length_bits - 1u)) & 1u) != 0) {
    v |= ~std::uint64_t{0} << s.length_bits;  // sign-extend
  }
  return static_cast<std::int64_t>(v);
}

void write_signal(const Signal& s, std::int64_t raw, std::uint8_t* data) {
  const auto v = static_cast<std::uint64_t>(raw);
  const std::uint32_t n = span_bytes(s);
  if (n <= 8u) {
    // Read-modify-write of the spanned bytes: the other bits are kept.
    std::uint8_t* p = data + s.start_bit / 8u;
    const std::uint32_t off = s.start_bit % 8u;
    const std::uint64_t mask = field_mask(s) << off;
    store_le(p, n, (load_le(p, n) & ~mask) | ((v << off) & mask));
    return;
  }
  std::uint32_t i = 0;
  while (i < s.length_bits) {
    const std::uint32_t bit = s.start_bit + i;
    const std::uint32_t off = bit % 8u;
    const std::uint32_t take = (8u - off) < (s.length_bits - i) ? (8u - off) : (s.length_bits - i);
    const std::uint32_t mask = ((1u << take) - 1u) << off;
    const std::uint32_t bits = (static_cast<std::uint32_t>(v >> i) << off) & mask;
    data[bit / 8u] = static_cast<std::uint8_t>((static_cast<std::uint32_t>(data[bit / 8u]) & ~mask) | bits);
    i += take;
  }
}

void pack_raw(const Message& m, const std::int64_t* raw, std::uint8_t* data) {
  for (std::size_t i = 0; i < m.length; ++i) data[i] = 0;
  for (std::size_t i = 0; i < m.signal_count; ++i) write_signal(m.signals[i], raw[i], data);
}

void unpack_raw(const Message& m, const std::uint8_t* data, std::int64_t* raw) {
  for (std::size_t i = 0; i < m.signal_count; ++i) raw[i] = read_signal(m.signals[i], data);
}

namespace {
// write_signal on a whole frame: one 8-byte read-modify-write when the 8
// bytes from the signal's first byte are inside the frame, else
// write_signal. Same bytes as write_signal.
__attribute__((always_inline)) inline void write_frame_signal(const Signal& s, std::int64_t raw, std::uint8_t* data) {
  const std::uint32_t first = s.start_bit / 8u;
  const std::uint32_t off = s.start_bit % 8u;
  if (std::endian::native == std::endian::little && first + 8u <= kMaxCanFdPayload && off + s.length_bits <= 64u) {
    std::uint64_t w;
    std::memcpy(&w, data + first, sizeof w);
    const std::uint64_t mask = field_mask(s) << off;
    w = (w & ~mask) | ((static_cast<std::uint64_t>(raw) << off) & mask);
    std::memcpy(data + first, &w, sizeof w);
    return;
  }
  write_signal(s, raw, data);
}
}  // namespace

void encode_raw(const Message& m, const std::int64_t* raw, std::uint8_t counter, CanFrame& frame) {
  frame.id = m.can_id;
  frame.len = m.length;
  frame.flags = static_cast<std::uint8_t>(kFlagFd | kFlagBrs);
  for (auto& b : frame.data) b = 0;
  // pack_raw on the cleared frame.
  for (std::size_t i = 0; i < m.signal_count; ++i) write_frame_signal(m.signals[i], raw[i], frame.data);
  e2e_protect(frame.data, m.length, m.data_id, counter);
}

namespace {
// encode_raw / unpack_frame for a catalog layout known at compile time (the
// servo path's sensor, actuator and current-monitor frames, ~4 per tick on
// each end): the same write_frame_signal / read_frame_signal per signal,
// unrolled with each signal's start bit, length and sign as constants, so
// the per-signal table walk and branches fold away. Same bytes and values
// as encode_raw / unpack_frame (can_codec_test compares them).
template <const auto& kSignals, std::size_t... I>
inline void pack_fixed(const std::int64_t* raw, std::uint8_t* data, std::index_sequence<I...>) {
  (write_frame_signal(kSignals[I], raw[I], data), ...);
}
template <const auto& kSignals, std::size_t... I>
inline void unpack_fixed(const std::uint8_t* data, std::int64_t* raw, std::index_sequence<I...>) {
  ((raw[I] = read_frame_signal(kSignals[I], data)), ...);
}
template <const auto& kSignals>
inline void encode_fixed(const Message& m, const std::int64_t* raw, std::uint8_t counter, CanFrame& frame) {
  frame.id = m.can_id;
  frame.len = m.length;
  frame.flags = static_cast<std::uint8_t>(kFlagFd | kFlagBrs);
  for (auto& b : frame.data) b = 0;
  pack_fixed<kSignals>(raw, frame.data, std::make_index_sequence<kSignals.size()>{});
  e2e_protect(frame.data, m.length, m.data_id, counter);
}
template <const auto& kSignals>
inline void decode_fixed(const CanFrame& f, std::int64_t* raw) {
  unpack_fixed<kSignals>(f.data, raw, std::make_index_sequence<kSignals.size()>{});
}

// Raw bounds from the physical [min, max]; compared in raw units so no
// floating point is needed at run time on the target for full-range signals.
bool raw_in_range(const Signal& s, std::int64_t raw) {
  if (s.is_float64) {
    const double v = std::bit_cast<double>(raw);
    return std::isfinite(v) && v >= s.min && v <= s.max;  // NaN fails both comparisons
  }
  const double phys = static_cast<double>(raw) * s.factor + s.offset;
  // Half an LSB of slack against rounding of factor * raw.
  const double slack = 0.5 * (s.factor < 0 ? -s.factor : s.factor);
  return phys >= s.min - slack && phys <= s.max + slack;
}
}  // namespace

namespace {
// Bit i set: signal i of catalog message k can carry a raw value outside its
// range, so check_frame reads and checks it in every frame. raw_in_range is
// monotone in raw for a fixed signal (raw -> double, * factor, + offset are
// each monotone under round-to-nearest, fused or not), so its accepted set
// is an interval of raw values: a signal whose smallest and largest raw
// values both pass passes for every raw value of its width, and the check
// is skipped with the same result. Evaluated with raw_in_range itself on
// the first call (the target's own arithmetic, so bit for bit the same
// decision), not from constants. float64 signals are always checked (NaN).
constexpr bool every_message_fits_a_mask() {
  for (const Message& m : kCatalog) {
    if (m.signal_count > 64) return false;
  }
  return true;
}
static_assert(every_message_fits_a_mask(), "a message with more than 64 signals needs a wider mask");
struct RangeCheckMasks {
  std::array<std::uint64_t, kCatalog.size()> needs_check{};
};
RangeCheckMasks make_range_check_masks() {
  RangeCheckMasks r{};
  for (std::size_t k = 0; k < kCatalog.size(); ++k) {
    const Message& m = kCatalog[k];
    for (std::size_t i = 0; i < m.signal_count; ++i) {
      const Signal& s = m.signals[i];
      bool full = !s.is_float64 && s.length_bits < 64;
      if (full) {
        const std::int64_t lo = s.is_signed ? -(std::int64_t{1} << (s.length_bits - 1u)) : 0;
        const std::int64_t hi = s.is_signed ? (std::int64_t{1} << (s.length_bits - 1u)) - 1
                                            : static_cast<std::int64_t>((std::uint64_t{1} << s.length_bits) - 1u);
        full = raw_in_range(s, lo) && raw_in_range(s, hi);
      }
      if (!full) r.needs_check[k] |= std::uint64_t{1} << i;
    }
  }
  return r;
}
const RangeCheckMasks& range_check_masks() {
  static const RangeCheckMasks masks = make_range_check_masks();
  return masks;
}
}  // namespace

std::uint64_t range_checked_signals(const Message& m) {
  return range_check_masks().needs_check[static_cast<std::size_t>(&m - kCatalog.data())];
}

namespace {
// Everything check_frame decides before the signals' ranges: format, id,
// length, CRC. *message: the catalog entry when the status is kOk.
RxStatus check_frame_envelope(const CanFrame& frame, const Message* expected, const Message** found,
                              const Message** message) {
  if (found != nullptr) *found = nullptr;
  if ((frame.flags & (kFlagExtendedId | kFlagErrorFrame)) != 0) return RxStatus::kWrongFormat;
  const Message* m = find_message(frame.id);
  if (m == nullptr || (expected != nullptr && m != expected)) return RxStatus::kUnknownId;
  if (found != nullptr) *found = m;
  if ((frame.flags & kFlagFd) == 0) return RxStatus::kWrongFormat;
  if (frame.len != m->length) return RxStatus::kWrongLength;
  if (!e2e_crc_ok(frame.data, m->length, m->data_id)) return RxStatus::kBadCrc;
  *message = m;
  return RxStatus::kOk;
}

// The range check of the signals in `mask` (bit i: signal i).
RxStatus check_signal_ranges(const CanFrame& frame, const Message& m, std::uint64_t mask) {
  for (std::uint64_t left = mask; left != 0; left &= left - 1u) {
    const Signal& s = m.signals[static_cast<std::size_t>(std::countr_zero(left))];
    if (!raw_in_range(s, read_frame_signal(s, frame.data))) return RxStatus::kOutOfRange;
  }
  return RxStatus::kOk;
}
}  // namespace

RxStatus check_frame_all_signals(const CanFrame& frame, const Message* expected, const Message** found) {
  const Message* m = nullptr;
  const RxStatus st = check_frame_envelope(frame, expected, found, &m);
  if (st != RxStatus::kOk) return st;
  const std::uint64_t all = m->signal_count >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << m->signal_count) - 1u;
  return check_signal_ranges(frame, *m, all);
}

RxStatus check_frame(const CanFrame& frame, const Message* expected, const Message** found) {
  const Message* m = nullptr;
  const RxStatus st = check_frame_envelope(frame, expected, found, &m);
  if (st != RxStatus::kOk) return st;
  // Only the signals whose width can hold an out-of-range value (above).
  return check_signal_ranges(frame, *m, range_checked_signals(*m));
}

// ---- typed -----------------------------------------------------------------------
namespace {
constexpr std::size_t kHdr = 2;  // raw[0] crc, raw[1] counter, payload from raw[2]
}

void encode_sync(const SyncFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kSyncSignals.size()] = {0, counter, v.tick, v.time_us};
  encode_raw(message(MessageKind::kSync), raw, counter, f);
}
void decode_sync(const CanFrame& f, SyncFrame& out) {
  std::int64_t raw[kSyncSignals.size()];
  unpack_frame(message(MessageKind::kSync), f, raw);
  out.tick = static_cast<std::uint32_t>(raw[kHdr + 0]);
  out.time_us = static_cast<std::uint32_t>(raw[kHdr + 1]);
}

void encode_actuator(const io::ActuatorCommand& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kActuatorSignals.size()] = {0, counter};
  for (std::size_t j = 0; j < io::kCoils; ++j) raw[kHdr + j] = v.dac_code[j];
  raw[kHdr + io::kCoils] = v.amplifier_enable ? 1 : 0;
  encode_fixed<kActuatorSignals>(message(MessageKind::kActuator), raw, counter, f);
}
void decode_actuator(const CanFrame& f, io::ActuatorCommand& out) {
  std::int64_t raw[kActuatorSignals.size()];
  decode_fixed<kActuatorSignals>(f, raw);
  for (std::size_t j = 0; j < io::kCoils; ++j) out.dac_code[j] = static_cast<std::int16_t>(raw[kHdr + j]);
  out.amplifier_enable = raw[kHdr + io::kCoils] != 0;
}

void encode_sensor(const io::SensorSample& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kSensorSignals.size()] = {0, counter};
  std::size_t k = kHdr;
  for (auto c : v.interferometer_counts) raw[k++] = c;
  for (auto c : v.displacement_adc) raw[k++] = c;
  for (auto c : v.hall_adc) raw[k++] = c;
  raw[k++] = v.status_flags;
  encode_fixed<kSensorSignals>(message(MessageKind::kSensor), raw, counter, f);
}
void decode_sensor(const CanFrame& f, io::SensorSample& out) {
  std::int64_t raw[kSensorSignals.size()];
  decode_fixed<kSensorSignals>(f, raw);
  std::size_t k = kHdr;
  for (auto& c : out.interferometer_counts) c = static_cast<std::uint32_t>(raw[k++]);
  for (auto& c : out.displacement_adc) c = static_cast<std::int16_t>(raw[k++]);
  for (auto& c : out.hall_adc) c = static_cast<std::int16_t>(raw[k++]);
  out.status_flags = static_cast<std::uint16_t>(raw[k++]);
}

void encode_current_monitor(const CurrentMonitorFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kCurrentMonitorSignals.size()] = {0, counter};
  for (std::size_t j = 0; j < io::kCoils; ++j) raw[kHdr + j] = v.coil_current_adc[j];
  encode_fixed<kCurrentMonitorSignals>(message(MessageKind::kCurrentMonitor), raw, counter, f);
}
void decode_current_monitor(const CanFrame& f, CurrentMonitorFrame& out) {
  std::int64_t raw[kCurrentMonitorSignals.size()];
  decode_fixed<kCurrentMonitorSignals>(f, raw);
  for (std::size_t j = 0; j < io::kCoils; ++j) {
    out.coil_current_adc[j] = static_cast<std::int16_t>(raw[kHdr + j]);
  }
}

void encode_controller_status(const ControllerStatusFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kControllerStatusSignals.size()] = {0, counter};
  std::size_t k = kHdr;
  for (auto p : v.pose_nm_nrad) raw[k++] = p;
  raw[k++] = v.sequencer_state;
  raw[k++] = v.fault_code;
  raw[k++] = v.saturation_flags;
  raw[k++] = v.scale_k_e4;
  for (auto c : v.current_command_mA) raw[k++] = c;
  raw[k++] = v.tick;
  encode_raw(message(MessageKind::kControllerStatus), raw, counter, f);
}
void decode_controller_status(const CanFrame& f, ControllerStatusFrame& out) {
  std::int64_t raw[kControllerStatusSignals.size()];
  unpack_frame(message(MessageKind::kControllerStatus), f, raw);
  std::size_t k = kHdr;
  for (auto& p : out.pose_nm_nrad) p = static_cast<std::int32_t>(raw[k++]);
  out.sequencer_state = static_cast<std::uint8_t>(raw[k++]);
  out.fault_code = static_cast<std::uint16_t>(raw[k++]);
  out.saturation_flags = static_cast<std::uint8_t>(raw[k++]);
  out.scale_k_e4 = static_cast<std::uint16_t>(raw[k++]);
  for (auto& c : out.current_command_mA) c = static_cast<std::int16_t>(raw[k++]);
  out.tick = static_cast<std::uint32_t>(raw[k++]);
}

void encode_heartbeat(MessageKind which, const HeartbeatFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kHeartbeatSignals.size()] = {0, counter, static_cast<std::uint8_t>(v.node_state),
                                                 v.uptime_ms, v.rx_rejected, v.bus_errors};
  encode_raw(message(which), raw, counter, f);
}
void decode_heartbeat(const CanFrame& f, HeartbeatFrame& out) {
  std::int64_t raw[kHeartbeatSignals.size()];
  unpack_frame(kCatalog[static_cast<std::size_t>(MessageKind::kHeartbeatPlant)], f, raw);
  out.node_state = static_cast<NodeState>(raw[kHdr + 0]);
  out.uptime_ms = static_cast<std::uint32_t>(raw[kHdr + 1]);
  out.rx_rejected = static_cast<std::uint16_t>(raw[kHdr + 2]);
  out.bus_errors = static_cast<std::uint16_t>(raw[kHdr + 3]);
}

void encode_host_command(const HostCommandFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kHostCommandSignals.size()] = {0, counter, static_cast<std::uint8_t>(v.code), v.axis, v.seq};
  // Field i of the command -> value slot i; unused slots stay 0.0.
  with_args(v.code, v.args, [&](const auto& a) {
    using A = std::remove_cv_t<std::remove_reference_t<decltype(a)>>;
    for (std::size_t i = 0; i < A::kFields.size(); ++i) {
      raw[kHdr + 3 + i] = std::bit_cast<std::int64_t>(a.*A::kFields[i].member);
    }
  });
  encode_raw(message(MessageKind::kHostCommand), raw, counter, f);
}
void decode_host_command(const CanFrame& f, HostCommandFrame& out) {
  std::int64_t raw[kHostCommandSignals.size()];
  unpack_frame(message(MessageKind::kHostCommand), f, raw);
  out.code = static_cast<HostCommandCode>(raw[kHdr + 0]);
  out.axis = static_cast<std::uint8_t>(raw[kHdr + 1]);
  out.seq = static_cast<std::uint16_t>(raw[kHdr + 2]);
  out.args = HostCommandArgs{};
  with_args(out.code, out.args, [&](auto& a) {
    using A = std::remove_reference_t<decltype(a)>;
    for (std::size_t i = 0; i < A::kFields.size(); ++i) {
      a.*A::kFields[i].member = std::bit_cast<double>(raw[kHdr + 3 + i]);
    }
  });
}

void encode_host_command_ack(const HostCommandAckFrame& v, std::uint8_t counter, CanFrame& f) {
  std::int64_t raw[kHostCommandAckSignals.size()] = {
      0, counter, v.seq, static_cast<std::uint8_t>(v.code), v.result, v.sequencer_state, v.tick};
  encode_raw(message(MessageKind::kHostCommandAck), raw, counter, f);
}
void decode_host_command_ack(const CanFrame& f, HostCommandAckFrame& out) {
  std::int64_t raw[kHostCommandAckSignals.size()];
  unpack_frame(message(MessageKind::kHostCommandAck), f, raw);
  out.seq = static_cast<std::uint16_t>(raw[kHdr + 0]);
  out.code = static_cast<HostCommandCode>(raw[kHdr + 1]);
  out.result = static_cast<std::uint8_t>(raw[kHdr + 2]);
  out.sequencer_state = static_cast<std::uint8_t>(raw[kHdr + 3]);
  out.tick = static_cast<std::uint32_t>(raw[kHdr + 4]);
}

}  // namespace maglev::can
