#include "maglev/lab_tools/lab_registers.hpp"

#include <bit>

namespace maglev::lab {
namespace {

using modbus::ExceptionCode;
using modbus::RegId;

constexpr std::uint16_t channel_of(RegId id) {
  return static_cast<std::uint16_t>(static_cast<std::uint16_t>(id) - static_cast<std::uint16_t>(RegId::rec_channel_0));
}
constexpr bool is_channel(RegId id) { return id >= RegId::rec_channel_0 && id <= RegId::rec_channel_7; }
static_assert(static_cast<int>(RegId::rec_channel_7) - static_cast<int>(RegId::rec_channel_0) == kMaxChannels - 1,
              "rec.channel.N registers: one per recorder channel, in order");

float as_f32(std::uint32_t raw) { return std::bit_cast<float>(raw); }
std::uint32_t raw_f32(float v) { return std::bit_cast<std::uint32_t>(v); }

}  // namespace

LabRegisters::LabRegisters(Recorder& recorder, WaveGenerator& wave, const kernel::KernelConfig& kernel_config,
                           const LabRegistersHooks& hooks)
    : recorder_(recorder), wave_(wave), kernel_config_(kernel_config), hooks_(hooks) {
  // The wave.* registers start at their register-map defaults.
  wave_cfg_.axis = static_cast<std::uint16_t>(modbus::def(RegId::wave_axis).default_value);
  wave_cfg_.point = static_cast<InjectionPoint>(modbus::def(RegId::wave_point).default_value);
  wave_cfg_.shape = static_cast<WaveShape>(modbus::def(RegId::wave_shape).default_value);
  wave_cfg_.tones = static_cast<std::uint16_t>(modbus::def(RegId::wave_tones).default_value);
  wave_cfg_.amplitude = static_cast<float>(modbus::def(RegId::wave_amplitude).default_value);
  wave_cfg_.f_start_Hz = static_cast<float>(modbus::def(RegId::wave_f_start).default_value);
  wave_cfg_.f_end_Hz = static_cast<float>(modbus::def(RegId::wave_f_end).default_value);
  wave_cfg_.duration_s = static_cast<float>(modbus::def(RegId::wave_duration).default_value);
}

std::uint32_t LabRegisters::read(RegId id) const {
  const RecorderConfig& rec_ = recorder_.config();  // the rec.* registers are the recorder's configuration
  if (is_channel(id)) return rec_.channel[channel_of(id)];
  switch (id) {
    case RegId::rec_state: return static_cast<std::uint32_t>(recorder_.state());
    case RegId::rec_channel_count: return rec_.channel_count;
    case RegId::rec_decimation: return rec_.decimation;
    case RegId::rec_length: return rec_.length;
    case RegId::rec_pretrigger: return rec_.pretrigger;
    case RegId::rec_trigger_mode: return static_cast<std::uint32_t>(rec_.mode);
    case RegId::rec_trigger_signal: return rec_.trigger_signal;
    case RegId::rec_trigger_edge: return static_cast<std::uint32_t>(rec_.edge);
    case RegId::rec_trigger_level: return raw_f32(rec_.level);
    case RegId::rec_capacity: return recorder_.capacity(rec_.channel_count);
    case RegId::rec_captured: return recorder_.captured();
    case RegId::rec_trigger_index: return recorder_.trigger_index();
    case RegId::rec_sample_rate:
      return raw_f32(kernel_config_.servo_rate_Hz / static_cast<float>(rec_.decimation == 0 ? 1u : rec_.decimation));
    case RegId::rec_capture_id: return recorder_.capture_id();
    case RegId::rec_error: return rec_error_;
    case RegId::rec_read_offset: return read_offset_;
    case RegId::wave_state: return static_cast<std::uint32_t>(wave_.state());
    case RegId::wave_axis: return wave_cfg_.axis;
    case RegId::wave_point: return static_cast<std::uint32_t>(wave_cfg_.point);
    case RegId::wave_shape: return static_cast<std::uint32_t>(wave_cfg_.shape);
    case RegId::wave_tones: return wave_cfg_.tones;
    case RegId::wave_amplitude: return raw_f32(wave_cfg_.amplitude);
    case RegId::wave_f_start: return raw_f32(wave_cfg_.f_start_Hz);
    case RegId::wave_f_end: return raw_f32(wave_cfg_.f_end_Hz);
    case RegId::wave_duration: return raw_f32(wave_cfg_.duration_s);
    case RegId::wave_limit: return raw_f32(amplitude_limit(kernel_config_, wave_cfg_.axis, wave_cfg_.point));
    case RegId::wave_error: return wave_error_;
    case RegId::wave_tick: return wave_.tick();
    default: return 0;  // rec.control, wave.control read 0
  }
}

ExceptionCode LabRegisters::read_block(RegId id, std::uint16_t first, std::uint16_t count, std::uint16_t* out) const {
  if (id != RegId::rec_data) return ExceptionCode::kIllegalDataAddress;
  if (recorder_.state() != RecorderState::kDone) return ExceptionCode::kServerDeviceBusy;
  for (std::uint16_t i = 0; i < count; ++i) {
    const std::uint32_t word = static_cast<std::uint32_t>(first) + i;
    const std::uint32_t k = read_offset_ + word / 2u;
    const std::uint32_t raw = k < recorder_.values() ? raw_f32(recorder_.at(k)) : 0u;
    out[i] = (word & 1u) == 0 ? static_cast<std::uint16_t>(raw >> 16) : static_cast<std::uint16_t>(raw & 0xFFFFu);
  }
  return ExceptionCode::kNone;
}

ExceptionCode LabRegisters::write(const modbus::PendingWrite* writes, std::size_t n, bool commit) {
  RecorderConfig rc = recorder_.config();
  WaveConfig wc = wave_cfg_;
  std::uint32_t offset = read_offset_;
  bool rec_config = false, wave_config = false;
  std::uint16_t rec_control = 0, wave_control = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const modbus::RegisterDef& d = *writes[i].def;
    if (d.kind != modbus::Kind::kLab) continue;
    const std::uint32_t raw = writes[i].raw;
    const auto u16 = static_cast<std::uint16_t>(raw);
    bool rec_field = true, wave_field = false;
    if (is_channel(d.id)) {
      rc.channel[channel_of(d.id)] = u16;
      rec_config = true;
      continue;
    }
    switch (d.id) {
      case RegId::rec_channel_count: rc.channel_count = u16; break;
      case RegId::rec_decimation: rc.decimation = u16; break;
      case RegId::rec_length: rc.length = raw; break;
      case RegId::rec_pretrigger: rc.pretrigger = raw; break;
      case RegId::rec_trigger_mode: rc.mode = static_cast<TriggerMode>(u16); break;
      case RegId::rec_trigger_signal: rc.trigger_signal = u16; break;
      case RegId::rec_trigger_edge: rc.edge = static_cast<TriggerEdge>(u16); break;
      case RegId::rec_trigger_level: rc.level = as_f32(raw); break;
      case RegId::rec_control: rec_control = u16; rec_field = false; break;
      case RegId::rec_read_offset: offset = raw; rec_field = false; break;
      default:
        rec_field = false;
        wave_field = true;
        switch (d.id) {
          case RegId::wave_axis: wc.axis = u16; break;
          case RegId::wave_point: wc.point = static_cast<InjectionPoint>(u16); break;
          case RegId::wave_shape: wc.shape = static_cast<WaveShape>(u16); break;
          case RegId::wave_tones: wc.tones = u16; break;
          case RegId::wave_amplitude: wc.amplitude = as_f32(raw); break;
          case RegId::wave_f_start: wc.f_start_Hz = as_f32(raw); break;
          case RegId::wave_f_end: wc.f_end_Hz = as_f32(raw); break;
          case RegId::wave_duration: wc.duration_s = as_f32(raw); break;
          case RegId::wave_control: wave_control = u16; wave_field = false; break;
          default: wave_field = false; break;
        }
        break;
    }
    rec_config = rec_config || rec_field;
    wave_config = wave_config || wave_field;
  }
  // --- check: refuse the whole request, nothing changed.
  const RecorderState rs = recorder_.state();
  const bool recording = rs == RecorderState::kArmed || rs == RecorderState::kTriggered;
  if (rec_config && recording) return ExceptionCode::kServerDeviceBusy;
  if (rec_config || rec_control == kRecArm) {
    const RecorderError e = recorder_.check(rc);
    if (e != RecorderError::kOk) {
      rec_error_ = static_cast<std::uint16_t>(e);
      return ExceptionCode::kIllegalDataValue;
    }
  }
  if (rec_control == kRecArm && recording) return ExceptionCode::kServerDeviceBusy;
  if (rec_control == kRecTrigger && (rs != RecorderState::kArmed || rc.mode != TriggerMode::kCommand)) {
    rec_error_ = static_cast<std::uint16_t>(RecorderError::kNotArmed);
    return ExceptionCode::kServerDeviceBusy;
  }
  const bool running = wave_.state() == WaveState::kRunning;
  if (wave_config && running) return ExceptionCode::kServerDeviceBusy;
  if (wave_control == kWaveStart) {
    if (running) return ExceptionCode::kServerDeviceBusy;
    const WaveError e = wave_.check(wc, kernel_config_);
    if (e != WaveError::kOk) {
      wave_error_ = static_cast<std::uint16_t>(e);
      return ExceptionCode::kIllegalDataValue;
    }
  }
  if (!commit) return ExceptionCode::kNone;

