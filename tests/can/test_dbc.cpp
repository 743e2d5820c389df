// Parses the COMMITTED host-tools/can/maglev.dbc with a small independent DBC
// reader and checks every signal against the codec: a random record packed by
// the codec, decoded from the bytes with the DBC's start bit / length / sign /
// factor / offset, must equal the record's field in physical units.
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "maglev/can_link/codec.hpp"
#include "dbc_reader.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using namespace maglev;
using namespace maglev::can;

namespace {
using test::DbcMessage;
using test::DbcSignal;
using test::dbc_decode;
using test::parse_dbc;

std::map<std::uint32_t, DbcMessage>* g_dbc = nullptr;
const std::map<std::uint32_t, DbcMessage>& dbc() { return *g_dbc; }

void check_frame_against_dbc(const CanFrame& f, const std::map<std::string, double>& expected_raw) {
  const auto it = dbc().find(f.id);
  CHECK_TRUE(it != dbc().end());
  LONGS_EQUAL(it->second.length, f.len);
  double mux = -1.0;
  for (const auto& s : it->second.signals) {
    if (s.is_multiplexor) mux = dbc_decode(s, f.data);
  }
  for (const auto& s : it->second.signals) {
    if (s.multiplex_value >= 0 && static_cast<double>(s.multiplex_value) != mux) continue;  // another command's field
    if (s.name == "e2e_crc") {
      DOUBLES_EQUAL(f.data[0] | (f.data[1] << 8), dbc_decode(s, f.data), 0.0);
      continue;
    }
    const auto e = expected_raw.find(s.name);
    if (e == expected_raw.end()) FAIL(("signal not covered by the test: " + s.name).c_str());
    const double want = s.is_float64 ? e->second : e->second * s.factor + s.offset;
    const double got = dbc_decode(s, f.data);
    // The DBC prints factors with 15 significant digits.
    DOUBLES_EQUAL(want, got, std::fabs(want) * 1e-12 + 1e-12);
    CHECK_TRUE(got >= s.min - std::fabs(s.factor) && got <= s.max + std::fabs(s.factor));
  }
}
}  // namespace

TEST_GROUP(Dbc) {
  std::map<std::uint32_t, DbcMessage> parsed;
  void setup() override {
    parsed = parse_dbc(MAGLEV_DBC_PATH);
    g_dbc = &parsed;
  }
  void teardown() override {
    g_dbc = nullptr;
    parsed.clear();
  }
};

TEST(Dbc, SameMessagesAndSignalLayoutAsCatalog) {
  LONGS_EQUAL(kCatalog.size(), dbc().size());
  for (const auto& m : kCatalog) {
    const auto it = dbc().find(m.can_id);
    CHECK_TRUE(it != dbc().end());
    STRCMP_EQUAL(m.name, it->second.name.c_str());
    LONGS_EQUAL(m.length, it->second.length);
    // Every catalog signal is in the DBC with its layout; host_command's value
    // slots appear instead as each command's named fields (multiplexed).
    const bool host_command = &m == &message(MessageKind::kHostCommand);
    std::size_t expected_signals = 0;
    for (std::size_t i = 0; i < m.signal_count; ++i) {
      const std::string name = m.signals[i].name;
      if (host_command && name.rfind("value_slot_", 0) == 0) continue;
      ++expected_signals;
      const DbcSignal* d = nullptr;
      for (const auto& s : it->second.signals) {
        if (s.name == name) d = &s;
      }
      CHECK_TRUE_TEXT(d != nullptr, name.c_str());
      LONGS_EQUAL(m.signals[i].start_bit, d->start);
      LONGS_EQUAL(m.signals[i].length_bits, d->length);
      CHECK_TRUE(d->little_endian);
      CHECK_EQUAL(m.signals[i].is_signed, d->is_signed);
      CHECK_EQUAL(m.signals[i].is_float64, d->is_float64);
      CHECK_EQUAL(host_command && name == "command_code", d->is_multiplexor);
    }
    if (host_command) {
      for (const HostCommandSpec& c : kHostCommandSpecs) {
        for (std::size_t f = 0; f < c.field_count; ++f) {
          ++expected_signals;
          const std::string name = std::string(c.name) + "_" + c.fields[f].name;
          const DbcSignal* d = nullptr;
          for (const auto& s : it->second.signals) {
            if (s.name == name) d = &s;
          }
          CHECK_TRUE_TEXT(d != nullptr, name.c_str());
          LONGS_EQUAL(static_cast<int>(c.code), d->multiplex_value);
          const Signal& slot = m.signals[2 + 3 + f];  // e2e header, code/axis/seq, then the slots
          LONGS_EQUAL(slot.start_bit, d->start);
          CHECK_TRUE(d->is_float64);
        }
      }
    }
    LONGS_EQUAL(expected_signals, it->second.signals.size());
  }
}

