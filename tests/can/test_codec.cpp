// Codec, E2E and receiver tests: round trips, every rejection path, counter wrap.
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

#include "maglev/can_link/codec.hpp"
#include "maglev/can_link/e2e.hpp"
#include "maglev/can_link/receiver.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::can;

namespace {
io::SensorSample random_sample(std::mt19937& rng) {
  io::SensorSample s{};
  for (auto& c : s.interferometer_counts) c = static_cast<std::uint32_t>(rng());
  for (auto& c : s.displacement_adc) c = static_cast<std::int16_t>(rng());
  for (auto& c : s.hall_adc) c = static_cast<std::int16_t>(rng());
  for (auto& c : s.coil_current_adc) c = static_cast<std::int16_t>(rng());
  s.status_flags = static_cast<std::uint16_t>(rng());
  return s;
}
io::ActuatorCommand random_command(std::mt19937& rng) {
  io::ActuatorCommand a{};
  for (auto& c : a.dac_code) c = static_cast<std::int16_t>(rng());
  a.amplifier_enable = (rng() & 1u) != 0;
  return a;
}
}  // namespace

TEST_GROUP(E2e){};

TEST(E2e, Crc16CcittFalseCheckValue) {
  const std::uint8_t msg[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  LONGS_EQUAL(0x29B1, crc16_ccitt(msg, sizeof msg));
}

// The slicing-by-8 CRC equals the byte-wise definition for every length
// 0-80 (every tail length after 0-10 eight-byte blocks), random data and
// random chained init values, and 0x00 / 0xFF runs.
TEST(E2e, SlicingBy8EqualsTheBytewiseCrc) {
  std::mt19937 rng(16);
  std::uint8_t buf[80];
  for (int trial = 0; trial < 200; ++trial) {
    for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
    if (trial == 0) std::memset(buf, 0x00, sizeof buf);
    if (trial == 1) std::memset(buf, 0xFF, sizeof buf);
    const auto init = trial < 100 ? kCrc16Init : static_cast<std::uint16_t>(rng());
    for (std::size_t n = 0; n <= sizeof buf; ++n) {
      LONGS_EQUAL(detail::crc16_ccitt_bytewise(buf, n, init), crc16_ccitt(buf, n, init));
    }
  }
  // Compile-time evaluation gives the same check value.
  static constexpr std::uint8_t kMsg[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  static_assert(crc16_ccitt(kMsg, sizeof kMsg) == 0x29B1);
}

TEST(E2e, DataIdChangesCrc) {
  std::mt19937 rng(1);
  CanFrame f{};
  encode_actuator(random_command(rng), 7, f);
  CHECK_TRUE(e2e_crc_ok(f.data, f.len, message(MessageKind::kActuator).data_id));
  // Same bytes under the current monitor's data ID (same 20-byte length): fails.
  CHECK_FALSE(e2e_crc_ok(f.data, f.len, message(MessageKind::kCurrentMonitor).data_id));
}

TEST_GROUP(RoundTrip){};

TEST(RoundTrip, SensorActuatorAndAllOthers) {
  std::mt19937 rng(42);
  for (int i = 0; i < 500; ++i) {
    CanFrame f{};
    const auto s = random_sample(rng);
    encode_sensor(s, static_cast<std::uint8_t>(i), f);
    LONGS_EQUAL(0x030, f.id);
    LONGS_EQUAL(32, f.len);
    LONGS_EQUAL(kFlagFd | kFlagBrs, f.flags);
    const Message* m = nullptr;
    CHECK(RxStatus::kOk == check_frame(f, nullptr, &m));
    io::SensorSample back{};
    decode_sensor(f, back);
    MEMCMP_EQUAL(s.interferometer_counts, back.interferometer_counts, sizeof s.interferometer_counts);
    MEMCMP_EQUAL(s.displacement_adc, back.displacement_adc, sizeof s.displacement_adc);
    MEMCMP_EQUAL(s.hall_adc, back.hall_adc, sizeof s.hall_adc);
    LONGS_EQUAL(s.status_flags, back.status_flags);
    LONGS_EQUAL(i & 0xFF, frame_counter(f));

    const auto a = random_command(rng);
    encode_actuator(a, static_cast<std::uint8_t>(i), f);
    CHECK(RxStatus::kOk == check_frame(f, &message(MessageKind::kActuator), nullptr));
    io::ActuatorCommand ab{};
    decode_actuator(f, ab);
    MEMCMP_EQUAL(a.dac_code, ab.dac_code, sizeof a.dac_code);
    CHECK_EQUAL(a.amplifier_enable, ab.amplifier_enable);

    CurrentMonitorFrame cm{};
    for (int j = 0; j < 8; ++j) cm.coil_current_adc[j] = s.coil_current_adc[j];
    encode_current_monitor(cm, 3, f);
    CHECK(RxStatus::kOk == check_frame(f, nullptr, nullptr));
    CurrentMonitorFrame cmb{};
    decode_current_monitor(f, cmb);
    MEMCMP_EQUAL(cm.coil_current_adc, cmb.coil_current_adc, sizeof cm.coil_current_adc);

    ControllerStatusFrame cs{};
    for (auto& p : cs.pose_nm_nrad) p = static_cast<std::int32_t>(rng());
    cs.sequencer_state = static_cast<std::uint8_t>(rng() % 16);
    cs.fault_code = static_cast<std::uint16_t>(rng());
    cs.saturation_flags = static_cast<std::uint8_t>(rng());
    cs.scale_k_e4 = static_cast<std::uint16_t>(rng());
    for (auto& c : cs.current_command_mA) c = static_cast<std::int16_t>(rng());
    cs.tick = static_cast<std::uint32_t>(rng());
    encode_controller_status(cs, 9, f);
    CHECK(RxStatus::kOk == check_frame(f, nullptr, nullptr));
    ControllerStatusFrame csb{};
    decode_controller_status(f, csb);
    MEMCMP_EQUAL(cs.pose_nm_nrad, csb.pose_nm_nrad, sizeof cs.pose_nm_nrad);
    LONGS_EQUAL(cs.sequencer_state, csb.sequencer_state);
    LONGS_EQUAL(cs.fault_code, csb.fault_code);
    LONGS_EQUAL(cs.saturation_flags, csb.saturation_flags);
    LONGS_EQUAL(cs.scale_k_e4, csb.scale_k_e4);
    MEMCMP_EQUAL(cs.current_command_mA, csb.current_command_mA, sizeof cs.current_command_mA);
    UNSIGNED_LONGS_EQUAL(cs.tick, csb.tick);

    const SyncFrame sy{static_cast<std::uint32_t>(rng()), static_cast<std::uint32_t>(rng())};
    encode_sync(sy, 1, f);
    CHECK(RxStatus::kOk == check_frame(f, nullptr, nullptr));
    SyncFrame syb{};
    decode_sync(f, syb);
    UNSIGNED_LONGS_EQUAL(sy.tick, syb.tick);
    UNSIGNED_LONGS_EQUAL(sy.time_us, syb.time_us);

    const HeartbeatFrame hb{static_cast<NodeState>(rng() % 4), static_cast<std::uint32_t>(rng()),
                            static_cast<std::uint16_t>(rng()), static_cast<std::uint16_t>(rng())};
    for (auto k : {MessageKind::kHeartbeatController, MessageKind::kHeartbeatPlant}) {
      encode_heartbeat(k, hb, 2, f);
      LONGS_EQUAL(message(k).can_id, f.id);
      CHECK(RxStatus::kOk == check_frame(f, nullptr, nullptr));
      HeartbeatFrame hbb{};
      decode_heartbeat(f, hbb);
      CHECK(hb.node_state == hbb.node_state);
      UNSIGNED_LONGS_EQUAL(hb.uptime_ms, hbb.uptime_ms);
      LONGS_EQUAL(hb.rx_rejected, hbb.rx_rejected);
      LONGS_EQUAL(hb.bus_errors, hbb.bus_errors);
    }
  }
}

TEST(RoundTrip, KnownBytesOfASensorFrame) {
  // Pins the wire layout: little endian, header then payload back to back.
  io::SensorSample s{};
  s.interferometer_counts[0] = 0x11223344u;
  s.displacement_adc[0] = -2;  // 0xFFFE
  s.status_flags = io::kBeamLoss1;
  CanFrame f{};
  encode_sensor(s, 0xAB, f);
  LONGS_EQUAL(0xAB, f.data[2]);
  LONGS_EQUAL(0x44, f.data[3]);
  LONGS_EQUAL(0x33, f.data[4]);
  LONGS_EQUAL(0x22, f.data[5]);
  LONGS_EQUAL(0x11, f.data[6]);
  LONGS_EQUAL(0xFE, f.data[15]);
  LONGS_EQUAL(0xFF, f.data[16]);
  LONGS_EQUAL(0x02, f.data[29]);  // status flags at bits 224..239
  LONGS_EQUAL(0x00, f.data[31]);  // padding
  const std::uint16_t crc = e2e_crc(f.data, 32, 0x0A03);
  LONGS_EQUAL(crc & 0xFF, f.data[0]);
  LONGS_EQUAL(crc >> 8, f.data[1]);
}

TEST_GROUP(Rejection) {
  LinkReceiver rx;
  CanFrame good{};
  void setup() override {
    std::mt19937 rng(5);
    encode_actuator(random_command(rng), 10, good);
    CHECK(RxStatus::kOk == rx.accept(good));  // establishes counter 10
  }
};

TEST(Rejection, UnknownId) {
  CanFrame f = good;
  f.id = 0x555;
  CHECK(RxStatus::kUnknownId == rx.accept(f));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kUnknownId));
  // Expecting a sensor frame but getting an actuator frame is also "unknown here".
  CanFrame g{};
  encode_actuator(io::kSafeActuatorCommand, 11, g);
  CHECK(RxStatus::kUnknownId == rx.accept(g, &message(MessageKind::kSensor)));
  LONGS_EQUAL(2, rx.stats().count(RxStatus::kUnknownId));
}

