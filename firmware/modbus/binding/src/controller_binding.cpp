#include "maglev/modbus/controller_binding.hpp"

#include <type_traits>

#include "maglev/can_link/host_commands.hpp"
#include "maglev/motion_commands/to_motion_command.hpp"
#include "maglev/stage_profile/apply_profile.hpp"
#include "maglev/stage_profile/stage_database.hpp"

namespace maglev::modbus {

namespace {
// A KernelConfig field as a register value: floats, and enums (the filter
// type) through their underlying integer.
// The kernel's verdict on a configuration as the register server's.
Device::ApplyResult to_apply_result(kernel::ConfigError e) {
  switch (e) {
    case kernel::ConfigError::kOk:
      return Device::ApplyResult::kApplied;
    case kernel::ConfigError::kLockedWhileLevitated:
    case kernel::ConfigError::kGainsLockedWhileLevitated:
      return Device::ApplyResult::kBusy;
    default:
      return Device::ApplyResult::kRefused;
  }
}

template <typename T>
double load_field(const T& f) {
  if constexpr (std::is_enum_v<T>) {
    return static_cast<double>(static_cast<std::underlying_type_t<T>>(f));
  } else {
    return static_cast<double>(f);
  }
}
template <typename T>
void store_field(T& f, double v) {
  if constexpr (std::is_enum_v<T>) {
    f = static_cast<T>(static_cast<std::underlying_type_t<T>>(v));
  } else {
    f = static_cast<T>(v);
  }
}
}  // namespace

#define MAGLEV_BIND_IDENT(id, field)
#define MAGLEV_BIND_STATUS(id, field)
#define MAGLEV_BIND_CONTROL(id, field)
#define MAGLEV_BIND_STAGE(id, field)
#define MAGLEV_BIND_LAB(id, field)
#define MAGLEV_REG(id, name, address, type, unit, min, max, def, access, when, persist, kind, field, desc) \
  MAGLEV_BIND_##kind(id, field)

bool has_config_field(RegId id) {
  switch (id) {
#define MAGLEV_BIND_CONFIG(id, field) case RegId::id:
#include "maglev/register_schema/registers.def"
#undef MAGLEV_BIND_CONFIG
    return true;
    default:
      return false;
  }
}

bool get_config_field(const kernel::KernelConfig& cfg, RegId id, double* value) {
  switch (id) {
#define MAGLEV_BIND_CONFIG(id, field) \
  case RegId::id:                     \
    *value = load_field(cfg.field);   \
    return true;
#include "maglev/register_schema/registers.def"
#undef MAGLEV_BIND_CONFIG
    default:
      return false;
  }
}

bool set_config_field(kernel::KernelConfig& cfg, RegId id, double value) {
  switch (id) {
#define MAGLEV_BIND_CONFIG(id, field) \
  case RegId::id:                     \
    store_field(cfg.field, value);    \
    return true;
#include "maglev/register_schema/registers.def"
#undef MAGLEV_BIND_CONFIG
    default:
      return false;
  }
}

#undef MAGLEV_REG
#undef MAGLEV_BIND_IDENT
#undef MAGLEV_BIND_STATUS
#undef MAGLEV_BIND_CONTROL
#undef MAGLEV_BIND_STAGE

void image_to_kernel(const ConfigImage& image, kernel::KernelConfig& config) {
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    (void)set_config_field(config, d.id, decode(d.type, image.raw[s]));
  }
  // The measurement runs at the servo rate by construction: servo.rate is
  // one register, not two that could disagree.
  config.measurement.servo_rate_Hz = config.servo_rate_Hz;
}

ConfigImage image_from_kernel(const kernel::KernelConfig& config) {
  ConfigImage image = ConfigImage::defaults();
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    double v = 0.0;
    if (get_config_field(config, d.id, &v)) image.raw[s] = encode(d.type, v);
  }
  return image;
}

std::uint16_t stage_profile_of(const ConfigImage& image) {
  return static_cast<std::uint16_t>(image.raw[static_cast<std::size_t>(persisted_slot(RegId::stage_profile))]);
}

void set_stage_profile(ConfigImage& image, std::uint16_t index) {
  image.raw[static_cast<std::size_t>(persisted_slot(RegId::stage_profile))] = index;
}

const RegisterDef* FirstRegisterOutOfRange(const kernel::KernelConfig& config) {
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    double v = 0.0;
    if (get_config_field(config, d.id, &v) && !value_in_range(d, v)) return &d;
  }
  return nullptr;
}

stage_profile::ProfileError KernelConfigOfProfile(std::uint16_t index, kernel::KernelConfig* out) {
  // Static: a StageProfile is ~4 kB, too large for the comms stack; the
  // comms loop is the only caller (boot, then Modbus writes).
  static stage_profile::StageProfile profile;
  const stage_profile::ProfileError loaded = stage_profile::LoadStageProfile(index, &profile);
  if (loaded != stage_profile::ProfileError::kOk) return loaded;
  const stage_profile::ProfileError checked = stage_profile::MakeKernelConfig(profile, out).error;
  if (checked != stage_profile::ProfileError::kOk) return checked;
  // (*out holds the refused configuration then: both callers drop it.)
  if (FirstRegisterOutOfRange(*out) != nullptr) return stage_profile::ProfileError::kRegisterRange;
  return stage_profile::ProfileError::kOk;
}