TEST(Dbc, EveryMessageDecodesLikeTheCodec) {
  std::mt19937 rng(2024);
  for (int round = 0; round < 200; ++round) {
    const auto counter = static_cast<std::uint8_t>(rng());
    CanFrame f{};
    io::SensorSample s{};
    for (auto& c : s.interferometer_counts) c = static_cast<std::uint32_t>(rng());
    for (auto& c : s.displacement_adc) c = static_cast<std::int16_t>(rng());
    for (auto& c : s.hall_adc) c = static_cast<std::int16_t>(rng());
    s.status_flags = static_cast<std::uint16_t>(rng());
    encode_sensor(s, counter, f);
    std::map<std::string, double> e{{"e2e_counter", counter}, {"status_flags", s.status_flags}};
    for (int i = 0; i < 3; ++i) e["interferometer_count_" + std::to_string(i)] = s.interferometer_counts[i];
    for (int i = 0; i < 3; ++i) e["displacement_adc_" + std::to_string(i)] = s.displacement_adc[i];
    for (int i = 0; i < 4; ++i) e["hall_adc_" + std::to_string(i)] = s.hall_adc[i];
    check_frame_against_dbc(f, e);

    io::ActuatorCommand a{};
    for (auto& c : a.dac_code) c = static_cast<std::int16_t>(rng());
    a.amplifier_enable = (rng() & 1u) != 0;
    encode_actuator(a, counter, f);
    e = {{"e2e_counter", counter}, {"amplifier_enable", a.amplifier_enable ? 1 : 0}};
    for (int i = 0; i < 8; ++i) e["dac_code_" + std::to_string(i)] = a.dac_code[i];
    check_frame_against_dbc(f, e);

    CurrentMonitorFrame cm{};
    for (auto& c : cm.coil_current_adc) c = static_cast<std::int16_t>(rng());
    encode_current_monitor(cm, counter, f);
    e = {{"e2e_counter", counter}};
    for (int i = 0; i < 8; ++i) e["coil_current_adc_" + std::to_string(i)] = cm.coil_current_adc[i];
    check_frame_against_dbc(f, e);

    ControllerStatusFrame cs{};
    for (auto& p : cs.pose_nm_nrad) p = static_cast<std::int32_t>(rng());
    cs.sequencer_state = static_cast<std::uint8_t>(rng() % 16);
    cs.fault_code = static_cast<std::uint16_t>(rng());
    cs.saturation_flags = static_cast<std::uint8_t>(rng());
    cs.scale_k_e4 = static_cast<std::uint16_t>(rng());
    for (auto& c : cs.current_command_mA) c = static_cast<std::int16_t>(rng());
    cs.tick = static_cast<std::uint32_t>(rng());
    encode_controller_status(cs, counter, f);
    e = {{"e2e_counter", counter},         {"x_nm", cs.pose_nm_nrad[0]},
         {"y_nm", cs.pose_nm_nrad[1]},     {"z_nm", cs.pose_nm_nrad[2]},
         {"theta_x_nrad", cs.pose_nm_nrad[3]}, {"theta_y_nrad", cs.pose_nm_nrad[4]},
         {"theta_z_nrad", cs.pose_nm_nrad[5]}, {"sequencer_state", cs.sequencer_state},
         {"fault_code", cs.fault_code},    {"saturation_flags", cs.saturation_flags},
         {"scale_k", cs.scale_k_e4},       {"tick", cs.tick}};
    for (int i = 0; i < 8; ++i) e["current_command_" + std::to_string(i)] = cs.current_command_mA[i];
    check_frame_against_dbc(f, e);

    const HeartbeatFrame hb{static_cast<NodeState>(rng() % 4), static_cast<std::uint32_t>(rng()),
                            static_cast<std::uint16_t>(rng()), static_cast<std::uint16_t>(rng())};
    encode_heartbeat(MessageKind::kHeartbeatPlant, hb, counter, f);
    e = {{"e2e_counter", counter},
         {"node_state", static_cast<double>(hb.node_state)},
         {"uptime_ms", hb.uptime_ms},
         {"rx_rejected", hb.rx_rejected},
         {"bus_errors", hb.bus_errors}};
    check_frame_against_dbc(f, e);

    const SyncFrame sy{static_cast<std::uint32_t>(rng()), static_cast<std::uint32_t>(rng())};
    encode_sync(sy, counter, f);
    check_frame_against_dbc(f, {{"e2e_counter", counter}, {"tick", sy.tick}, {"time_us", sy.time_us}});

    // host_command: multiplexed by command_code, the named fields of that command.
    std::uniform_real_distribution<double> arg(-1.0, 1.0);
    const auto code = static_cast<HostCommandCode>(1 + rng() % kHostCommandCodeMax);
    HostCommandFrame hc{code, static_cast<std::uint8_t>(rng() % 6), static_cast<std::uint16_t>(rng()), {}};
    std::map<std::string, double> he{{"e2e_counter", counter}, {"command_code", static_cast<double>(hc.code)},
                                     {"axis", hc.axis}, {"command_seq", hc.seq}};
    with_args(code, hc.args, [&](auto& args) {
      using A = std::remove_reference_t<decltype(args)>;
      for (const auto& fd : A::kFields) {
        args.*fd.member = arg(rng) * 100.0;
        he[std::string(to_string(code)) + "_" + fd.name] = args.*fd.member;
      }
    });
    encode_host_command(hc, counter, f);
    check_frame_against_dbc(f, he);
    const HostCommandAckFrame ack{static_cast<std::uint16_t>(rng()), static_cast<HostCommandCode>(1 + rng() % 16),
                                  static_cast<std::uint8_t>(rng() % 16), static_cast<std::uint8_t>(rng() % 16),
                                  static_cast<std::uint32_t>(rng())};
    encode_host_command_ack(ack, counter, f);
    check_frame_against_dbc(f, {{"e2e_counter", counter}, {"command_seq", ack.seq},
                                {"command_code", static_cast<double>(ack.code)}, {"result", ack.result},
                                {"sequencer_state", ack.sequencer_state}, {"tick", ack.tick}});
  }
}

TEST(Dbc, PhysicalScalesAreTheStageElectronics) {
  // dac_code LSB in amperes: 10 V / 32768 * 0.5 A/V.
  const auto& act = dbc().at(0x020);
  DOUBLES_EQUAL(10.0 / 32768.0 * 0.5, act.signals[2].factor, 1e-18);
  DOUBLES_EQUAL(-5.0, act.signals[2].min, 1e-12);
  // Interferometer LSB: 632.991 nm / 1024.
  const auto& sen = dbc().at(0x030);
  DOUBLES_EQUAL(632.991 / 1024.0, sen.signals[2].factor, 1e-12);
}