TEST(Rejection, WrongLengthAndFormat) {
  CanFrame f{};
  encode_actuator(io::kSafeActuatorCommand, 11, f);
  f.len = 24;
  CHECK(RxStatus::kWrongLength == rx.accept(f));
  f.len = 20;
  f.flags = 0;  // classical frame
  CHECK(RxStatus::kWrongFormat == rx.accept(f));
  f.flags = kFlagFd | kFlagExtendedId;
  CHECK(RxStatus::kWrongFormat == rx.accept(f));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kWrongLength));
  LONGS_EQUAL(2, rx.stats().count(RxStatus::kWrongFormat));
  LONGS_EQUAL(1, rx.stats().accepted);
}

TEST(Rejection, BadCrcOnEverySingleBitFlip) {
  CanFrame f{};
  encode_actuator(io::kSafeActuatorCommand, 11, f);
  for (int bit = 0; bit < 20 * 8; ++bit) {
    CanFrame c = f;
    c.data[bit / 8] = static_cast<std::uint8_t>(c.data[bit / 8] ^ (1u << (bit % 8)));
    CHECK(RxStatus::kBadCrc == rx.accept(c));
  }
  LONGS_EQUAL(160, rx.stats().count(RxStatus::kBadCrc));
  CHECK(RxStatus::kOk == rx.accept(f));  // the intact frame still goes through
}

