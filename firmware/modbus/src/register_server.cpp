#include "maglev/modbus/register_server.hpp"

#include <algorithm>
#include <bit>

namespace maglev::modbus {
namespace {

std::uint16_t get_u16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }
void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v & 0xFF);
}

std::size_t exception_reply(std::uint8_t function, ExceptionCode code, std::uint8_t* resp) {
  resp[0] = static_cast<std::uint8_t>(function | 0x80);
  resp[1] = static_cast<std::uint8_t>(code);
  return 2;
}

}  // namespace

RegisterServer::RegisterServer(Device& device, const ConfigImage& initial)
    : device_(device), config_(initial), saved_(initial), pending_{} {}

std::uint32_t RegisterServer::read_raw(const RegisterDef& d) const {
  switch (d.kind) {
    case Kind::kIdent:
      if (d.id == RegId::id_schema_hash) return kSchemaHash;
      return encode(d.type, d.default_value);
    case Kind::kConfig:
    case Kind::kStage:
      return config_.raw[static_cast<std::size_t>(persisted_slot(d.id))];
    case Kind::kStatus: {
      const PersistStatus ps = device_.persist_status();
      switch (d.id) {
        case RegId::persist_flags:
          return static_cast<std::uint16_t>(ps.flags | (config_ == saved_ ? 0u : static_cast<unsigned>(kUnsaved)));
        case RegId::persist_reason:
          return ps.reason;
        case RegId::persist_sequence:
          return ps.sequence;
        case RegId::access_level:
          return static_cast<std::uint32_t>(level_);
        default:
          return encode(d.type, device_.read_status(d.id));
      }
    }
    case Kind::kLab:
      return lab_ != nullptr ? lab_->read(d.id) : 0u;
    case Kind::kControl:
      switch (d.id) {
        case RegId::cmd_axis:
          return cmd_axis_;
        case RegId::cmd_value:
          return std::bit_cast<std::uint32_t>(cmd_value_);
        case RegId::cmd_code:
          return cmd_code_;
        case RegId::cmd_result:
          return cmd_result_;
        case RegId::tuning_live:
          return live_tuning_ ? 1u : 0u;
        default:
          return 0;  // access.key and config.save read 0: the key is never echoed
      }
  }
  return 0;
}

ExceptionCode RegisterServer::read_registers(std::uint16_t start, std::uint16_t count, std::uint16_t* out) const {
  if (count == 0 || count > kMaxReadCount) return ExceptionCode::kIllegalDataValue;
  if (static_cast<std::uint32_t>(start) + count > 0x10000u) return ExceptionCode::kIllegalDataAddress;
  // Check the whole range first: a gap anywhere refuses the whole read.
  const std::uint32_t end = static_cast<std::uint32_t>(start) + count;
  for (std::uint32_t a = start; a < end; ++a) {
    const RegisterDef* d = find_by_address(static_cast<std::uint16_t>(a));
    if (d == nullptr || (d->kind == Kind::kLab && lab_ == nullptr)) return ExceptionCode::kIllegalDataAddress;
  }
  for (std::uint32_t a = start; a < end; ++a) {
    const RegisterDef* d = find_by_address(static_cast<std::uint16_t>(a));
    if (d == nullptr) return ExceptionCode::kIllegalDataAddress;  // checked above; keeps the analyser sure
    if (d->type == RegType::kBlock) {
      // One call for the part of the block inside the range.
      const std::uint32_t block_end = std::min<std::uint32_t>(end, static_cast<std::uint32_t>(d->address) + width(d->type));
      const auto n = static_cast<std::uint16_t>(block_end - a);
      const ExceptionCode e = lab_->read_block(d->id, static_cast<std::uint16_t>(a - d->address), n, out + (a - start));
      if (e != ExceptionCode::kNone) return e;
      a = block_end - 1u;
      continue;
    }
    const std::uint32_t raw = read_raw(*d);
    if (width(d->type) == 1) {
      out[a - start] = static_cast<std::uint16_t>(raw);
    } else {
      // ABCD: high word at the lower address.
      out[a - start] = a == d->address ? static_cast<std::uint16_t>(raw >> 16) : static_cast<std::uint16_t>(raw & 0xFFFF);
    }
  }
  return ExceptionCode::kNone;
}

