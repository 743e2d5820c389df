// A Device for the PROTOCOL tests (framing, exceptions, whole-or-nothing
// writes): it stands in for the stage behind the maglev::modbus::Device
// interface only, with a settable activity, and it persists through the real
// ConfigStore on a RamFlash. Tests that need the stage itself use the real
// kernel through the controller binding.
#pragma once

#include <cstdint>
#include <vector>

#include "maglev/modbus/register_server.hpp"
#include "maglev/persistence/config_store.hpp"

namespace maglev::modbus::test {

class ProtocolDevice final : public Device {
 public:
  ProtocolDevice() : flash_(storage_, 4096, 4), store_(flash_, 2, 3) {
    for (std::uint8_t& b : storage_) b = 0xFF;  // a fresh, erased part
    loaded_ = store_.load();
  }

  Activity activity() const override { return activity_; }
  double read_status(RegId id) const override {
    switch (id) {
      case RegId::status_x: return 1.25e-3;
      case RegId::status_theta_z: return -2.5e-6;
      case RegId::status_state: return 3;
      case RegId::status_moving: return activity_ == Activity::kMoving ? 1 : 0;
      default: return 0;
    }
  }
  ApplyResult apply_config(ConfigImage& config, bool live_tuning) override {
    last_live_tuning = live_tuning;
    ++apply_calls;
    if (refuse_config) return ApplyResult::kRefused;
    applied = config;
    return ApplyResult::kApplied;
  }
  std::uint16_t command(std::uint16_t code, std::uint16_t axis, float value) override {
    commands.push_back({code, axis, value});
    return 0;
  }
  bool save_config(const ConfigImage& config) override { return !fail_save && store_.save(config); }
  PersistStatus persist_status() const override { return store_.status(); }

  struct Command {
    std::uint16_t code;  // can::HostCommandCode value
    std::uint16_t axis;
    float value;
  };
  Activity activity_ = Activity::kIdle;
  bool refuse_config = false;
  bool fail_save = false;  // flash write failure
  bool last_live_tuning = false;
  int apply_calls = 0;
  ConfigImage applied = ConfigImage::defaults();
  std::vector<Command> commands;
  persistence::LoadResult loaded_;
  persistence::ConfigStore& store() { return store_; }

 private:
  std::uint8_t storage_[4096 * 4];
  persistence::RamFlash flash_;
  persistence::ConfigStore store_;
};

}  // namespace maglev::modbus::test