TEST(Rejection, RepeatedOutOfOrderJumpAndLost) {
  CanFrame f{};
  encode_actuator(io::kSafeActuatorCommand, 10, f);
  CHECK(RxStatus::kRepeated == rx.accept(f));
  encode_actuator(io::kSafeActuatorCommand, 9, f);
  CHECK(RxStatus::kOutOfOrder == rx.accept(f));
  encode_actuator(io::kSafeActuatorCommand, 13, f);  // 11, 12 lost: still OK (max jump 3)
  CHECK(RxStatus::kOk == rx.accept(f));
  LONGS_EQUAL(2, rx.stats().lost);
  encode_actuator(io::kSafeActuatorCommand, 20, f);  // jump 7 > 3
  CHECK(RxStatus::kSequenceJump == rx.accept(f));
  encode_actuator(io::kSafeActuatorCommand, 21, f);  // resynchronised on 20
  CHECK(RxStatus::kOk == rx.accept(f));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kRepeated));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kOutOfOrder));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kSequenceJump));
  LONGS_EQUAL(3, rx.stats().accepted);
}

// After an outage of 128-253 frames the counter reads as "older" (int8):
// only a few frames late is out of order; anything further is a jump the
// receiver resynchronises on (it refused up to 129 valid frames before).
TEST(Rejection, AnOutageOfHalfTheCounterResynchronisesAtOnce) {
  CanFrame f{};
  for (int outage : {100, 127, 128, 150, 200, 251}) {
    rx.reset();
    encode_actuator(io::kSafeActuatorCommand, 0, f);
    CHECK(RxStatus::kOk == rx.accept(f));
    const auto first = static_cast<std::uint8_t>(outage + 1);  // frames 1..outage lost
    encode_actuator(io::kSafeActuatorCommand, first, f);
    CHECK(RxStatus::kSequenceJump == rx.accept(f));
    encode_actuator(io::kSafeActuatorCommand, static_cast<std::uint8_t>(first + 1), f);
    CHECK(RxStatus::kOk == rx.accept(f));
  }
  // A frame up to max_delta_counter (3) late is still out of order, state kept.
  rx.reset();
  encode_actuator(io::kSafeActuatorCommand, 50, f);
  CHECK(RxStatus::kOk == rx.accept(f));
  encode_actuator(io::kSafeActuatorCommand, 47, f);
  CHECK(RxStatus::kOutOfOrder == rx.accept(f));
  encode_actuator(io::kSafeActuatorCommand, 51, f);
  CHECK(RxStatus::kOk == rx.accept(f));
}

