// PmlsmController: one servo tick of paper 002's stage (see pmlsm_stage.hpp
// for the data path). Float32, all state inside the object, no heap, no
// exceptions, no libm in the tick: the same object runs on the M7 (bit-exact
// replay, tests/target/bitexact) and on the bench (maglev-hil --profile
// fmp2009-pmlsm).
//
// States: landed (amplifiers off, the platen on its stops at the rest gap)
// -> lifting (every loop closed, the gap reference ramps from the measured
// gap to the nominal gap) -> ready (motion commands) -> landing (the ramp
// into the lower stops, then amplifiers off) -> landed. A fault latches
// (until kClearFault) and lands the platen under control while the gap
// encoder is good, amplifiers off at once when it is not (see latch()).
#pragma once

#include <cstdint>

#include "maglev/controller/controller.hpp"
#include "maglev/pmlsm_stage/feedback_linearization.hpp"
#include "maglev/pmlsm_stage/pmlsm_stage.hpp"
#include "maglev/supervisor/supervisor.hpp"

namespace maglev::pmlsm_stage {

using kernel::CommandResult;
using kernel::FaultCode;

// Values cross the bench's metrics and the replay vectors: never renumber.
enum class StageState : std::uint8_t { kLanded = 0, kLifting = 1, kReady = 2, kLanding = 3, kFault = 4 };
const char* to_string(StageState s);

enum class PmlsmConfigError : std::uint8_t {
  kOk = 0,
  kBadServoRate = 1,
  kBadBody = 2,
  kBadTable = 3,
  kBadGains = 4,
  kBadLimits = 5,        // phase peak beyond the DAC, reference range outside the window
  kLockedWhileLevitated = 6,
};
const char* to_string(PmlsmConfigError e);

enum class MotionType : std::uint8_t {
  kLevitate = 0,
  kLand = 1,
  kClearFault = 2,
  kHold = 3,       // every axis keeps its present reference (stops ramps and sinusoids)
  kStep = 4,       // axis, delta: applied in one tick (the paper's set-point steps)
  kMoveTo = 5,     // axis, target, velocity: constant-speed ramp
  kSinusoid = 6,   // axis, center, amplitude, omega, phase: r = center + A sin(omega t + phase)
};

struct MotionCommand {
  MotionType type = MotionType::kHold;
  Axis axis = Axis::kGap;
  float delta = 0.0f;          // kStep (m or rad)
  float target = 0.0f;         // kMoveTo
  float velocity = 0.0f;       // kMoveTo (m/s or rad/s)
  float center = 0.0f;         // kSinusoid
  float amplitude = 0.0f;      // kSinusoid
  float omega_rad_per_s = 0.0f;  // kSinusoid
  float phase_rad = 0.0f;      // kSinusoid, at the first tick
};

struct PmlsmStatus {
  StageState state = StageState::kLanded;
  FaultCode fault = FaultCode::kNone;
  std::uint32_t tick = 0;
  float pose[kAxes] = {};        // m, rad
  float reference[kAxes] = {};
  float w[kAxes] = {};           // regulator outputs (m/s^2, rad/s^2)
  float i_d_A[kMotors] = {};     // commanded, after the phase clamp
  float i_q_A[kMotors] = {};
  float phase_A[kMotors][3] = {};
  float u_x_raw_A = 0.0f, u_z_raw_A = 0.0f;
  bool horizontal_saturated = false;  // sat_7 acted on u_x or u_z
  bool phase_clamped = false;         // the phase clamp scaled a motor's currents
  std::uint32_t saturated_ticks = 0;  // consecutive ticks with the phase clamp acting
  bool motion_active = false;
};

class PmlsmController {
 public:
  PmlsmController() = default;

  PmlsmConfigError apply_config(const PmlsmKernelConfig& config);
  CommandResult command(const MotionCommand& cmd);
  ActuatorCommand step(const SensorSample& sample);

  const PmlsmStatus& status() const { return status_; }
  const PmlsmKernelConfig& config() const { return config_; }
  bool configured() const { return configured_; }

 private:
  struct Ramp {
    bool active = false;
    float target = 0.0f;
    float step = 0.0f;  // per tick
  };
  struct Sinusoid {
    bool active = false;
    float center = 0.0f, amplitude = 0.0f;
    std::uint32_t phase = 0, increment = 0;
  };
  // suspect_axes: bit a = axis a's encoder cannot be trusted any more.
  void latch(FaultCode f, std::uint8_t suspect_axes);
  bool supervise(const SensorSample& s);
  void advance_references();
  void reset_loops();
  bool reference_in_range(int a, float v) const;
  void cancel(int a);

  PmlsmKernelConfig config_{};
  bool configured_ = false;
  bool first_sample_ = true;
  std::int32_t last_counts_[kAxes] = {};
  std::uint32_t stale_ticks_ = 0;
  std::uint32_t landing_hold_ticks_ = 0;
  bool fault_landing_ = false;  // latched fault, landing under control before the amplifiers go off
  std::uint8_t suspect_ = 0;    // axes whose encoder a fault made suspect
  bool loops_fresh_ = true;
  float xi_[kAxes][3] = {};
  float filt_[kAxes] = {};
  float ref_[kAxes] = {};
  float pending_step_[kAxes] = {};
  Ramp ramp_[kAxes]{};
  Sinusoid sine_[kAxes]{};
  PmlsmStatus status_{};
};

}  // namespace maglev::pmlsm_stage
