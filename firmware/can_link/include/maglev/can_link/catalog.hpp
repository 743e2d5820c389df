// THE message catalog of the maglev CAN FD link, defined once. The firmware
// codec (codec.hpp), the generated DBC (host-tools/can/maglev.dbc) and the
// tables in docs/CAN.md all come from these constexpr tables.
//
// Bus: CAN FD, 1 Mbit/s nominal, 5 Mbit/s data (BRS), 11-bit IDs. Every frame
// starts with the 3-byte E2E header (e2e.hpp): crc (16 bit), counter (8 bit).
// Signals are little endian (DBC "@1", Intel), bit numbers as in DBC.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "maglev/can_link/host_commands.hpp"
#include "maglev/io/sensor_sample.hpp"
#include "maglev/io/stage_parameters.hpp"

namespace maglev::can {

struct Signal {
  const char* name;
  std::uint16_t start_bit;   // LSB position, Intel numbering (byte * 8 + bit)
  std::uint8_t length_bits;  // 1..32
  bool is_signed;
  double factor;  // physical = raw * factor + offset
  double offset;
  double min;     // physical range; raw values outside it are rejected
  double max;
  const char* unit;
  const char* comment;
  // true: the 64 bits are an IEEE-754 binary64 value (DBC SIG_VALTYPE_ 2),
  // factor 1, offset 0; [min, max] bound the value, NaN/inf are rejected.
  bool is_float64;
};

struct Message {
  const char* name;
  std::uint32_t can_id;   // 11-bit; lower = higher priority
  std::uint8_t length;    // bytes, a valid CAN FD length
  std::uint16_t data_id;  // E2E data ID (never transmitted)
  std::uint8_t max_delta_counter;  // counter jump still accepted (jump-1 frames lost)
  std::uint16_t period_ticks;      // sent every N servo ticks (0 = event/aperiodic)
  const char* sender;
  const char* receiver;
  const Signal* signals;
  std::uint8_t signal_count;
  const char* comment;
};

// ---- helpers to write the tables ------------------------------------------
namespace catalog_detail {
constexpr double raw_min(std::uint8_t bits, bool is_signed) {
  if (!is_signed) return 0.0;
  return -static_cast<double>(std::uint64_t{1} << (bits - 1));
}
constexpr double raw_max(std::uint8_t bits, bool is_signed) {
  const std::uint64_t span = is_signed ? (std::uint64_t{1} << (bits - 1)) : (std::uint64_t{1} << bits);
  return static_cast<double>(span - 1);
}
// Full-range signal: min/max follow from the raw range.
constexpr Signal sig(const char* name, std::uint8_t bits, bool is_signed, double factor,
                     const char* unit, const char* comment, double offset = 0.0) {
  return Signal{name, 0, bits, is_signed, factor, offset,
                raw_min(bits, is_signed) * factor + offset, raw_max(bits, is_signed) * factor + offset,
                unit, comment, false};
}
// Limited-range signal (enums, booleans): raw outside [min,max] is rejected.
constexpr Signal sig_range(const char* name, std::uint8_t bits, double min, double max,
                           const char* unit, const char* comment) {
  return Signal{name, 0, bits, false, 1.0, 0.0, min, max, unit, comment, false};
}
// IEEE-754 binary64 argument: exact for any double the host computes, so a
// command sent over CAN is bit-identical to the one applied in process.
constexpr Signal sig_f64(const char* name, double min, double max, const char* unit, const char* comment) {
  return Signal{name, 0, 64, true, 1.0, 0.0, min, max, unit, comment, true};
}
// Prepends the E2E header and assigns start bits back to back.
template <std::size_t N>
constexpr std::array<Signal, N + 2> layout(const std::array<Signal, N>& payload) {
  std::array<Signal, N + 2> out{};
  out[0] = sig("e2e_crc", 16, false, 1.0, "", "CRC-16/CCITT-FALSE over bytes 2..len-1 and the data ID");
  out[1] = sig("e2e_counter", 8, false, 1.0, "", "sequence counter, +1 per frame, wraps");
  for (std::size_t i = 0; i < N; ++i) out[i + 2] = payload[i];
  std::uint16_t bit = 0;
  for (auto& s : out) {
    s.start_bit = bit;
    bit = static_cast<std::uint16_t>(bit + s.length_bits);
  }
  return out;
}
template <std::size_t N>
constexpr std::uint16_t used_bits(const std::array<Signal, N>& s) {
  return static_cast<std::uint16_t>(s[N - 1].start_bit + s[N - 1].length_bits);
}

// Scales (exact binary fractions of the seed stage's electronics).
inline constexpr double kAdcVoltPerCode = io::stage::kAdcFullScale_V / 32768.0;  // 305.2 uV
inline constexpr double kCurrentMonitorAmpPerCode =
    kAdcVoltPerCode / io::stage::kCurrentMonitorGain_V_per_A;                  // 152.6 uA
inline constexpr double kDacAmpPerCode =
    io::stage::kDacFullScale_V / 32768.0 * io::stage::kAmplifierGain_A_per_V;  // 152.6 uA
inline constexpr double kInterferometerNmPerCount = io::stage::kInterferometerLsb_m * 1e9;
}  // namespace catalog_detail

// ---- signal tables ----------------------------------------------------------
// Raw-value order of every table = the order the codec's typed encoders fill
// (index 0 e2e_crc, 1 e2e_counter, then the payload).
namespace cd = catalog_detail;

inline constexpr auto kSyncSignals = cd::layout(std::array<Signal, 2>{
    cd::sig("tick", 32, false, 1.0, "tick", "servo tick number of the time master"),
    cd::sig("time_us", 32, false, 1.0, "us", "time master's monotonic clock, wraps"),
});

inline constexpr auto kActuatorSignals = cd::layout(std::array<Signal, 9>{
    cd::sig("dac_code_0", 16, true, cd::kDacAmpPerCode, "A", "coil 1 AD5764 code (amplifier current command)"),
    cd::sig("dac_code_1", 16, true, cd::kDacAmpPerCode, "A", "coil 2"),
    cd::sig("dac_code_2", 16, true, cd::kDacAmpPerCode, "A", "coil 3"),
    cd::sig("dac_code_3", 16, true, cd::kDacAmpPerCode, "A", "coil 4"),
    cd::sig("dac_code_4", 16, true, cd::kDacAmpPerCode, "A", "coil 5"),
    cd::sig("dac_code_5", 16, true, cd::kDacAmpPerCode, "A", "coil 6"),
    cd::sig("dac_code_6", 16, true, cd::kDacAmpPerCode, "A", "coil 7"),
    cd::sig("dac_code_7", 16, true, cd::kDacAmpPerCode, "A", "coil 8"),
    cd::sig_range("amplifier_enable", 8, 0, 1, "", "1 = amplifiers enabled; 0 = zero current"),
});

inline constexpr auto kSensorSignals = cd::layout(std::array<Signal, 11>{
    cd::sig("interferometer_count_0", 32, false, cd::kInterferometerNmPerCount, "nm", "axis x, wrapping counter"),
    cd::sig("interferometer_count_1", 32, false, cd::kInterferometerNmPerCount, "nm", "axis y1, wrapping counter"),
    cd::sig("interferometer_count_2", 32, false, cd::kInterferometerNmPerCount, "nm", "axis y2, wrapping counter"),
    cd::sig("displacement_adc_0", 16, true, cd::kAdcVoltPerCode, "V", "laser displacement sensor 1, AD7606 code"),
    cd::sig("displacement_adc_1", 16, true, cd::kAdcVoltPerCode, "V", "laser displacement sensor 2"),
    cd::sig("displacement_adc_2", 16, true, cd::kAdcVoltPerCode, "V", "laser displacement sensor 3"),
    cd::sig("hall_adc_0", 16, true, cd::kAdcVoltPerCode, "V", "Hall A.Bx"),
    cd::sig("hall_adc_1", 16, true, cd::kAdcVoltPerCode, "V", "Hall A.By"),
    cd::sig("hall_adc_2", 16, true, cd::kAdcVoltPerCode, "V", "Hall B.Bx"),
    cd::sig("hall_adc_3", 16, true, cd::kAdcVoltPerCode, "V", "Hall B.By"),
    cd::sig("status_flags", 16, false, 1.0, "", "io::SensorStatusBit: bit0-2 beam loss, 3-5 LDS out of range, 6 ADC fault, 7 stale"),
});

inline constexpr auto kCurrentMonitorSignals = cd::layout(std::array<Signal, 8>{
    cd::sig("coil_current_adc_0", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 1 current monitor, AD7606 code"),
    cd::sig("coil_current_adc_1", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 2"),
    cd::sig("coil_current_adc_2", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 3"),
    cd::sig("coil_current_adc_3", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 4"),
    cd::sig("coil_current_adc_4", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 5"),
    cd::sig("coil_current_adc_5", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 6"),
    cd::sig("coil_current_adc_6", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 7"),
    cd::sig("coil_current_adc_7", 16, true, cd::kCurrentMonitorAmpPerCode, "A", "coil 8"),
});

inline constexpr auto kControllerStatusSignals = cd::layout(std::array<Signal, 19>{
    cd::sig("x_nm", 32, true, 1.0, "nm", "pose x (controller's estimate)"),
    cd::sig("y_nm", 32, true, 1.0, "nm", "pose y"),
    cd::sig("z_nm", 32, true, 1.0, "nm", "pose z (height above rest)"),
    cd::sig("theta_x_nrad", 32, true, 1.0, "nrad", "pose theta_x"),
    cd::sig("theta_y_nrad", 32, true, 1.0, "nrad", "pose theta_y"),
    cd::sig("theta_z_nrad", 32, true, 1.0, "nrad", "pose theta_z"),
    cd::sig_range("sequencer_state", 8, 0, 15, "", "kernel sequencer state enum"),
    cd::sig("fault_code", 16, false, 1.0, "", "kernel fault code, 0 = none"),
    cd::sig("saturation_flags", 8, false, 1.0, "", "bit j: coil j+1 command saturated"),
    cd::sig("scale_k", 16, false, 1.0 / 10000.0, "", "force scale k (sequencer ramp), 1e-4 per LSB"),
    cd::sig("current_command_0", 16, true, 0.001, "A", "coil 1 commanded current"),
    cd::sig("current_command_1", 16, true, 0.001, "A", "coil 2"),
    cd::sig("current_command_2", 16, true, 0.001, "A", "coil 3"),
    cd::sig("current_command_3", 16, true, 0.001, "A", "coil 4"),
    cd::sig("current_command_4", 16, true, 0.001, "A", "coil 5"),
    cd::sig("current_command_5", 16, true, 0.001, "A", "coil 6"),
    cd::sig("current_command_6", 16, true, 0.001, "A", "coil 7"),
    cd::sig("current_command_7", 16, true, 0.001, "A", "coil 8"),
    cd::sig("tick", 32, false, 1.0, "tick", "servo tick this status belongs to"),
});

inline constexpr auto kHeartbeatSignals = cd::layout(std::array<Signal, 4>{
    cd::sig_range("node_state", 8, 0, 3, "", "0 init, 1 operational, 2 fault, 3 stopped"),
    cd::sig("uptime_ms", 32, false, 1.0, "ms", "sender's uptime, wraps"),
    cd::sig("rx_rejected", 16, false, 1.0, "", "frames the sender rejected (all reasons), saturating"),
    cd::sig("bus_errors", 16, false, 1.0, "", "error frames the sender observed, saturating"),
});

// Host command (host/bench -> controller node), sporadic. command_code is
// can::HostCommandCode; the value slots carry that command's named fields in
// order (host_commands.hpp: field i -> value_slot_i, IEEE binary64, unused 0).
// The DBC shows them as signals multiplexed by command_code, one named set
// per command; nothing but the codec uses the slots.
inline constexpr double kHostCommandArgLimit = 1e9;  // any sane SI argument; NaN/inf rejected
inline constexpr auto kHostCommandSignals = cd::layout(std::array<Signal, 8>{
    cd::sig_range("command_code", 8, 1, kHostCommandCodeMax, "", "can::HostCommandCode (home, levitate, ..., shutdown)"),
    cd::sig_range("axis", 8, 0, 5, "", "kernel::Axis: 0 x, 1 y, 2 theta_z, 3 z, 4 theta_x, 5 theta_y"),
    cd::sig("command_seq", 16, false, 1.0, "", "sender's command number, echoed by host_command_ack"),
    cd::sig_f64("value_slot_0", -kHostCommandArgLimit, kHostCommandArgLimit, "SI", "field 0 of the command"),
    cd::sig_f64("value_slot_1", -kHostCommandArgLimit, kHostCommandArgLimit, "SI", "field 1 of the command"),
    cd::sig_f64("value_slot_2", -kHostCommandArgLimit, kHostCommandArgLimit, "SI", "field 2 of the command"),
    cd::sig_f64("value_slot_3", -kHostCommandArgLimit, kHostCommandArgLimit, "SI", "field 3 of the command"),
    cd::sig_f64("value_slot_4", -kHostCommandArgLimit, kHostCommandArgLimit, "SI", "field 4 of the command"),
});
static_assert(kHostCommandMaxFields == 5, "one value slot per field");

inline constexpr auto kHostCommandAckSignals = cd::layout(std::array<Signal, 5>{
    cd::sig("command_seq", 16, false, 1.0, "", "command_seq of the host_command answered"),
    cd::sig_range("command_code", 8, 1, kHostCommandCodeMax, "", "its command_code"),
    cd::sig_range("result", 8, 0, 15, "", "kernel::CommandResult (0 accepted); 15 = not executed by the node"),
    cd::sig_range("sequencer_state", 8, 0, 15, "", "kernel sequencer state after the command"),
    cd::sig("tick", 32, false, 1.0, "tick", "controller ticks run before the command took effect"),
});

// ---- messages -----------------------------------------------------------------
enum class MessageKind : std::uint8_t {
  kSync = 0,
  kActuator,
  kSensor,
  kCurrentMonitor,
  kControllerStatus,
  kHeartbeatController,
  kHeartbeatPlant,
  kHostCommand,
  kHostCommandAck,
  kCount,
};
inline constexpr std::size_t kMessageCount = static_cast<std::size_t>(MessageKind::kCount);

// Decimation of the slow frames, in servo ticks (2.5 kHz default).
inline constexpr std::uint16_t kCurrentMonitorPeriodTicks = 5;     // 500 Hz
inline constexpr std::uint16_t kControllerStatusPeriodTicks = 10;  // 250 Hz
inline constexpr std::uint16_t kSyncPeriodTicks = 25;              // 100 Hz
inline constexpr std::uint16_t kHeartbeatPeriodTicks = 250;        // 10 Hz

inline constexpr std::array<Message, kMessageCount> kCatalog{{
    {"sync", 0x010, 12, 0x0A01, 1, kSyncPeriodTicks, "controller", "plant",
     kSyncSignals.data(), kSyncSignals.size(),
     "time master's tick broadcast; aligns the plant's tick counter in real-time mode"},
    {"actuator", 0x020, 20, 0x0A02, 3, 1, "controller", "plant",
     kActuatorSignals.data(), kActuatorSignals.size(),
     "io::ActuatorCommand; e2e_counter = counter of the sensor frame it answers"},
    {"sensor", 0x030, 32, 0x0A03, 3, 1, "plant", "controller",
     kSensorSignals.data(), kSensorSignals.size(),
     "io::SensorSample without coil currents; e2e_counter = tick mod 256"},
    {"current_monitor", 0x100, 20, 0x0A04, 3, kCurrentMonitorPeriodTicks, "plant", "controller",
     kCurrentMonitorSignals.data(), kCurrentMonitorSignals.size(),
     "io::SensorSample::coil_current_adc, decimated (supervision, not servo)"},
    {"controller_status", 0x200, 64, 0x0A05, 3, kControllerStatusPeriodTicks, "controller", "plant",
     kControllerStatusSignals.data(), kControllerStatusSignals.size(),
     "telemetry: pose, sequencer state, fault, saturation, scale k, commanded currents"},
    {"heartbeat_controller", 0x701, 12, 0x0A06, 1, kHeartbeatPeriodTicks, "controller", "plant",
     kHeartbeatSignals.data(), kHeartbeatSignals.size(), "controller node liveness"},
    {"heartbeat_plant", 0x702, 12, 0x0A07, 1, kHeartbeatPeriodTicks, "plant", "controller",
     kHeartbeatSignals.data(), kHeartbeatSignals.size(), "plant node liveness"},
    // Sporadic; below the servo pair in priority (a command never delays a
    // sensor or actuator frame), above the decimated telemetry.
    {"host_command", 0x040, 48, 0x0A08, 3, 0, "plant", "controller",
     kHostCommandSignals.data(), kHostCommandSignals.size(),
     "host/bench command to the controller node (sporadic); applied before the next servo tick"},
    {"host_command_ack", 0x041, 12, 0x0A09, 3, 0, "controller", "plant",
     kHostCommandAckSignals.data(), kHostCommandAckSignals.size(),
     "controller node's answer to one host_command (sporadic)"},
}};

constexpr const Message& message(MessageKind k) { return kCatalog[static_cast<std::size_t>(k)]; }

// Lookup by CAN ID; nullptr for an unknown ID.
constexpr const Message* find_message(std::uint32_t can_id) {
  for (const auto& m : kCatalog) {
    if (m.can_id == can_id) return &m;
  }
  return nullptr;
}
constexpr int message_index(std::uint32_t can_id) {
  for (std::size_t i = 0; i < kCatalog.size(); ++i) {
    if (kCatalog[i].can_id == can_id) return static_cast<int>(i);
  }
  return -1;
}

// Compile-time sanity of the table: signals fit, IDs unique and 11-bit,
// lengths are valid FD lengths, data IDs unique.
constexpr bool catalog_is_consistent() {
  constexpr std::uint8_t kFdLens[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64};
  for (std::size_t i = 0; i < kCatalog.size(); ++i) {
    const auto& m = kCatalog[i];
    bool len_ok = false;
    for (auto l : kFdLens) len_ok = len_ok || l == m.length;
    if (!len_ok || m.can_id > 0x7FF || m.signal_count == 0) return false;
    const Signal& last = m.signals[m.signal_count - 1];
    if (last.start_bit + last.length_bits > m.length * 8) return false;
    for (std::size_t j = i + 1; j < kCatalog.size(); ++j) {
      if (kCatalog[j].can_id == m.can_id || kCatalog[j].data_id == m.data_id) return false;
    }
  }
  return true;
}
static_assert(catalog_is_consistent(), "CAN catalog: overlapping ID/data ID or signals beyond length");
static_assert(cd::used_bits(kSensorSignals) <= 32 * 8);
static_assert(cd::used_bits(kActuatorSignals) == 20 * 8);
static_assert(cd::used_bits(kControllerStatusSignals) <= 64 * 8);
static_assert(cd::used_bits(kHostCommandSignals) <= 48 * 8);
static_assert(cd::used_bits(kHostCommandAckSignals) == 12 * 8);

// Payload signal counts (without the E2E header), for the typed codec.
inline constexpr std::size_t kMaxSignals = 21;
static_assert(kControllerStatusSignals.size() <= kMaxSignals);

}  // namespace maglev::can
