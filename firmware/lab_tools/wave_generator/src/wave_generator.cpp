#include "maglev/lab_tools/wave_generator.hpp"

#include <cmath>

#include "maglev/numeric/sin_cos.hpp"
#include "maglev/numeric/elementary.hpp"

namespace maglev::lab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kQ30 = 1.0f / 1073741824.0f;

float sine(std::uint32_t phase) { return static_cast<float>(numeric::sin_q30(phase)) * kQ30; }

std::uint32_t phase_increment(double f_Hz, double fs_Hz) {
  return static_cast<std::uint32_t>(std::llround(f_Hz / fs_Hz * 4294967296.0));
}

}  // namespace

float amplitude_limit(const kernel::KernelConfig& k, std::uint16_t axis, InjectionPoint point) {
  if (axis >= kernel::kAxisCount) return 0.0f;
  return point == InjectionPoint::kEffort ? k.excitation.max_amplitude_A : k.references.max_step[axis];
}

WaveError WaveGenerator::check(const WaveConfig& c, const kernel::KernelConfig& k) const {
  if (c.axis >= kernel::kAxisCount) return WaveError::kAxis;
  if (c.point != InjectionPoint::kEffort && c.point != InjectionPoint::kReference) return WaveError::kPoint;
  if (c.shape != WaveShape::kSine && c.shape != WaveShape::kSweep && c.shape != WaveShape::kMultisine &&
      c.shape != WaveShape::kNoise) {
    return WaveError::kShape;
  }
  if (!(c.amplitude > 0.0f) || c.amplitude > amplitude_limit(k, c.axis, c.point)) return WaveError::kAmplitude;
  const float nyquist = k.servo_rate_Hz / 2.0f;
  const bool uses_end = c.shape == WaveShape::kSweep || c.shape == WaveShape::kMultisine;
  if (c.shape != WaveShape::kNoise) {
    if (!(c.f_start_Hz > 0.0f) || (uses_end && !(c.f_end_Hz >= c.f_start_Hz))) return WaveError::kFrequency;
    const float f_max = uses_end ? c.f_end_Hz : c.f_start_Hz;
    if (f_max >= nyquist) return WaveError::kNyquist;
    if (f_max > k.excitation.max_frequency_Hz) return WaveError::kFrequency;
  }
  if (!(c.duration_s >= 0.0f) || c.duration_s > k.excitation.max_duration_s) return WaveError::kDuration;
  if (c.shape == WaveShape::kSweep && !(c.duration_s > 0.0f)) return WaveError::kDuration;
  if (c.shape == WaveShape::kMultisine) {
    if (c.tones < 1 || c.tones > kMaxTones) return WaveError::kTones;
    const auto period_ticks = static_cast<std::uint32_t>(std::lround(k.servo_rate_Hz / kMultisineGrid_Hz));
    const std::uint32_t hold = MultisineHoldTicks(period_ticks, table_len_);
    if (hold == 0 || period_ticks / hold < 2) return WaveError::kTable;
    // Every tone below the held table's own Nyquist (else it would alias).
    if (c.f_end_Hz >= k.servo_rate_Hz / static_cast<float>(2 * hold)) return WaveError::kTable;
  }
  return WaveError::kOk;
}

