// lab::WaveGenerator: test signals injected into the running loop of one axis,
// at its effort (A) or its reference (m / rad), through
// kernel::Controller::set_injection (the kernel clamps again and applies it
// only on a closed axis in Ready).
//
// Data path (one tick, before kernel step()):
//   ServoHooks::before_step -> WaveGenerator::step(motion_allowed) -> Injection
//     -> Controller::set_injection -> step(): effort d / reference offset
// Shapes:
//   sine       A sin(2 pi f t), phase accumulator (2^32 = one turn), the kernel's sine table
//   sweep      exponential (log) sine sweep f_start -> f_end over duration_s, then stops
//   multisine  Schroeder-phased tones, log-spaced f_start..f_end on the grid
//              servo_rate / period (period = servo_rate / 1 Hz samples: 1 Hz grid),
//              one period precomputed into a static table by start() (thread
//              mode, before the generator runs): the tick reads one table entry
//   noise      uniform white noise in [-A, A] (xorshift32)
// amplitude is the PEAK of the injected signal (the multisine table is scaled
// so its peak is the amplitude): the limit check covers every shape.
//
// Refused (WaveError, nothing changed): unknown axis/point/shape, amplitude
// above the axis limit (effort: the kernel's ExcitationLimits::max_amplitude_A;
// reference: ReferenceLimits::max_step of the axis), a frequency at or above
// Nyquist (servo_rate / 2) or above the kernel's max excitation frequency,
// start > end, a sweep without duration, tones out of 1..kMaxTones.
//
// Heap-free, exception-free; host + Cortex-M7.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/controller/controller.hpp"

namespace maglev::lab {

// Pinned: register values (wave.shape, wave.point, wave.state).
enum class WaveShape : std::uint16_t { kSine = 0, kSweep = 1, kMultisine = 2, kNoise = 3 };
enum class InjectionPoint : std::uint16_t { kEffort = 0, kReference = 1 };
enum class WaveState : std::uint16_t {
  kOff = 0,
  kRunning = 1,
  kFinished = 2,  // duration elapsed / sweep ended
  kAborted = 3,   // motion no longer allowed (fault, landing, not Ready)
};
enum class WaveError : std::uint8_t {
  kOk = 0,
  kAxis = 1,
  kPoint = 2,
  kShape = 3,
  kAmplitude = 4,   // <= 0 or above the axis limit
  kFrequency = 5,   // <= 0, start > end, or above the kernel's max excitation frequency
  kNyquist = 6,     // at or above servo_rate / 2
  kDuration = 7,    // negative, too long, or a sweep without one
  kTones = 8,
  kBusy = 9,        // configuration while running
  kTable = 10,      // the multisine period does not fit the table
};

inline constexpr std::uint16_t kMaxTones = 200;
// The multisine grid: one period = servo_rate / kMultisineGrid_Hz ticks.
inline constexpr float kMultisineGrid_Hz = 1.0f;
// Table length: one multisine period at servo rates up to 4096 Hz sample by
// sample; above, the period's table is played with each sample held for
// MultisineHoldTicks ticks (5 and 10 kHz: 2500 samples, 20 kHz: 4000).
inline constexpr std::size_t kWaveTableLen = 4096;

// The ticks each multisine table sample is held for: the smallest h that
// divides the period (period_ticks = servo_rate / grid) into at most
// table_len samples; 0 if none up to kMaxMultisineHold does. A held sample is
// a zero-order hold at servo_rate / h: the tones keep their frequencies and
// the table's peak (so the amplitude limit holds), each is scaled by
// sinc(f h / servo_rate) (0.958 at 400 Hz, h = 4 at 10 kHz), and images
// appear only around multiples of servo_rate / h (>= 2500 Hz), above every
// tone the kernel's excitation limit (1 kHz) allows.
inline constexpr std::uint32_t kMaxMultisineHold = 16;
constexpr std::uint32_t MultisineHoldTicks(std::uint32_t period_ticks, std::uint32_t table_len) {
  for (std::uint32_t h = 1; h <= kMaxMultisineHold; ++h) {
    if (period_ticks % h == 0 && period_ticks / h <= table_len) return h;
  }
  return 0;
}

struct WaveConfig {
  std::uint16_t axis = 0;  // kernel Axis index
  InjectionPoint point = InjectionPoint::kEffort;
  WaveShape shape = WaveShape::kSine;
  float amplitude = 0.0f;    // peak; A (effort) or m / rad (reference)
  float f_start_Hz = 10.0f;  // sine: its frequency
  float f_end_Hz = 10.0f;    // sweep / multisine
  float duration_s = 0.0f;   // 0: until stopped (not for a sweep)
  std::uint16_t tones = 1;   // multisine
};

// The loop-response multisine: the bench's loop_response lines (28 tones
// log-spaced 5..400 Hz), 0.1 A peak at the effort of axis 0 (x). stagectl
// frf's default (a tenth of the amplitude on the rotations), the lab tick's
// measured setup (lab_tick_setup.hpp) and the tests start from it.
constexpr WaveConfig LoopResponseMultisine() {
  WaveConfig c{};
  c.shape = WaveShape::kMultisine;
  c.amplitude = 0.1f;
  c.f_start_Hz = 5.0f;
  c.f_end_Hz = 400.0f;
  c.tones = 28;
  return c;
}

// The amplitude limit of an axis at a point, from the kernel's configuration.
float amplitude_limit(const kernel::KernelConfig& k, std::uint16_t axis, InjectionPoint point);

class WaveGenerator {
 public:
  // `table`: static storage for one multisine period (>= servo_rate / 1 Hz floats).
  WaveGenerator(float* table, std::size_t table_len) : table_(table), table_len_(static_cast<std::uint32_t>(table_len)) {}

