// Table-driven pack/unpack for the catalog (catalog.hpp) plus the typed
// encoders/decoders the plant, the controller and the board use.
// Heap-free, exception-free; compiles for the Cortex-M7 target.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/host_commands.hpp"
#include "maglev/can_port/can_port.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::can {

// Why a received frame was rejected (or kOk). Every receiver counts these per
// reason; a rejected frame is never applied.
enum class RxStatus : std::uint8_t {
  kOk = 0,
  kUnknownId,      // ID not in the catalog (or not the expected message)
  kWrongLength,    // len differs from the catalog
  kWrongFormat,    // not an FD frame, or extended ID / error frame
  kBadCrc,         // E2E CRC mismatch (corruption or wrong data ID)
  kRepeated,       // same counter as the last accepted frame
  kOutOfOrder,     // counter older than the last accepted frame
  kSequenceJump,   // counter jumped further than max_delta_counter (receiver resyncs)
  kOutOfRange,     // a signal's raw value outside the catalog's [min, max]
  kCount,
};
inline constexpr std::size_t kRxStatusCount = static_cast<std::size_t>(RxStatus::kCount);
const char* to_string(RxStatus s);

// ---- generic codec --------------------------------------------------------------
// Writes raw[i] into signal i of m (raw values are truncated to the signal's
// length); bytes not covered by a signal are zero. data must hold m.length.
void pack_raw(const Message& m, const std::int64_t* raw, std::uint8_t* data);
// Reads every signal of m (sign-extended for signed signals).
void unpack_raw(const Message& m, const std::uint8_t* data, std::int64_t* raw);
std::int64_t read_signal(const Signal& s, const std::uint8_t* data);
void write_signal(const Signal& s, std::int64_t raw, std::uint8_t* data);

// Packs raw (counter taken from the argument, CRC computed) into a ready frame:
// id, len, flags = FD | BRS.
void encode_raw(const Message& m, const std::int64_t* raw, std::uint8_t counter, CanFrame& frame);

// Stateless checks: catalog ID (if expected != nullptr it must be that
// message), FD format, length, CRC, signal ranges. No counter check
// (that is LinkReceiver's job).
RxStatus check_frame(const CanFrame& frame, const Message* expected, const Message** found);
// check_frame with every signal's range checked in every frame: the
// definition check_frame must equal (it skips the signals whose every raw
// value is in range; can_codec_test compares the two).
RxStatus check_frame_all_signals(const CanFrame& frame, const Message* expected, const Message** found);
// Bit i set: check_frame checks signal i of m's range.
std::uint64_t range_checked_signals(const Message& m);

// ---- typed records ------------------------------------------------------------------
struct SyncFrame {
  std::uint32_t tick;
  std::uint32_t time_us;
};

struct CurrentMonitorFrame {
  std::int16_t coil_current_adc[io::kCoils];
};

// The controller's telemetry, in plain scaled integers. Binding to
// maglev::kernel::ControllerStatus (Pose64 pm/prad -> nm/nrad) comes later.
struct ControllerStatusFrame {
  std::int32_t pose_nm_nrad[6];  // x, y, z [nm], theta_x, theta_y, theta_z [nrad]
  std::uint8_t sequencer_state;  // 0..15
  std::uint16_t fault_code;
  std::uint8_t saturation_flags;
  std::uint16_t scale_k_e4;      // k * 10000
  std::int16_t current_command_mA[io::kCoils];
  std::uint32_t tick;
};

enum class NodeState : std::uint8_t { kInit = 0, kOperational = 1, kFault = 2, kStopped = 3 };
struct HeartbeatFrame {
  NodeState node_state;
  std::uint32_t uptime_ms;
  std::uint16_t rx_rejected;
  std::uint16_t bus_errors;
};

// Host commands: host_commands.hpp (one struct per command, named fields).

// Ack result: kernel::CommandResult value, or this when the node did not
// execute the command (e.g. shutdown, or a code it does not implement).
inline constexpr std::uint8_t kHostResultNotExecuted = 15;
struct HostCommandAckFrame {
  std::uint16_t seq;
  HostCommandCode code;
  std::uint8_t result;
  std::uint8_t sequencer_state;
  std::uint32_t tick;
};

// Encoders: build a complete, protected frame.
void encode_sync(const SyncFrame& v, std::uint8_t counter, CanFrame& f);
void encode_actuator(const io::ActuatorCommand& v, std::uint8_t counter, CanFrame& f);
// Sensor frame: everything of the sample except coil_current_adc.
void encode_sensor(const io::SensorSample& v, std::uint8_t counter, CanFrame& f);
void encode_current_monitor(const CurrentMonitorFrame& v, std::uint8_t counter, CanFrame& f);
void encode_controller_status(const ControllerStatusFrame& v, std::uint8_t counter, CanFrame& f);
void encode_heartbeat(MessageKind which, const HeartbeatFrame& v, std::uint8_t counter, CanFrame& f);
void encode_host_command(const HostCommandFrame& v, std::uint8_t counter, CanFrame& f);
void encode_host_command_ack(const HostCommandAckFrame& v, std::uint8_t counter, CanFrame& f);

// Decoders: unpack WITHOUT checks; only call on a frame a LinkReceiver (or
// check_frame) accepted. decode_sensor leaves out.coil_current_adc untouched.
void decode_sync(const CanFrame& f, SyncFrame& out);
void decode_actuator(const CanFrame& f, io::ActuatorCommand& out);
void decode_sensor(const CanFrame& f, io::SensorSample& out);
void decode_current_monitor(const CanFrame& f, CurrentMonitorFrame& out);
void decode_controller_status(const CanFrame& f, ControllerStatusFrame& out);
void decode_heartbeat(const CanFrame& f, HeartbeatFrame& out);
void decode_host_command(const CanFrame& f, HostCommandFrame& out);
void decode_host_command_ack(const CanFrame& f, HostCommandAckFrame& out);

inline std::uint8_t frame_counter(const CanFrame& f) { return f.data[2]; }

}  // namespace maglev::can