TEST(Rejection, CounterWrapIsAccepted) {
  LinkReceiver r;
  CanFrame f{};
  for (int i = 250; i < 250 + 20; ++i) {
    encode_sensor(io::SensorSample{}, static_cast<std::uint8_t>(i), f);
    CHECK(RxStatus::kOk == r.accept(f));
  }
  LONGS_EQUAL(20, r.stats().accepted);
  LONGS_EQUAL(0, r.stats().lost);
  LONGS_EQUAL(0, r.stats().rejected_total());
}

TEST(Rejection, OutOfRangeEnableIsNeverApplied) {
  // A frame with a valid CRC but amplifier_enable = 2 (a sender bug).
  std::int64_t raw[kActuatorSignals.size()] = {};
  raw[2] = 1000;
  raw[10] = 2;
  CanFrame f{};
  encode_raw(message(MessageKind::kActuator), raw, 11, f);
  CHECK(RxStatus::kOutOfRange == rx.accept(f));
  LONGS_EQUAL(1, rx.stats().count(RxStatus::kOutOfRange));
  CHECK(rx.last_message() == nullptr);
}

// ---- host_command / host_command_ack ------------------------------------------
TEST_GROUP(HostCommand){};

TEST(HostCommand, RoundTripIsBitExactForDoubles) {
  const HostCommandFrame c = make_host_command(4711, 3, MoveJerkByArgs{8e-6, 1e-3, 0.0123456789012345, -1.0 / 3.0});
  CanFrame f{};
  encode_host_command(c, 9, f);
  LONGS_EQUAL(0x040, f.id);
  LONGS_EQUAL(48, f.len);
  LinkReceiver rx;
  LONGS_EQUAL(static_cast<int>(RxStatus::kOk), static_cast<int>(rx.accept(f)));
  CHECK_TRUE(rx.last_message() == &message(MessageKind::kHostCommand));
  HostCommandFrame d{};
  decode_host_command(f, d);
  CHECK_TRUE(d.code == HostCommandCode::kMoveJerkBy);
  LONGS_EQUAL(3, d.axis);
  LONGS_EQUAL(4711, d.seq);
  CHECK_TRUE(std::memcmp(&c.args.move_jerk_by, &d.args.move_jerk_by, sizeof(MoveJerkByArgs)) == 0);
  // Every command's named fields survive the wire bit for bit, in field order.
  for (const HostCommandSpec& spec : kHostCommandSpecs) {
    HostCommandFrame e{spec.code, 1, 7, {}};
    with_args(spec.code, e.args, [&](auto& a) {
      using A = std::remove_reference_t<decltype(a)>;
      for (std::size_t i = 0; i < A::kFields.size(); ++i) a.*A::kFields[i].member = 0.1 * static_cast<double>(i + 1) + 1e-17;
    });
    encode_host_command(e, 10, f);
    HostCommandFrame g{};
    decode_host_command(f, g);
    CHECK_TRUE(g.code == spec.code);
    with_args(spec.code, g.args, [&](auto& a) {
      using A = std::remove_reference_t<decltype(a)>;
      LONGS_EQUAL(spec.field_count, A::kFields.size());
      for (std::size_t i = 0; i < A::kFields.size(); ++i) {
        DOUBLES_EQUAL(0.1 * static_cast<double>(i + 1) + 1e-17, a.*A::kFields[i].member, 0.0);
      }
    });
  }

  HostCommandAckFrame a{4711, HostCommandCode::kStep, 9, 6, 123456u};
  encode_host_command_ack(a, 200, f);
  LONGS_EQUAL(0x041, f.id);
  LONGS_EQUAL(12, f.len);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOk), static_cast<int>(rx.accept(f)));
  HostCommandAckFrame b{};
  decode_host_command_ack(f, b);
  LONGS_EQUAL(4711, b.seq);
  CHECK_TRUE(b.code == HostCommandCode::kStep);
  LONGS_EQUAL(9, b.result);
  LONGS_EQUAL(6, b.sequencer_state);
  LONGS_EQUAL(123456u, b.tick);
}

