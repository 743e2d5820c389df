// The thin layer between the register map and the real kernel:
//   * ConfigImage <-> maglev::kernel::KernelConfig, generated from the
//     `field` column of registers.def (every CONFIG entry is a float field);
//   * ControllerDevice<Scalar>: the modbus::Device the RegisterServer drives,
//     over kernel::Controller<Scalar> and persistence::ConfigStore.
// Heap-free; host and target.
#pragma once

#include "maglev/controller/controller.hpp"
#include "maglev/modbus/register_server.hpp"
#include "maglev/persistence/config_store.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::modbus {

// The KernelConfig field a CONFIG register is (a float, or an enum through
// its integer value). false: `id` is not a CONFIG register.
bool has_config_field(RegId id);
bool get_config_field(const kernel::KernelConfig& config, RegId id, double* value);
bool set_config_field(kernel::KernelConfig& config, RegId id, double value);
// Copy the mapped fields; fields the map does not carry are left as they are.
void image_to_kernel(const ConfigImage& image, kernel::KernelConfig& config);
ConfigImage image_from_kernel(const kernel::KernelConfig& config);
// The stage.profile entry of an image.
std::uint16_t stage_profile_of(const ConfigImage& image);
void set_stage_profile(ConfigImage& image, std::uint16_t index);
// The first persisted register whose value in `config` its range does not
// admit, or nullptr. A profile's configuration must fit the register map
// whole: a value outside it was loaded, then could not be written back, and
// the saved record was refused at the next boot (the stage fell back to the
// default one).
const RegisterDef* FirstRegisterOutOfRange(const kernel::KernelConfig& config);
// The kernel configuration of database profile `index` (LoadStageProfile,
// then MakeKernelConfig, then FirstRegisterOutOfRange: kRegisterRange): kOk,
// or why it is refused (*out untouched, but for kRegisterRange: then it holds
// the configuration the map could not).
stage_profile::ProfileError KernelConfigOfProfile(std::uint16_t index, kernel::KernelConfig* out);

template <typename Scalar>
class ControllerDevice final : public Device {
 public:
  // `store` may be nullptr (no flash: config.save fails with 04).
  ControllerDevice(kernel::Controller<Scalar>& controller, persistence::ConfigStore* store);

  // Boot: load flash, load the stage profile it selects (stage.profile) from
  // the built-in database and check it, then apply the record over that
  // profile's configuration. A record the kernel refuses falls back to the
  // profile's defaults (flagged refused). A profile that fails its check
  // (unknown index, CRC, CheckStageProfile) leaves the kernel on the default
  // stage's configuration with FaultCode::kStageProfileInvalid latched and
  // status.profile_error naming the ProfileError: the stage stays landed
  // until a valid profile is selected. Returns the image the RegisterServer
  // starts from (the stored selection kept, so the operator sees it).
  ConfigImage boot();

  Activity activity() const override;
  double read_status(RegId id) const override;
  // Validation, loop designs and a stage profile's load run outside the
  // critical section; the kernel's commit inside it.
  ApplyResult apply_config(ConfigImage& config, bool live_tuning) override;
  bool set_critical_section(void (*enter)(), void (*exit)()) override {
    critical_enter_ = enter;
    critical_exit_ = exit;
    return true;
  }
  std::uint16_t command(std::uint16_t code, std::uint16_t axis, float value) override;
  bool save_config(const ConfigImage& config) override;
  PersistStatus persist_status() const override;
  void sync_config(ConfigImage& config) override;

 private:
  kernel::Controller<Scalar>& controller_;
  persistence::ConfigStore* store_;
  PersistStatus boot_status_{};
  std::uint16_t active_profile_ = 0;  // stage.profile the kernel runs
  void (*critical_enter_)() = nullptr;
  void (*critical_exit_)() = nullptr;
  // prepare_config unmasked, commit_config masked.
  ApplyResult apply_kernel_config(const kernel::KernelConfig& cfg);
};

extern template class ControllerDevice<float>;
extern template class ControllerDevice<numeric::Q7_24>;

}  // namespace maglev::modbus
