// The amplifier-enable interlock line. The eight linear current amplifiers
// only drive their coils while this line is high; the board has a pull-down
// on it, so during reset, boot and any MCU fault it is OFF in hardware.
// Software keeps the same default: the line is driven low at construction,
// and every fault latches it low until the fault is explicitly cleared --
// a later enable request alone cannot re-energise the coils.
#pragma once

#include <cstdint>

#include "maglev/drivers/bus.hpp"

namespace maglev::drivers {

class AmplifierEnable {
 public:
  explicit AmplifierEnable(OutputPin& line) : line_(line) { line_.write(false); }

  // Apply the command's enable request; returns the level actually driven.
  // The line is written when its level changes: nothing else drives it (the
  // constructor set it low, trip() drives it low), so `enabled_` is its
  // level, and the DAC interrupt's request(true) on every tick costs no
  // pin write.
  bool request(bool enable) {
    const bool on = enable && !fault_latched_;
    if (on != enabled_) line_.write(on);
    enabled_ = on;
    return on;
  }
  // Immediate OFF, latched (supervisor trip, watchdog pre-warning, overrun).
  void trip() {
    fault_latched_ = true;
    line_.write(false);
    enabled_ = false;
    ++trips_;
  }
  void clear_fault() { fault_latched_ = false; }

  bool enabled() const { return enabled_; }
  bool fault_latched() const { return fault_latched_; }
  std::uint32_t trips() const { return trips_; }

 private:
  OutputPin& line_;
  bool enabled_ = false;
  bool fault_latched_ = false;
  std::uint32_t trips_ = 0;
};

}  // namespace maglev::drivers