TEST(HostCommand, RejectionsAreCountedAndNeverAccepted) {
  LinkReceiver rx;
  CanFrame f{};
  const HostCommandFrame ok = make_host_command(1, 0, StepArgs{8e-6});
  encode_host_command(ok, 10, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOk), static_cast<int>(rx.accept(f)));
  // Same counter again: repeated (a duplicated command is never applied twice).
  LONGS_EQUAL(static_cast<int>(RxStatus::kRepeated), static_cast<int>(rx.accept(f)));
  // Corrupted argument bit: bad CRC.
  encode_host_command(ok, 11, f);
  CanFrame bad = f;
  bad.data[20] ^= 0x10;
  LONGS_EQUAL(static_cast<int>(RxStatus::kBadCrc), static_cast<int>(rx.accept(bad)));
  // Wrong length.
  bad = f;
  bad.len = 32;
  LONGS_EQUAL(static_cast<int>(RxStatus::kWrongLength), static_cast<int>(rx.accept(bad)));
  // NaN, infinity and |arg| > 1e9 are out of range even with a valid CRC.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  HostCommandFrame c = ok;
  c.args.step.delta = nan;
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  c.args.step.delta = std::numeric_limits<double>::infinity();
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  c.args.step.delta = 2e9;
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  // Command code 0 / kHostCommandCodeMax + 1 and axis 6: out of range.
  c = ok;
  c.code = static_cast<HostCommandCode>(0);
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  c.code = static_cast<HostCommandCode>(kHostCommandCodeMax + 1);
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  c = ok;
  c.axis = 6;
  encode_host_command(c, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOutOfRange), static_cast<int>(rx.accept(f)));
  // The next good one (counter 12, delta 2 from 10) is accepted, 1 counted lost.
  encode_host_command(ok, 12, f);
  LONGS_EQUAL(static_cast<int>(RxStatus::kOk), static_cast<int>(rx.accept(f)));
  LONGS_EQUAL(1u, rx.stats().count(RxStatus::kRepeated));
  LONGS_EQUAL(1u, rx.stats().count(RxStatus::kBadCrc));
  LONGS_EQUAL(1u, rx.stats().count(RxStatus::kWrongLength));
  LONGS_EQUAL(6u, rx.stats().count(RxStatus::kOutOfRange));
  LONGS_EQUAL(2u, rx.stats().accepted);
  LONGS_EQUAL(1u, rx.stats().lost);
  // Unknown ID next to it (0x042) is rejected as such.
  f.id = 0x042;
  LONGS_EQUAL(static_cast<int>(RxStatus::kUnknownId), static_cast<int>(rx.accept(f)));
}

// read_signal / write_signal against the DBC Intel definition bit by bit
// (signal bit i = frame bit start + i, frame bit b = byte b / 8, bit b % 8),
// at every start bit of a 64-byte frame, lengths 1-32 and 64, signed and
// unsigned: the word-wise codec must equal it, and a write must leave every
// other bit of the frame as it was.
TEST_GROUP(SignalLayout){};