template <typename Scalar>
ControllerDevice<Scalar>::ControllerDevice(kernel::Controller<Scalar>& controller, persistence::ConfigStore* store)
    : controller_(controller), store_(store) {}

template <typename Scalar>
ConfigImage ControllerDevice<Scalar>::boot() {
  const ConfigImage kernel_defaults = image_from_kernel(kernel::default_kernel_config());
  if (store_ == nullptr) return kernel_defaults;
  const persistence::LoadResult loaded = store_->load();
  boot_status_ = loaded.status;
  if ((loaded.status.flags & kLoadedDefaults) != 0) {
    // No usable record: the kernel's defaults (the table's defaults equal
    // them; stage.profile 0 is the default stage).
    return kernel_defaults;
  }
  // The stage first: its profile is the base the record's values overlay.
  const std::uint16_t index = stage_profile_of(loaded.config);
  kernel::KernelConfig base{};
  const stage_profile::ProfileError pe = KernelConfigOfProfile(index, &base);
  if (pe != stage_profile::ProfileError::kOk) {
    // Refused: stay landed with the reason latched; the kernel keeps the
    // default stage's configuration, which can never lift this stage.
    controller_.set_stage_profile_error(static_cast<std::uint8_t>(pe));
    active_profile_ = 0;
    return loaded.config;
  }
  kernel::KernelConfig cfg = base;
  image_to_kernel(loaded.config, cfg);
  if (controller_.apply_config(cfg) != kernel::ConfigError::kOk) {
    boot_status_.flags = static_cast<std::uint16_t>((boot_status_.flags & ~(kLoadedBankA | kLoadedBankB)) |
                                                    kRefused | kLoadedDefaults);
    boot_status_.reason = static_cast<std::uint16_t>(persistence::Reason::kValueOutOfRange);
    // The profile's own defaults (CheckStageProfile passed them, with the
    // kernel's own designs). Should the kernel refuse them all the same, the
    // stage stays landed with the reason latched, as for a refused profile.
    if (controller_.apply_config(base) != kernel::ConfigError::kOk) {
      controller_.set_stage_profile_error(static_cast<std::uint8_t>(stage_profile::ProfileError::kKernelRefused));
      active_profile_ = 0;
      return loaded.config;
    }
    active_profile_ = index;
    ConfigImage image = image_from_kernel(base);
    set_stage_profile(image, index);
    return image;
  }
  active_profile_ = index;
  return loaded.config;
}

template <typename Scalar>
Activity ControllerDevice<Scalar>::activity() const {
  using S = kernel::SequencerState;
  switch (controller_.status().state) {
    case S::kIdle:
    case S::kFault:
      return Activity::kIdle;
    case S::kReady:
      // Levitated: moving while a reference profile / step / excitation runs
      // (the kernel's live flag, so a write right after a move command is
      // already refused), holding otherwise.
      return controller_.motion_active() ? Activity::kMoving : Activity::kHolding;
    default:
      return Activity::kMoving;  // homing, locking, lifting, landing
  }
}

template <typename Scalar>
double ControllerDevice<Scalar>::read_status(RegId id) const {
  const kernel::ControllerStatus& st = controller_.status();
  constexpr double kPico = 1e-12;  // Pose64: 1 pm / 1 prad per LSB
  switch (id) {
    case RegId::status_state: return static_cast<double>(st.state);
    case RegId::status_fault: return static_cast<double>(st.fault);
    case RegId::status_saturation: return st.saturated ? 1.0 : 0.0;
    case RegId::status_moving: return activity() == Activity::kMoving ? 1.0 : 0.0;
    case RegId::status_x: return static_cast<double>(st.pose[maglev::kernel::Axis::kX]) * kPico;
    case RegId::status_y: return static_cast<double>(st.pose[maglev::kernel::Axis::kY]) * kPico;
    case RegId::status_z: return static_cast<double>(st.pose[maglev::kernel::Axis::kZ]) * kPico;
    case RegId::status_theta_x: return static_cast<double>(st.pose[maglev::kernel::Axis::kThetaX]) * kPico;
    case RegId::status_theta_y: return static_cast<double>(st.pose[maglev::kernel::Axis::kThetaY]) * kPico;
    case RegId::status_theta_z: return static_cast<double>(st.pose[maglev::kernel::Axis::kThetaZ]) * kPico;
    case RegId::status_closed_axes: return st.closed_axes;
    case RegId::status_config_error: return static_cast<double>(st.last_config_error);
    case RegId::status_scale_k: return static_cast<double>(st.scale_k);
    case RegId::status_profile_error: return static_cast<double>(controller_.stage_profile_error());
    case RegId::status_calibration: return static_cast<double>(st.calibration_result);
    case RegId::status_calibration_step: return static_cast<double>(st.calibration_experiment);
    case RegId::status_coupling_before: return static_cast<double>(st.calibration_coupling_before);
    case RegId::status_coupling_after: return static_cast<double>(st.calibration_coupling_after);
    case RegId::status_lds_target_steps: return static_cast<double>(st.lds_target_steps);
    default: return 0.0;
  }
}