  // --- apply.
  read_offset_ = offset;
  if (rec_config) {
    enter();
    const RecorderError e = recorder_.configure(rc);
    exit();
    if (e != RecorderError::kOk) {
      rec_error_ = static_cast<std::uint16_t>(e);
      return ExceptionCode::kServerDeviceBusy;  // the recorder changed state since the check
    }
    rec_error_ = 0;
  }
  if (rec_control != 0) {
    enter();
    RecorderError e = RecorderError::kOk;
    if (rec_control == kRecArm) e = recorder_.arm();
    if (rec_control == kRecTrigger) e = recorder_.trigger();
    if (rec_control == kRecStop) recorder_.stop();
    exit();
    rec_error_ = static_cast<std::uint16_t>(e);
    if (e != RecorderError::kOk) return ExceptionCode::kServerDeviceBusy;
  }
  if (wave_config) wave_cfg_ = wc;
  if (wave_control == kWaveStop) wave_.stop();
  if (wave_control == kWaveStart) {
    // Builds the multisine table while the generator is off (the tick reads
    // nothing until start() sets it running): no critical section needed.
    const WaveError e = wave_.start(wc, kernel_config_);
    wave_error_ = static_cast<std::uint16_t>(e);
    if (e != WaveError::kOk) return e == WaveError::kBusy ? ExceptionCode::kServerDeviceBusy : ExceptionCode::kIllegalDataValue;
  }
  return ExceptionCode::kNone;
}

}  // namespace maglev::lab