WaveError WaveGenerator::start(const WaveConfig& c, const kernel::KernelConfig& k) {
  if (state_ == WaveState::kRunning) return WaveError::kBusy;
  const WaveError e = check(c, k);
  if (e != WaveError::kOk) return e;
  config_ = c;
  servo_rate_Hz_ = k.servo_rate_Hz;
  const double fs = static_cast<double>(k.servo_rate_Hz);
  tick_ = 0;
  // 0 runs until stopped; any positive duration lasts at least one tick (a
  // 0.1 ms sweep rounded to 0, ran forever and multiplied its frequency by
  // f_end / f_start every tick, past Nyquist and on to inf).
  const long long ticks = std::llround(static_cast<double>(c.duration_s) * fs);
  duration_ticks_ = static_cast<std::uint32_t>(c.duration_s > 0.0f && ticks < 1 ? 1 : ticks);
  phase_ = 0;
  index_ = 0;
  tones_generated_ = 0;
  switch (c.shape) {
    case WaveShape::kSine:
      increment_ = phase_increment(static_cast<double>(c.f_start_Hz), fs);
      break;
    case WaveShape::kSweep: {
      // Exponential sweep: f(t) = f0 (f1/f0)^(t/T); per tick the increment
      // grows by (f1/f0)^(1/N).
      sweep_phase_ = 0.0;
      sweep_increment_ = static_cast<double>(c.f_start_Hz) / fs;
      const double n = static_cast<double>(duration_ticks_ > 1 ? duration_ticks_ - 1 : 1);
      sweep_ratio_ = numeric::dpow(static_cast<double>(c.f_end_Hz) / static_cast<double>(c.f_start_Hz), 1.0 / n);
      break;
    }
    case WaveShape::kMultisine: {
      const auto period_ticks = static_cast<std::uint32_t>(std::lround(fs / static_cast<double>(kMultisineGrid_Hz)));
      hold_ = MultisineHoldTicks(period_ticks, table_len_);  // >= 1: check() passed
      hold_left_ = hold_;
      period_ = period_ticks / hold_;
      const double df = fs / static_cast<double>(period_ticks);
      // Log-spaced tones rounded to the grid, duplicates dropped.
      std::uint32_t bins[kMaxTones];
      for (std::uint16_t t = 0; t < c.tones; ++t) {
        const double f = c.tones == 1 ? static_cast<double>(c.f_start_Hz)
                                      : static_cast<double>(c.f_start_Hz) *
                                            numeric::dpow(static_cast<double>(c.f_end_Hz) / static_cast<double>(c.f_start_Hz),
                                                     static_cast<double>(t) / (c.tones - 1));
        auto b = static_cast<std::uint32_t>(std::llround(f / df));
        if (b < 1) b = 1;
        if (tones_generated_ == 0 || b > bins[tones_generated_ - 1]) bins[tones_generated_++] = b;
      }
      for (std::uint32_t i = 0; i < period_; ++i) table_[i] = 0.0f;
      // One period, tone by tone, by phasor rotation (no sin() per sample:
      // 200 tones x 2500 samples stays a few ms of thread-mode time).
      const double nt = static_cast<double>(tones_generated_);
      for (std::uint16_t t = 0; t < tones_generated_; ++t) {
        tone_Hz_[t] = static_cast<float>(bins[t] * df);
        const double kk = static_cast<double>(t + 1);
        const double phi = -kPi * kk * (kk - 1.0) / nt;  // Schroeder phases: low crest factor
        const double w = 2.0 * kPi * static_cast<double>(bins[t]) / static_cast<double>(period_);
        const double cw = numeric::dcos(w), sw = numeric::dsin(w);
        double re = numeric::dcos(phi), im = numeric::dsin(phi);  // e^{j(w i + phi)}
        for (std::uint32_t i = 0; i < period_; ++i) {
          table_[i] += static_cast<float>(im);
          const double r2 = re * cw - im * sw;
          im = re * sw + im * cw;
          re = r2;
        }
      }
      float peak = 0.0f;
      for (std::uint32_t i = 0; i < period_; ++i) peak = std::fabs(table_[i]) > peak ? std::fabs(table_[i]) : peak;
      const float scale = peak > 0.0f ? c.amplitude / peak : 0.0f;
      for (std::uint32_t i = 0; i < period_; ++i) table_[i] *= scale;
      break;
    }
    case WaveShape::kNoise:
      noise_ = 0x12345678u;
      break;
  }
  state_ = WaveState::kRunning;  // last: the tick starts generating now
  return WaveError::kOk;
}

void WaveGenerator::stop() {
  if (state_ == WaveState::kRunning) state_ = WaveState::kOff;
}

kernel::Injection WaveGenerator::step(bool motion_allowed) {
  kernel::Injection in{};
  if (state_ != WaveState::kRunning) return in;
  if (!motion_allowed) {
    state_ = WaveState::kAborted;
    return in;
  }
  if (duration_ticks_ != 0 && tick_ >= duration_ticks_) {
    state_ = WaveState::kFinished;
    return in;
  }
  float v = 0.0f;
  switch (config_.shape) {
    case WaveShape::kSine:
      v = config_.amplitude * sine(phase_);
      phase_ += increment_;
      break;
    case WaveShape::kSweep: {
      const double turns = sweep_phase_ - std::floor(sweep_phase_);
      v = config_.amplitude * sine(static_cast<std::uint32_t>(turns * 4294967296.0));
      sweep_phase_ += sweep_increment_;
      sweep_increment_ *= sweep_ratio_;
      break;
    }
    case WaveShape::kMultisine:
      v = table_[index_];
      if (--hold_left_ == 0) {
        hold_left_ = hold_;
        index_ = index_ + 1u == period_ ? 0u : index_ + 1u;
      }
      break;
    case WaveShape::kNoise: {
      std::uint32_t x = noise_;
      x ^= x << 13;
      x ^= x >> 17;
      x ^= x << 5;
      noise_ = x;
      v = config_.amplitude * (static_cast<float>(x) * (2.0f / 4294967296.0f) - 1.0f);
      break;
    }
  }
  ++tick_;
  in.active = true;
  in.at_reference = config_.point == InjectionPoint::kReference;
  in.axis = static_cast<std::uint8_t>(config_.axis);
  in.value = v;
  return in;
}

}  // namespace maglev::lab