TEST(SignalLayout, WordWiseReadWriteEqualsTheBitwiseDefinition) {
  std::mt19937_64 rng(7);
  auto bit_of = [](const std::uint8_t* d, std::uint32_t b) { return (static_cast<unsigned>(d[b / 8u]) >> (b % 8u)) & 1u; };
  std::uint8_t lengths[33];
  for (std::uint8_t l = 1; l <= 32; ++l) lengths[l - 1] = l;
  lengths[32] = 64;
  int checked = 0;
  for (std::uint8_t len : lengths) {
    for (std::uint32_t start = 0; start + len <= 64u * 8u; ++start) {
      for (int is_signed = 0; is_signed < 2; ++is_signed) {
        Signal s{};
        s.name = "probe";
        s.start_bit = static_cast<std::uint16_t>(start);
        s.length_bits = len;
        s.is_signed = is_signed != 0;
        std::uint8_t frame[64];
        for (auto& b : frame) b = static_cast<std::uint8_t>(rng());
        // Read.
        std::uint64_t want = 0;
        for (std::uint32_t i = 0; i < len; ++i) want |= static_cast<std::uint64_t>(bit_of(frame, start + i)) << i;
        if (s.is_signed && len < 64 && ((want >> (len - 1u)) & 1u) != 0) want |= ~std::uint64_t{0} << len;
        CHECK_EQUAL(want, static_cast<std::uint64_t>(read_signal(s, frame)));
        // Write: the field takes the value's low bits, nothing else moves.
        const std::uint64_t value = rng();
        std::uint8_t before[64];
        std::memcpy(before, frame, sizeof frame);
        write_signal(s, static_cast<std::int64_t>(value), frame);
        for (std::uint32_t b = 0; b < 64u * 8u; ++b) {
          const bool in_field = b >= start && b < start + len;
          const std::uint32_t expect = in_field ? static_cast<std::uint32_t>((value >> (b - start)) & 1u) : bit_of(before, b);
          if (expect != bit_of(frame, b)) {
            FAIL("write_signal: a frame bit differs from the bitwise definition");
          }
        }
        ++checked;
      }
    }
  }
  CHECK(checked > 30000);
}

// check_frame skips the range check of signals whose every raw value is in
// range (codec.cpp, range_checked_signals); it must decide every frame as
// check_frame_all_signals does. Per catalog message: frames whose signals
// take random raw values of their full width, and frames with one signal
// at each end of its width (the rest random), all with a valid CRC.
TEST(SignalLayout, SkippedRangeChecksDecideAsCheckingEverySignal) {
  std::mt19937_64 rng(11);
  int frames = 0, out_of_range = 0, skipped = 0;
  for (const Message& m : kCatalog) {
    const std::uint64_t checked = range_checked_signals(m);
    for (std::size_t i = 0; i < m.signal_count; ++i) skipped += ((checked >> i) & 1u) == 0;
    auto random_raw = [&](const Signal& s) -> std::int64_t {
      if (s.is_float64) return static_cast<std::int64_t>(rng());
      const std::uint64_t v = rng() & ((std::uint64_t{1} << s.length_bits) - 1u);
      if (s.is_signed && ((v >> (s.length_bits - 1u)) & 1u) != 0) return static_cast<std::int64_t>(v | (~std::uint64_t{0} << s.length_bits));
      return static_cast<std::int64_t>(v);
    };
    auto check = [&](const std::int64_t* raw) {
      CanFrame f{};
      encode_raw(m, raw, static_cast<std::uint8_t>(raw[1]), f);
      const Message* a = nullptr;
      const Message* b = nullptr;
      const RxStatus fast = check_frame(f, nullptr, &a);
      const RxStatus all = check_frame_all_signals(f, nullptr, &b);
      CHECK(fast == all);
      CHECK(a == b);
      ++frames;
      out_of_range += all == RxStatus::kOutOfRange;
    };
    std::int64_t raw[64] = {};
    for (int n = 0; n < 2000; ++n) {
      for (std::size_t i = 0; i < m.signal_count; ++i) raw[i] = random_raw(m.signals[i]);
      check(raw);
    }
    for (std::size_t j = 2; j < m.signal_count; ++j) {  // 0, 1: CRC and counter
      const Signal& s = m.signals[j];
      if (s.is_float64) continue;
      const std::int64_t lo = s.is_signed ? -(std::int64_t{1} << (s.length_bits - 1u)) : 0;
      const std::int64_t hi = s.is_signed ? (std::int64_t{1} << (s.length_bits - 1u)) - 1
                                          : static_cast<std::int64_t>((std::uint64_t{1} << s.length_bits) - 1u);
      for (std::int64_t v : {lo, lo + 1, hi - 1, hi}) {
        for (std::size_t i = 0; i < m.signal_count; ++i) raw[i] = random_raw(m.signals[i]);
        raw[j] = v;
        check(raw);
      }
    }
  }
  std::printf("\n  %d frames (%d out of range), %d signals' range checks skipped", frames, out_of_range, skipped);
  CHECK(skipped > 0);
  CHECK(out_of_range > 0);
}

