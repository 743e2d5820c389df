// The device behind the register map in the Modbus fuzzers (RTU, MBAP):
// accepts everything and cycles its activity and answers, so every write
// condition and every kind of reply of the map is exercised.
#pragma once

#include <cstdint>

#include "maglev/modbus/register_server.hpp"

namespace maglev::test {

class FuzzDevice final : public modbus::Device {
 public:
  modbus::Activity activity() const override { return static_cast<modbus::Activity>(calls_ % 3); }
  double read_status(modbus::RegId id) const override { return static_cast<double>(static_cast<int>(id)) * 1e-6; }
  ApplyResult apply_config(modbus::ConfigImage& c, bool) override {
    ++calls_;
    return static_cast<ApplyResult>(c.raw[0] % 3);
  }
  std::uint16_t command(std::uint16_t code, std::uint16_t axis, float) override {
    ++calls_;
    return static_cast<std::uint16_t>(static_cast<unsigned>(code) + axis);
  }
  bool save_config(const modbus::ConfigImage&) override { return (++calls_ & 1u) != 0; }
  modbus::PersistStatus persist_status() const override { return {}; }

 private:
  unsigned calls_ = 0;
};

}  // namespace maglev::test
