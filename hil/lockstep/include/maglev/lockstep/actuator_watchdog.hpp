// The amplifier board's command watchdog on the bench (docs/RELIABILITY.md,
// "When the actuator link dies").
//
// A missing actuator frame is bridged by holding the last command for up to
// kActuatorHoldTicks ticks (10 ms at 2.5 kHz); after that the amplifiers are
// switched off (io::kSafeActuatorCommand) until a frame arrives again.
//
// Why hold rather than cut at once: the stage floats 30 um above its pads,
// so with zero current it touches down about 2.5 ms (6 ticks) later. Cutting
// on the first lost frame turned every burst of 6 or more lost frames into a
// 5 mm/s touchdown (the 500-run CAN campaign); holding the last currents for
// 10 ms keeps the weight compensated while the controller's own link-loss
// detection (stale sensor frames) takes over. A controller that is gone for
// longer than that cannot be helped from the amplifier side: the stage then
// drops from at most z_max (40 um), touchdown speed <= sqrt(2 g z_max)
// = 28 mm/s, in practice less (the pads' contact model).
#pragma once

#include <cstdint>

#include "maglev/io/actuator_command.hpp"

namespace maglev::lockstep {

inline constexpr std::uint32_t kActuatorHoldTicks = 25;

class ActuatorWatchdog {
 public:
  // One tick: `received` with its command, or not. Returns what the
  // amplifiers apply this tick.
  const io::ActuatorCommand& update(bool received, const io::ActuatorCommand& command) {
    if (received) {
      last_ = command;
      missed_run_ = 0;
    } else if (++missed_run_ > kActuatorHoldTicks) {
      last_ = io::kSafeActuatorCommand;
    }
    return last_;
  }
  std::uint32_t missed_run() const { return missed_run_; }

 private:
  io::ActuatorCommand last_ = io::kSafeActuatorCommand;
  std::uint32_t missed_run_ = 0;
};

}  // namespace maglev::lockstep