// The servo path's typed encoders and decoders (sensor, actuator, current
// monitor: compile-time layouts, codec.cpp encode_fixed / decode_fixed) give
// the bytes of the table-driven definition -- pack_raw of the struct's raw
// values on a cleared frame, then e2e_protect -- and decode any frame's bytes
// (random, every bit set somewhere) to unpack_raw's values.
TEST(SignalLayout, TypedServoFramesEqualTheTableDrivenCodec) {
  std::mt19937 rng(5);
  auto expect_frame = [](MessageKind kind, const std::int64_t* raw, std::uint8_t counter, const CanFrame& f) {
    const Message& m = message(kind);
    std::uint8_t want[kMaxCanFdPayload] = {};
    pack_raw(m, raw, want);
    e2e_protect(want, m.length, m.data_id, counter);
    LONGS_EQUAL(m.can_id, f.id);
    LONGS_EQUAL(m.length, f.len);
    MEMCMP_EQUAL(want, f.data, kMaxCanFdPayload);
  };
  for (int i = 0; i < 2000; ++i) {
    const auto counter = static_cast<std::uint8_t>(rng());
    CanFrame f{};
    // Encoders.
    const io::SensorSample s = random_sample(rng);
    encode_sensor(s, counter, f);
    {
      std::int64_t raw[kSensorSignals.size()] = {0, counter};
      std::size_t k = 2;
      for (auto c : s.interferometer_counts) raw[k++] = c;
      for (auto c : s.displacement_adc) raw[k++] = c;
      for (auto c : s.hall_adc) raw[k++] = c;
      raw[k++] = s.status_flags;
      expect_frame(MessageKind::kSensor, raw, counter, f);
    }
    const io::ActuatorCommand a = random_command(rng);
    encode_actuator(a, counter, f);
    {
      std::int64_t raw[kActuatorSignals.size()] = {0, counter};
      for (std::size_t j = 0; j < io::kCoils; ++j) raw[2 + j] = a.dac_code[j];
      raw[2 + io::kCoils] = a.amplifier_enable ? 1 : 0;
      expect_frame(MessageKind::kActuator, raw, counter, f);
    }
    CurrentMonitorFrame cm{};
    for (auto& c : cm.coil_current_adc) c = static_cast<std::int16_t>(rng());
    encode_current_monitor(cm, counter, f);
    {
      std::int64_t raw[kCurrentMonitorSignals.size()] = {0, counter};
      for (std::size_t j = 0; j < io::kCoils; ++j) raw[2 + j] = cm.coil_current_adc[j];
      expect_frame(MessageKind::kCurrentMonitor, raw, counter, f);
    }
    // Decoders, on random bytes.
    CanFrame r{};
    for (auto& b : r.data) b = static_cast<std::uint8_t>(rng());
    std::int64_t raw[kMaxSignals];
    io::SensorSample ds{};
    decode_sensor(r, ds);
    unpack_raw(message(MessageKind::kSensor), r.data, raw);
    std::size_t k = 2;
    for (auto c : ds.interferometer_counts) LONGS_EQUAL(static_cast<std::uint32_t>(raw[k++]), c);
    for (auto c : ds.displacement_adc) LONGS_EQUAL(static_cast<std::int16_t>(raw[k++]), c);
    for (auto c : ds.hall_adc) LONGS_EQUAL(static_cast<std::int16_t>(raw[k++]), c);
    LONGS_EQUAL(static_cast<std::uint16_t>(raw[k++]), ds.status_flags);
    io::ActuatorCommand da{};
    decode_actuator(r, da);
    unpack_raw(message(MessageKind::kActuator), r.data, raw);
    for (std::size_t j = 0; j < io::kCoils; ++j) LONGS_EQUAL(static_cast<std::int16_t>(raw[2 + j]), da.dac_code[j]);
    CHECK_EQUAL(raw[2 + io::kCoils] != 0, da.amplifier_enable);
    CurrentMonitorFrame dcm{};
    decode_current_monitor(r, dcm);
    unpack_raw(message(MessageKind::kCurrentMonitor), r.data, raw);
    for (std::size_t j = 0; j < io::kCoils; ++j) LONGS_EQUAL(static_cast<std::int16_t>(raw[2 + j]), dcm.coil_current_adc[j]);
  }
}
