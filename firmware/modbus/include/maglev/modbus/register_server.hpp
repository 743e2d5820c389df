// The Modbus semantics of the register map, transport-free: one PDU in, one
// PDU out. The RTU server (firmware) and the libmodbus TCP adapter (bench)
// both drive this class, so the map behaves identically on both transports.
//
// A write (0x06, 0x10, 0x17) is validated WHOLE before anything changes:
//   02 illegal data address  unknown/gap address, read-only register, or a
//                            range that cuts an I32/F32 in half
//   01 illegal function      engineer register while the engineer key is not
//                            written (the server is "in the wrong state for
//                            this request", Modbus spec 7)
//   03 illegal data value    value out of [min, max], NaN, bad count, or the
//                            kernel refused the resulting configuration
//   06 server device busy    the register may not be written now (moving,
//                            levitating) -- retry later
//   04 server device failure config.save could not write flash
// and then applied whole: configuration first (one apply_config call), then
// control registers in address order, cmd.code last.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/register_schema/register_map.hpp"

namespace maglev::modbus {

enum class ExceptionCode : std::uint8_t {
  kNone = 0,
  kIllegalFunction = 0x01,
  kIllegalDataAddress = 0x02,
  kIllegalDataValue = 0x03,
  kServerDeviceFailure = 0x04,
  kServerDeviceBusy = 0x06,
};

enum class Activity : std::uint8_t {
  kIdle,     // landed / not levitating: everything may be written
  kHolding,  // levitating, no reference running
  kMoving,   // a reference (move, step, circle, ...) is running
};

// What the register map needs from the stage. Implemented by the controller
// binding (real kernel + persistence); kept abstract so the map semantics
// stay free of the kernel's Scalar template.
class Device {
 public:
  virtual Activity activity() const = 0;
  // A STATUS register's value (pose, state, fault, saturation, moving).
  virtual double read_status(RegId id) const = 0;
  // Apply a whole candidate configuration; on refusal nothing changed.
  // kBusy: the kernel locks it in its present state (reply 06), kRefused: the
  // values are inconsistent (reply 03). On kApplied the device may have
  // rewritten other entries of `config` to what it applied (selecting a
  // stage profile loads that profile's gains and limits): the server keeps
  // the image as the device left it.
  enum class ApplyResult : std::uint8_t { kApplied, kRefused, kBusy };
  virtual ApplyResult apply_config(ConfigImage& config, bool live_tuning) = 0;
  // The board's critical section (mask / unmask the servo tick). A device
  // that takes it masks only the short commit of apply_config and returns
  // true; the caller then must not mask the whole call (a configuration's
  // validation and loop designs take ~9 ms on the M7: ~22 ticks at 2.5 kHz
  // held at their last output). Default: false, the caller masks it all.
  virtual bool set_critical_section(void (* /*enter*/)(), void (* /*exit*/)()) { return false; }
  // Run a motion command; returns 0 when accepted, else a kernel result code.
  // code: can::HostCommandCode value (cmd.code); 0 = none.
  virtual std::uint16_t command(std::uint16_t code, std::uint16_t axis, float value) = 0;
  // Persist `config`; false when flash failed.
  virtual bool save_config(const ConfigImage& config) = 0;
  virtual PersistStatus persist_status() const = 0;
  // Entries the device changed by itself since (the kernel's coupling
  // calibration writes its correction): copied into `config` before every
  // request, so reads, writes and config.save see them. Default: none.
  virtual void sync_config(ConfigImage& /*config*/) {}