bool RegisterServer::may_write_now(const RegisterDef& d) const {
  const Activity act = device_.activity();
  switch (d.when) {
    case WriteWhen::kNever:
      return false;
    case WriteWhen::kAlways:
      return true;
    case WriteWhen::kNotMoving:
      return act != Activity::kMoving;
    case WriteWhen::kIdle:
      return act == Activity::kIdle;
    case WriteWhen::kGains:
      // The kernel locks gains whenever the stage is off its rest, unless
      // live tuning is on (Controller::apply_config, kGainsLockedWhileLevitated).
      return live_tuning_ || act == Activity::kIdle;
  }
  return false;
}

ExceptionCode RegisterServer::validate_write(std::uint16_t start, std::uint16_t count, const std::uint16_t* values,
                                             std::size_t& n_pending) {
  n_pending = 0;
  if (count == 0 || count > kMaxWriteCount) return ExceptionCode::kIllegalDataValue;
  const std::uint32_t end = static_cast<std::uint32_t>(start) + count;
  if (end > 0x10000u) return ExceptionCode::kIllegalDataAddress;
  // 1. addressing: every register known, writable, every I32/F32 complete.
  for (std::uint32_t a = start; a < end;) {
    const RegisterDef* d = find_by_address(static_cast<std::uint16_t>(a));
    if (d == nullptr || d->address != a) return ExceptionCode::kIllegalDataAddress;
    const std::uint16_t w = width(d->type);
    if (a + w > end) return ExceptionCode::kIllegalDataAddress;
    if (d->access == Access::kReadOnly || d->when == WriteWhen::kNever) return ExceptionCode::kIllegalDataAddress;
    if (d->kind == Kind::kLab && lab_ == nullptr) return ExceptionCode::kIllegalDataAddress;
    const std::uint32_t raw = w == 1 ? values[a - start]
                                     : (static_cast<std::uint32_t>(values[a - start]) << 16) | values[a - start + 1];
    pending_[n_pending++] = Pending{d, raw};
    a += w;
  }
  // 2. access level.
  for (std::size_t i = 0; i < n_pending; ++i) {
    if (pending_[i].def->access == Access::kEngineer && level_ != Access::kEngineer) {
      return ExceptionCode::kIllegalFunction;
    }
  }
  // 3. values.
  for (std::size_t i = 0; i < n_pending; ++i) {
    if (!value_in_range(*pending_[i].def, decode(pending_[i].def->type, pending_[i].raw))) {
      return ExceptionCode::kIllegalDataValue;
    }
  }
  // 4. write condition (state of the machine now).
  for (std::size_t i = 0; i < n_pending; ++i) {
    if (!may_write_now(*pending_[i].def)) return ExceptionCode::kServerDeviceBusy;
  }
  // 5. the lab tools check their part whole (signals, channel count, limits, Nyquist, busy).
  lab_pending_ = false;
  for (std::size_t i = 0; i < n_pending; ++i) lab_pending_ = lab_pending_ || pending_[i].def->kind == Kind::kLab;
  if (lab_pending_) return lab_->write(pending_, n_pending, false);
  return ExceptionCode::kNone;
}

