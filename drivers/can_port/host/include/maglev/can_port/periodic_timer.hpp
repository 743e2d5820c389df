// Host-only real-time pacing: a timerfd on CLOCK_MONOTONIC armed with
// ABSOLUTE deadlines (deadline k = start + k * period, so errors never
// accumulate). wait() blocks until the next deadline; deadlines that passed
// while the caller was busy are counted as misses (timerfd's expiration
// count - 1). Wake-up lateness (now - deadline) goes into a fixed-bin
// histogram.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace maglev::can {

struct JitterHistogram {
  // Upper bin edges in microseconds; the last bin is "above the last edge".
  static constexpr std::array<std::uint32_t, 9> kEdges_us = {5, 10, 20, 50, 100, 200, 500, 1000, 5000};
  std::array<std::uint64_t, kEdges_us.size() + 1> counts{};
  std::uint64_t samples = 0;
  std::int64_t max_ns = 0;
  double sum_ns = 0.0;
  void add(std::int64_t lateness_ns);
  std::string to_string() const;
};

class PeriodicTimer {
 public:
  explicit PeriodicTimer(std::uint64_t period_ns);
  ~PeriodicTimer();
  PeriodicTimer(const PeriodicTimer&) = delete;
  PeriodicTimer& operator=(const PeriodicTimer&) = delete;
  bool ok() const { return fd_ >= 0; }
  // Starts at now + period. Returns false if timerfd fails.
  bool start();
  // Blocks until the next deadline. Returns the number of periods elapsed
  // (1 normally; >1 means deadlines were missed and counted).
  std::uint64_t wait();
  std::uint64_t ticks() const { return ticks_; }
  std::uint64_t deadline_misses() const { return misses_; }
  const JitterHistogram& jitter() const { return jitter_; }
  std::uint64_t period_ns() const { return period_ns_; }

 private:
  int fd_ = -1;
  std::uint64_t period_ns_;
  std::int64_t start_ns_ = 0;
  std::uint64_t ticks_ = 0;
  std::uint64_t misses_ = 0;
  JitterHistogram jitter_;
};

std::int64_t monotonic_ns();

}  // namespace maglev::can
