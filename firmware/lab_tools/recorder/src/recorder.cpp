#include "maglev/lab_tools/recorder.hpp"

#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/int64_double.hpp"

namespace maglev::lab {
namespace {

// Current monitor code -> A: +-10 V over 16 bit, kCurrentMonitorGain_V_per_A.
constexpr float kMonitorA_per_code =
    static_cast<float>(io::stage::kAdcFullScale_V / 32768.0 / io::stage::kCurrentMonitorGain_V_per_A);

using numeric::PicoToSi;  // int64 pm -> float m, the kernel's one form

}  // namespace

RecorderConfig fault_watch_config(float servo_rate_Hz) {
  RecorderConfig c{};
  const std::uint16_t ids[] = {find_signal("x.pose"),    find_signal("x.reference"), find_signal("x.effort"),
                               find_signal("z.pose"),    find_signal("z.effort"),    find_signal("coil1.current"),
                               find_signal("state"),     find_signal("fault")};
  c.channel_count = kMaxChannels;
  for (std::uint16_t i = 0; i < kMaxChannels; ++i) c.channel[i] = ids[i];
  c.decimation = 1;
  const auto one_second = static_cast<std::uint32_t>(servo_rate_Hz);
  c.length = 2u * one_second;
  c.pretrigger = one_second;
  c.mode = TriggerMode::kFault;
  return c;
}

float signal_value(SignalRef s, const kernel::ControllerStatus& st, const io::SensorSample& sample) {
  const std::uint8_t i = s.index;
  switch (s.group) {
    case SignalGroup::kPose: return PicoToSi(st.pose.pico[i]);
    case SignalGroup::kReference: return PicoToSi(st.reference.pico[i]);
    case SignalGroup::kError: return PicoToSi(st.reference.pico[i] - st.pose.pico[i]);
    case SignalGroup::kEffort: return st.effort_A[i];
    case SignalGroup::kLoopEffort: return st.loop_effort_A[i];
    case SignalGroup::kExcitation: return st.excitation_A[i];
    case SignalGroup::kRefInjection:
      return st.injection_active && st.injection_axis == i ? st.reference_injection : 0.0f;
    case SignalGroup::kCoilCurrentCmd: return st.coil_current_A[i];
    case SignalGroup::kCoilCurrent: return static_cast<float>(sample.coil_current_adc[i]) * kMonitorA_per_code;
    case SignalGroup::kState: return static_cast<float>(static_cast<int>(st.state));
    case SignalGroup::kFault: return static_cast<float>(static_cast<int>(st.fault));
    case SignalGroup::kScaleK: return st.scale_k;
    case SignalGroup::kNone: break;
  }
  return 0.0f;
}

RecorderError Recorder::check(const RecorderConfig& c) const {
  if (c.channel_count == 0 || c.channel_count > kMaxChannels) return RecorderError::kChannelCount;
  for (std::uint16_t i = 0; i < c.channel_count; ++i) {
    if (!signal_known(c.channel[i])) return RecorderError::kUnknownSignal;
  }
  if (c.decimation == 0) return RecorderError::kDecimation;
  if (c.length == 0 || c.length > capacity(c.channel_count)) return RecorderError::kLength;
  if (c.pretrigger >= c.length) return RecorderError::kPretrigger;
  switch (c.mode) {
    case TriggerMode::kImmediate:
    case TriggerMode::kCommand:
    case TriggerMode::kFault:
      break;
    case TriggerMode::kLevel:
      if (!signal_known(c.trigger_signal)) return RecorderError::kUnknownSignal;
      break;
    default:
      return RecorderError::kBadMode;
  }
  if (c.edge != TriggerEdge::kRising && c.edge != TriggerEdge::kFalling && c.edge != TriggerEdge::kEither) {
    return RecorderError::kBadMode;
  }
  return RecorderError::kOk;
}

RecorderError Recorder::configure(const RecorderConfig& c) {
  if (state_ == RecorderState::kArmed || state_ == RecorderState::kTriggered) return RecorderError::kBusy;
  const RecorderError e = check(c);
  if (e != RecorderError::kOk) return e;
  config_ = c;
  for (std::uint16_t i = 0; i < kMaxChannels; ++i) ref_[i] = i < c.channel_count ? signal_ref(c.channel[i]) : SignalRef{};
  trigger_ref_ = c.mode == TriggerMode::kFault ? SignalRef{SignalGroup::kFault, 0}
                 : c.mode == TriggerMode::kLevel ? signal_ref(c.trigger_signal)
                                                 : SignalRef{};
  cap_ = capacity(c.channel_count);
  state_ = RecorderState::kIdle;
  return RecorderError::kOk;
}

RecorderError Recorder::arm() {
  if (state_ == RecorderState::kArmed || state_ == RecorderState::kTriggered) return RecorderError::kBusy;
  const RecorderError e = check(config_);
  if (e != RecorderError::kOk) return e;
  write_slot_ = 0;
  filled_ = 0;
  remaining_ = 0;
  start_slot_ = 0;
  trigger_index_ = 0;
  decimation_count_ = static_cast<std::uint16_t>(config_.decimation - 1u);  // the first tick records
  have_previous_ = false;
  trigger_request_ = false;
  state_ = RecorderState::kArmed;  // last: the tick starts writing now
  return RecorderError::kOk;
}

RecorderError Recorder::trigger() {
  if (state_ != RecorderState::kArmed || config_.mode != TriggerMode::kCommand) return RecorderError::kNotArmed;
  trigger_request_ = true;
  return RecorderError::kOk;
}

void Recorder::stop() { state_ = RecorderState::kIdle; }

float Recorder::at(std::uint32_t k) const {
  if (state_ != RecorderState::kDone || config_.channel_count == 0) return 0.0f;
  const std::uint32_t n = config_.channel_count;
  const std::uint32_t sample = k / n;
  if (sample >= config_.length) return 0.0f;
  std::uint32_t slot = start_slot_ + sample;
  if (slot >= cap_) slot -= cap_;
  return pool_[slot * n + (k - sample * n)];
}

bool Recorder::triggered_now(const kernel::ControllerStatus& st, const io::SensorSample& s) {
  switch (config_.mode) {
    case TriggerMode::kImmediate:
      return filled_ > config_.pretrigger;  // the pre-trigger samples are in
    case TriggerMode::kCommand:
      return trigger_request_;
    case TriggerMode::kFault: {
      const float v = (st.fault != kernel::FaultCode::kNone || st.state == kernel::SequencerState::kFault) ? 1.0f : 0.0f;
      const bool fire = have_previous_ && previous_ == 0.0f && v != 0.0f;
      previous_ = v;
      have_previous_ = true;
      return fire;
    }
    case TriggerMode::kLevel: {
      const float v = signal_value(trigger_ref_, st, s);
      const float l = config_.level;
      const bool up = have_previous_ && previous_ < l && v >= l;
      const bool down = have_previous_ && previous_ > l && v <= l;
      previous_ = v;
      have_previous_ = true;
      return config_.edge == TriggerEdge::kRising ? up : config_.edge == TriggerEdge::kFalling ? down : (up || down);
    }
  }
  return false;
}

void Recorder::record(const kernel::ControllerStatus& st, const io::SensorSample& s) {
  const std::uint32_t n = config_.channel_count;
  float* dst = pool_ + write_slot_ * n;
  for (std::uint32_t c = 0; c < n; ++c) dst[c] = signal_value(ref_[c], st, s);
  const std::uint32_t slot = write_slot_;
  write_slot_ = slot + 1u == cap_ ? 0u : slot + 1u;
  if (filled_ < cap_) ++filled_;
  if (state_ == RecorderState::kArmed) {
    if (!triggered_now(st, s)) return;
    // This sample is the trigger sample: up to `pretrigger` older ones precede it.
    const std::uint32_t pre = filled_ - 1u < config_.pretrigger ? filled_ - 1u : config_.pretrigger;
    start_slot_ = slot >= pre ? slot - pre : slot + cap_ - pre;
    trigger_index_ = pre;
    // Keep `length` samples from start_slot_: the ones after the trigger still to come.
    remaining_ = config_.length - pre - 1u;
    state_ = RecorderState::kTriggered;
  } else if (remaining_ > 0) {
    --remaining_;
  }
  if (state_ == RecorderState::kTriggered && remaining_ == 0) {
    ++capture_id_;
    state_ = RecorderState::kDone;
  }
}

}  // namespace maglev::lab
