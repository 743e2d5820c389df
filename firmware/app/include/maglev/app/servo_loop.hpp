// The servo application: one tick = read inputs -> kernel step() -> write
// outputs, run from the top-priority interrupt (AD7606 BUSY falling edge on
// the board). Everything else (Modbus, CAN telemetry, recorder drain) runs at
// lower priority and only ever sees the loop's State.
//
// Safety properties this file owns:
//   * zero-current preset: every tick starts from io::kSafeActuatorCommand;
//     if the inputs are bad the kernel still runs (so its supervisor sees
//     kAdcFault and latches) but the outputs written are the safe ones;
//   * missed ticks: check_deadline(), called from a lower-priority periodic
//     interrupt, makes the outputs safe (ActuatorSink::force_safe) when no
//     tick has completed for `deadline_ticks` periods (ADC/timer dead:
//     nothing else would). force_safe, not write: a tick that resumes at
//     that moment preempts it, and must not find a DAC transfer half-started
//     by the lower-priority path (that abandoned write tripped the latched
//     enable: safe, but a spurious trip);
//   * overruns: a tick that used more than `cycle_budget` cycles, or after
//     which the next tick is already pending, or that is re-entered, sets
//     State::overruns and passes tick_overrun = true to the NEXT step();
//   * watchdog: the loop checks in with the FeedGate every tick; the
//     communications loop must check in too before the IWDG is fed.
//
// Kernel is any type with `io::ActuatorCommand step(const io::SensorSample&,
// bool tick_overrun)` -- maglev::kernel::Controller<float> on the board.
#pragma once

#include <cstdint>

#include "maglev/app/board_io.hpp"
#include "maglev/io/actuator_command.hpp"
#include "maglev/io/sensor_sample.hpp"

namespace maglev::app {

struct ServoConfig {
  std::uint32_t cycle_budget = 0;      // CPU cycles a tick may use (0 = no budget check)
  std::uint32_t period_cycles = 0;     // CPU cycles per servo period
  std::uint32_t deadline_ticks = 3;    // missed periods before outputs are forced safe
};

struct ServoState {
  std::uint32_t ticks = 0;
  std::uint32_t overruns = 0;        // budget exceeded / next tick already pending / re-entry
  std::uint32_t sensor_faults = 0;
  std::uint32_t missed_deadlines = 0;
  std::uint32_t last_cycles = 0;
  std::uint32_t max_cycles = 0;
  std::uint32_t last_tick_start = 0;  // cycle counter at the start of the last tick
};

// Cheap hooks the board provides (plain function pointers: no std::function).
struct ServoHooks {
  std::uint32_t (*cycle_counter)() = nullptr;  // DWT CYCCNT on the board
  bool (*next_tick_pending)() = nullptr;       // the tick interrupt is pending again
  void (*servo_ran)() = nullptr;               // FeedGate::servo_ran
  void (*record)(const io::SensorSample&, const io::ActuatorCommand&) = nullptr;  // recorder
  // Right before kernel step() (the lab wave generator hands the kernel this
  // tick's injection: Controller::set_injection).
  void (*before_step)() = nullptr;
};

template <typename Kernel>
class ServoLoop {
 public:
  ServoLoop(SensorSource& sensors, ActuatorSink& actuators, Kernel& kernel, const ServoConfig& config,
            const ServoHooks& hooks)
      : sensors_(sensors), actuators_(actuators), kernel_(kernel), config_(config), hooks_(hooks) {}

  // Top-priority interrupt body.
  void on_tick() {
    const std::uint32_t start = cycles();
    if (in_tick_) {  // only possible if someone calls on_tick from a nested context
      ++state_.overruns;
      overrun_pending_ = true;
      return;
    }
    in_tick_ = true;
    io::ActuatorCommand command = io::kSafeActuatorCommand;
    // All zero, as `io::SensorSample sample{}` would be: what a failed read
    // leaves unwritten reads 0. Copied from blank_sample_ (never written)
    // because the value-initialization compiled to a memset call on the
    // Cortex-M7 (~50 instructions a tick); the copy is a few LDM / STM.
    io::SensorSample sample = blank_sample_;
    const bool inputs_ok = sensors_.read(sample);
    if (!inputs_ok) {
      sample.status_flags = static_cast<std::uint16_t>(sample.status_flags | io::kAdcFault);
      ++state_.sensor_faults;
    }
    if (hooks_.before_step != nullptr) hooks_.before_step();
    const io::ActuatorCommand kernel_command = kernel_.step(sample, overrun_pending_);
    overrun_pending_ = false;
    if (inputs_ok) command = kernel_command;
    actuators_.write(command);
    if (hooks_.record != nullptr) hooks_.record(sample, command);
    if (hooks_.servo_ran != nullptr) hooks_.servo_ran();

    const std::uint32_t used = cycles() - start;
    state_.last_cycles = used;
    if (used > state_.max_cycles) state_.max_cycles = used;
    const bool over_budget = config_.cycle_budget != 0 && used > config_.cycle_budget;
    const bool next_due = hooks_.next_tick_pending != nullptr && hooks_.next_tick_pending();
    if (over_budget || next_due) {
      ++state_.overruns;
      overrun_pending_ = true;
    }
    state_.last_tick_start = start;
    ++state_.ticks;
    in_tick_ = false;
  }

  // Lower-priority periodic check (e.g. SysTick): force safe outputs when
  // the tick source has stopped. Returns true if it had to.
  bool check_deadline(std::uint32_t now_cycles) {
    if (config_.period_cycles == 0 || in_tick_) return false;
    const std::uint32_t ticks = state_.ticks;
    const std::uint32_t since = now_cycles - state_.last_tick_start;
    if (ticks == deadline_ticks_seen_ && since > config_.deadline_ticks * config_.period_cycles) {
      actuators_.force_safe();
      ++state_.missed_deadlines;
      state_.last_tick_start = now_cycles;  // re-arm: repeat once per deadline while stalled
      return true;
    }
    deadline_ticks_seen_ = ticks;
    return false;
  }

  const ServoState& state() const { return state_; }
  bool overrun_pending() const { return overrun_pending_; }
  // A new servo rate (register servo.rate, applied landed): the budget and
  // period in CPU cycles. Only with the tick source stopped (the board
  // re-programs its timer around it).
  void set_timing(const ServoConfig& config) { config_ = config; }
  const ServoConfig& timing() const { return config_; }

 private:
  std::uint32_t cycles() const { return hooks_.cycle_counter != nullptr ? hooks_.cycle_counter() : 0u; }

  // The compiler cannot fold this non-const all-zero sample back into a
  // memset; nothing writes it.
  static inline io::SensorSample blank_sample_{};

  SensorSource& sensors_;
  ActuatorSink& actuators_;
  Kernel& kernel_;
  ServoConfig config_;
  ServoHooks hooks_;
  ServoState state_{};
  volatile bool in_tick_ = false;
  bool overrun_pending_ = false;
  std::uint32_t deadline_ticks_seen_ = 0;
};

}  // namespace maglev::app