template <typename Scalar>
Device::ApplyResult ControllerDevice<Scalar>::apply_config(ConfigImage& config, bool live_tuning) {
  const std::uint16_t index = stage_profile_of(config);
  if (index != active_profile_ || controller_.stage_profile_error() != 0) {
    // A stage selection (or, after a refused boot, any write: nothing else
    // may change until a valid stage is selected). The profile's whole
    // configuration replaces the old stage's: gains and limits tuned for
    // one stage mean nothing on another.
    // (Static: a KernelConfig is large for the comms stack; this context is its only user.)
    static kernel::KernelConfig cfg;
    cfg = kernel::KernelConfig{};
    if (KernelConfigOfProfile(index, &cfg) != stage_profile::ProfileError::kOk) return ApplyResult::kRefused;
    cfg.live_tuning = live_tuning;
    const ApplyResult r = apply_kernel_config(cfg);
    if (r != ApplyResult::kApplied) return r;
    active_profile_ = index;
    if (critical_enter_ != nullptr) critical_enter_();
    controller_.set_stage_profile_error(0);
    if (critical_exit_ != nullptr) critical_exit_();
    config = image_from_kernel(cfg);
    set_stage_profile(config, index);
    return ApplyResult::kApplied;
  }
  kernel::KernelConfig cfg = controller_.config();  // config_ changes only in this context's commits
  image_to_kernel(config, cfg);
  cfg.live_tuning = live_tuning;
  return apply_kernel_config(cfg);
}

template <typename Scalar>
Device::ApplyResult ControllerDevice<Scalar>::apply_kernel_config(const kernel::KernelConfig& cfg) {
  const kernel::ConfigError prepared = controller_.prepare_config(cfg);
  if (prepared != kernel::ConfigError::kOk) return to_apply_result(prepared);
  if (critical_enter_ != nullptr) critical_enter_();
  const kernel::ConfigError e = controller_.commit_config(cfg);
  if (critical_exit_ != nullptr) critical_exit_();
  return to_apply_result(e);
}

template <typename Scalar>
std::uint16_t ControllerDevice<Scalar>::command(std::uint16_t code, std::uint16_t axis, float value) {
  using C = can::HostCommandCode;
  if (code == 0) return 0;
  // The Modbus command as the typed host command, then the one mapping.
  const auto c = static_cast<C>(code);
  const auto ax = static_cast<std::uint8_t>(axis);
  can::HostCommandFrame h{};
  switch (c) {
    case C::kHome: case C::kLevitate: case C::kLand: case C::kStop: case C::kClearFault: case C::kHold:
    case C::kCalibrateCoupling:
      h = can::make_host_command(c, 0, ax);
      break;
    case C::kStep:
      h = can::make_host_command(0, ax, can::StepArgs{static_cast<double>(value)});
      break;
    case C::kMoveTo: {
      // Moves run at the configured profile limits of their axis.
      const kernel::ReferenceLimits& lim = controller_.config().references;
      const int a = axis % kernel::kAxisCount;
      h = can::make_host_command(0, ax, can::MoveToArgs{static_cast<double>(value),
                                                        static_cast<double>(lim.max_velocity[a]),
                                                        static_cast<double>(lim.max_acceleration[a])});
      break;
    }
    default:  // more fields than cmd.value carries: over CAN only
      return static_cast<std::uint16_t>(kernel::CommandResult::kUnsupported);
  }
  kernel::MotionCommand cmd;
  if (!motion_commands::to_motion_command(h, controller_.status().reference, &cmd)) {
    return static_cast<std::uint16_t>(kernel::CommandResult::kUnsupported);
  }
  return static_cast<std::uint16_t>(controller_.command(cmd));
}

template <typename Scalar>
bool ControllerDevice<Scalar>::save_config(const ConfigImage& config) {
  if (store_ == nullptr) return false;
  const bool ok = store_->save(config);
  boot_status_ = store_->status();
  return ok;
}

// The coupling correction is the one configuration the kernel writes itself
// (a passed calibration): the image takes the kernel's values.
template <typename Scalar>
void ControllerDevice<Scalar>::sync_config(ConfigImage& config) {
  const kernel::KernelConfig& cfg = controller_.config();
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    const RegisterDef& d = persisted_def(s);
    if (d.id < RegId::coupling_enabled || d.id > RegId::coupling_theta_y_theta_y) continue;
    double v = 0.0;
    if (get_config_field(cfg, d.id, &v)) config.raw[s] = encode(d.type, v);
  }
}

template <typename Scalar>
PersistStatus ControllerDevice<Scalar>::persist_status() const {
  return boot_status_;
}

template class ControllerDevice<float>;
template class ControllerDevice<numeric::Q7_24>;

}  // namespace maglev::modbus