ExceptionCode RegisterServer::apply_pending(std::size_t n_pending) {
  // Configuration: one candidate, applied whole by the kernel or not at all.
  ConfigImage candidate = config_;
  bool config_touched = false;
  for (std::size_t i = 0; i < n_pending; ++i) {
    const RegisterDef& d = *pending_[i].def;
    if (d.kind != Kind::kConfig && d.kind != Kind::kStage) continue;
    candidate.raw[static_cast<std::size_t>(persisted_slot(d.id))] = pending_[i].raw;
    config_touched = true;
  }
  if (config_touched && !(candidate == config_)) {
    switch (device_.apply_config(candidate, live_tuning_)) {
      case Device::ApplyResult::kApplied:
        break;
      case Device::ApplyResult::kBusy:
        return ExceptionCode::kServerDeviceBusy;
      case Device::ApplyResult::kRefused:
        return ExceptionCode::kIllegalDataValue;
    }
    config_ = candidate;
  }
  // The lab tools (checked in validate_write): before the commands.
  if (lab_pending_) {
    const ExceptionCode e = lab_->write(pending_, n_pending, true);
    if (e != ExceptionCode::kNone) return e;
  }
  // Control registers in address order; the command itself last so one 0x10
  // can carry axis, value and code.
  bool run_command = false;
  bool save = false;
  for (std::size_t i = 0; i < n_pending; ++i) {
    const RegisterDef& d = *pending_[i].def;
    const std::uint32_t raw = pending_[i].raw;
    switch (d.id) {
      case RegId::cmd_axis:
        cmd_axis_ = static_cast<std::uint16_t>(raw);
        break;
      case RegId::cmd_value:
        cmd_value_ = std::bit_cast<float>(raw);
        break;
      case RegId::cmd_code:
        cmd_code_ = static_cast<std::uint16_t>(raw);
        run_command = cmd_code_ != 0;
        break;
      case RegId::access_key:
        level_ = raw == kEngineerKey ? Access::kEngineer : Access::kOperator;
        if (level_ != Access::kEngineer) live_tuning_ = false;
        break;
      case RegId::tuning_live:
        live_tuning_ = raw != 0;
        break;
      case RegId::config_save:
        save = raw != 0;
        break;
      default:
        break;
    }
  }
  if (save) {
    if (!device_.save_config(config_)) return ExceptionCode::kServerDeviceFailure;
    saved_ = config_;
  }
  if (run_command) {
    cmd_result_ = device_.command(cmd_code_, cmd_axis_, cmd_value_);
  }
  return ExceptionCode::kNone;
}

ExceptionCode RegisterServer::write_registers(std::uint16_t start, std::uint16_t count, const std::uint16_t* values) {
  std::size_t n = 0;
  const ExceptionCode e = validate_write(start, count, values, n);
  if (e != ExceptionCode::kNone) return e;
  const ExceptionCode r = apply_pending(n);
  if (r == ExceptionCode::kNone) engineer_idle_us_ = 0;
  return r;
}

void RegisterServer::advance_time_us(std::uint32_t dt_us) {
  if (level_ != Access::kEngineer) return;
  engineer_idle_us_ += dt_us;
  if (engineer_idle_us_ >= kEngineerRelock_us) {
    level_ = Access::kOperator;
    live_tuning_ = false;
    engineer_idle_us_ = 0;
  }
}