  WaveError check(const WaveConfig& c, const kernel::KernelConfig& k) const;
  // Check, build the multisine table (if any), start. Not while running.
  WaveError start(const WaveConfig& c, const kernel::KernelConfig& k);
  void stop();

  // The servo tick: this tick's injection (inactive when not running).
  // motion_allowed false while running aborts the generator.
  kernel::Injection step(bool motion_allowed);

  WaveState state() const { return state_; }
  const WaveConfig& config() const { return config_; }
  std::uint32_t tick() const { return tick_; }
  // Multisine: tones actually generated (after rounding to the grid), the
  // table's samples per period and the ticks each is held for (period() x
  // hold_ticks() ticks = one period of the 1 Hz grid).
  std::uint16_t tones_generated() const { return tones_generated_; }
  std::uint32_t period() const { return period_; }
  std::uint32_t hold_ticks() const { return hold_; }
  float tone_Hz(std::uint16_t i) const { return i < tones_generated_ ? tone_Hz_[i] : 0.0f; }

 private:
  float* table_;
  std::uint32_t table_len_;
  WaveConfig config_{};
  float servo_rate_Hz_ = 2500.0f;
  std::uint32_t tick_ = 0;
  std::uint32_t duration_ticks_ = 0;
  std::uint32_t phase_ = 0;
  std::uint32_t increment_ = 0;
  double sweep_phase_ = 0.0;       // turns
  double sweep_increment_ = 0.0;   // turns per tick
  double sweep_ratio_ = 1.0;       // increment growth per tick
  std::uint32_t period_ = 0;
  std::uint32_t index_ = 0;
  std::uint32_t hold_ = 1;       // ticks per table sample
  std::uint32_t hold_left_ = 0;  // ticks of the current sample still to come
  std::uint32_t noise_ = 0x12345678u;
  std::uint16_t tones_generated_ = 0;
  float tone_Hz_[kMaxTones] = {};
  volatile WaveState state_ = WaveState::kOff;
};

}  // namespace maglev::lab