 protected:
  Device() = default;
  Device(const Device&) = default;
  Device& operator=(const Device&) = default;
  ~Device() = default;
};

// One register of a validated write request (its def and its raw 32-bit value).
struct PendingWrite {
  const RegisterDef* def;
  std::uint32_t raw;
};

// The lab tools behind the Kind::kLab registers (recorder, wave generator:
// firmware/lab_tools/registers). Without one, kLab addresses answer 02.
class LabTools {
 public:
  // A kLab register's raw value (U16 in the low half, I32/F32 bits).
  virtual std::uint32_t read(RegId id) const = 0;
  // Words [first, first + count) of a kBlock register; an exception code
  // (06: nothing to read now) refuses the whole read.
  virtual ExceptionCode read_block(RegId id, std::uint16_t first, std::uint16_t count, std::uint16_t* out) const = 0;
  // The whole request's writes (every kind, address order; kLab ones are the
  // lab's): commit false = check only (nothing changes), true = apply. Called
  // with commit true only after a check passed and the rest was applied.
  virtual ExceptionCode write(const PendingWrite* writes, std::size_t n, bool commit) = 0;

 protected:
  LabTools() = default;
  LabTools(const LabTools&) = default;
  LabTools& operator=(const LabTools&) = default;
  ~LabTools() = default;
};

inline constexpr std::size_t kMaxPdu = 253;
inline constexpr std::uint16_t kMaxReadCount = 125;
inline constexpr std::uint16_t kMaxWriteCount = 123;
inline constexpr std::uint16_t kMaxRwWriteCount = 121;

class RegisterServer {
 public:
  RegisterServer(Device& device, const ConfigImage& initial);

  // Handle one request PDU (function code first). Writes the response PDU to
  // `resp` (>= kMaxPdu bytes) and returns its length. For a broadcast request
  // writes are applied and 0 is returned (no reply); broadcast reads are ignored.
  std::size_t handle_pdu(const std::uint8_t* req, std::size_t len, std::uint8_t* resp, bool broadcast);

  // The same semantics without framing (tests, the app).
  ExceptionCode read_registers(std::uint16_t start, std::uint16_t count, std::uint16_t* out) const;
  ExceptionCode write_registers(std::uint16_t start, std::uint16_t count, const std::uint16_t* values);

  const ConfigImage& config() const { return config_; }
  Access level() const { return level_; }
  // Engineering access relocks by itself: after kEngineerRelock_us without a
  // successful write, the level falls back to operator (and live tuning off),
  // so a forgotten engineer session does not leave the gains open. The
  // caller advances the clock (the board's service loop, the bench's tick).
  static constexpr std::uint64_t kEngineerRelock_us = 10ull * 60ull * 1000000ull;  // 10 min
  void advance_time_us(std::uint32_t dt_us);
  bool live_tuning() const { return live_tuning_; }
  // The configuration now matches what flash holds (after load or save).
  void mark_saved() { saved_ = config_; }
  // Takes in what the device changed by itself (Device::sync_config);
  // handle_pdu does it before every request, direct callers before theirs.
  void sync() { device_.sync_config(config_); }
  // The lab tools serving the kLab registers (nullptr: none, 02).
  void set_lab_tools(LabTools* lab) { lab_ = lab; }

 private:
  using Pending = PendingWrite;
  ExceptionCode validate_write(std::uint16_t start, std::uint16_t count, const std::uint16_t* values,
                               std::size_t& n_pending) ;
  ExceptionCode apply_pending(std::size_t n_pending);
  std::uint32_t read_raw(const RegisterDef& d) const;
  bool may_write_now(const RegisterDef& d) const;

  Device& device_;
  ConfigImage config_;
  ConfigImage saved_;
  Access level_ = Access::kOperator;
  std::uint64_t engineer_idle_us_ = 0;  // since the last successful write at engineer level
  bool live_tuning_ = false;
  std::uint16_t cmd_axis_ = 0;
  float cmd_value_ = 0.0f;
  std::uint16_t cmd_code_ = 0;
  std::uint16_t cmd_result_ = 0;
  Pending pending_[kMaxWriteCount];
  LabTools* lab_ = nullptr;
  bool lab_pending_ = false;  // the validated request carries kLab writes
};

}  // namespace maglev::modbus