std::size_t RegisterServer::handle_pdu(const std::uint8_t* req, std::size_t len, std::uint8_t* resp, bool broadcast) {
  if (len < 1) return 0;
  sync();
  const std::uint8_t fc = req[0];
  std::uint16_t words[kMaxReadCount];
  ExceptionCode e = ExceptionCode::kNone;
  std::size_t n = 0;
  switch (fc) {
    case 0x03:
    case 0x04: {
      if (broadcast) return 0;
      if (len != 5) return exception_reply(fc, ExceptionCode::kIllegalDataValue, resp);
      const std::uint16_t start = get_u16(req + 1);
      const std::uint16_t count = get_u16(req + 3);
      e = read_registers(start, count, words);
      if (e != ExceptionCode::kNone) break;
      resp[0] = fc;
      resp[1] = static_cast<std::uint8_t>(count * 2);
      for (std::uint16_t i = 0; i < count; ++i) put_u16(resp + 2 + 2 * i, words[i]);
      return 2u + 2u * count;
    }
    case 0x06: {
      if (len != 5) {
        e = ExceptionCode::kIllegalDataValue;
        break;
      }
      const std::uint16_t addr = get_u16(req + 1);
      words[0] = get_u16(req + 3);
      e = write_registers(addr, 1, words);
      if (e != ExceptionCode::kNone) break;
      if (broadcast) return 0;
      for (std::size_t i = 0; i < 5; ++i) resp[i] = req[i];  // echo
      return 5;
    }
    case 0x10: {
      if (len < 6) {
        e = ExceptionCode::kIllegalDataValue;
        break;
      }
      const std::uint16_t start = get_u16(req + 1);
      const std::uint16_t count = get_u16(req + 3);
      const std::uint8_t bytes = req[5];
      if (count == 0 || count > kMaxWriteCount || bytes != count * 2 || len != 6u + bytes) {
        e = ExceptionCode::kIllegalDataValue;
        break;
      }
      for (std::uint16_t i = 0; i < count; ++i) words[i] = get_u16(req + 6 + 2 * i);
      e = write_registers(start, count, words);
      if (e != ExceptionCode::kNone) break;
      if (broadcast) return 0;
      for (std::size_t i = 0; i < 5; ++i) resp[i] = req[i];
      return 5;
    }
    case 0x17: {
      if (broadcast) return 0;
      if (len < 10) {
        e = ExceptionCode::kIllegalDataValue;
        break;
      }
      const std::uint16_t rstart = get_u16(req + 1);
      const std::uint16_t rcount = get_u16(req + 3);
      const std::uint16_t wstart = get_u16(req + 5);
      const std::uint16_t wcount = get_u16(req + 7);
      const std::uint8_t bytes = req[9];
      if (rcount == 0 || rcount > kMaxReadCount || wcount == 0 || wcount > kMaxRwWriteCount ||
          bytes != wcount * 2 || len != 10u + bytes) {
        e = ExceptionCode::kIllegalDataValue;
        break;
      }
      // The read range is checked before the write so a bad read never
      // leaves a half-done transaction behind.
      for (std::uint32_t a = rstart; a < static_cast<std::uint32_t>(rstart) + rcount; ++a) {
        const RegisterDef* rd = a > 0xFFFFu ? nullptr : find_by_address(static_cast<std::uint16_t>(a));
        if (rd == nullptr || (rd->kind == Kind::kLab && lab_ == nullptr)) {
          e = ExceptionCode::kIllegalDataAddress;
          break;
        }
      }
      if (e != ExceptionCode::kNone) break;
      // And whether it can be read now (a lab block answers 06 while its
      // capture runs): the write used to be applied and the reply then said
      // 06, "busy, retry" -- a retried step stepped twice. Reads have no side
      // effects; the real read follows the write, as the function defines.
      e = read_registers(rstart, rcount, words);
      if (e != ExceptionCode::kNone) break;
      std::uint16_t wvals[kMaxRwWriteCount];
      for (std::uint16_t i = 0; i < wcount; ++i) wvals[i] = get_u16(req + 10 + 2 * i);
      e = write_registers(wstart, wcount, wvals);
      if (e != ExceptionCode::kNone) break;
      e = read_registers(rstart, rcount, words);
      if (e != ExceptionCode::kNone) break;
      resp[0] = fc;
      resp[1] = static_cast<std::uint8_t>(rcount * 2);
      for (std::uint16_t i = 0; i < rcount; ++i) put_u16(resp + 2 + 2 * i, words[i]);
      n = 2u + 2u * rcount;
      return n;
    }
    default:
      e = ExceptionCode::kIllegalFunction;
      break;
  }
  if (broadcast) return 0;
  return exception_reply(fc, e, resp);
}

}  // namespace maglev::modbus
