// Frame watchdogs. SensorFrameWatchdog (controller side): sensor frames stop
// for longer than the bound -> the kernel enters its safe reaction.
// ActuatorFrameWatchdog (plant side): actuator frames stop -> like an
// amplifier whose enable timed out: zero current.
//
// Default bound: 3 servo periods = 1.2 ms at 2.5 kHz. One lost frame is
// tolerated (the E2E receiver accepts a counter jump of up to 3), two are
// tolerated, the third consecutive silent period trips. Time is a wrapping
// uint32 microsecond clock; the lockstep mode feeds tick numbers * period.
#pragma once

#include <cstdint>

namespace maglev::can {

struct FrameWatchdogConfig {
  std::uint32_t timeout_us = 1200;  // 3 ticks at 2.5 kHz
};

class FrameWatchdog {
 public:
  using Config = FrameWatchdogConfig;
  FrameWatchdog() = default;
  explicit FrameWatchdog(Config config) : config_(config) {}

  // An accepted frame arrived at now_us.
  void feed(std::uint32_t now_us) {
    last_us_ = now_us;
    fed_ = true;
    expired_ = false;
  }
  // True while no accepted frame arrived for more than timeout_us (or none
  // ever since start_us). Counts each transition into "expired" once.
  bool check(std::uint32_t now_us) {
    if (!fed_) {
      // Before the first frame: measure from arm().
      if (static_cast<std::uint32_t>(now_us - last_us_) > config_.timeout_us && armed_) trip();
      return expired_;
    }
    if (static_cast<std::uint32_t>(now_us - last_us_) > config_.timeout_us) trip();
    return expired_;
  }
  // Start the clock without a frame (e.g. when the link is opened).
  void arm(std::uint32_t now_us) {
    last_us_ = now_us;
    armed_ = true;
  }
  bool expired() const { return expired_; }
  std::uint32_t timeouts() const { return timeouts_; }
  std::uint32_t timeout_us() const { return config_.timeout_us; }

 private:
  void trip() {
    if (!expired_) ++timeouts_;
    expired_ = true;
  }
  Config config_;
  std::uint32_t last_us_ = 0;
  std::uint32_t timeouts_ = 0;
  bool fed_ = false;
  bool armed_ = false;
  bool expired_ = false;
};

// Same mechanism, named by role so call sites read right.
class SensorFrameWatchdog : public FrameWatchdog {
 public:
  using FrameWatchdog::FrameWatchdog;
};
class ActuatorFrameWatchdog : public FrameWatchdog {
 public:
  using FrameWatchdog::FrameWatchdog;
};

}  // namespace maglev::can
