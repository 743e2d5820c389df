#include "maglev/can_port/periodic_timer.hpp"

#include <sys/timerfd.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

namespace maglev::can {

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void JitterHistogram::add(std::int64_t lateness_ns) {
  const std::int64_t us = lateness_ns / 1000;
  std::size_t bin = kEdges_us.size();
  for (std::size_t i = 0; i < kEdges_us.size(); ++i) {
    if (us < static_cast<std::int64_t>(kEdges_us[i])) {
      bin = i;
      break;
    }
  }
  ++counts[bin];
  ++samples;
  if (lateness_ns > max_ns) max_ns = lateness_ns;
  sum_ns += static_cast<double>(lateness_ns);
}

std::string JitterHistogram::to_string() const {
  std::string out;
  char buf[96];
  std::uint32_t lo = 0;
  for (std::size_t i = 0; i <= kEdges_us.size(); ++i) {
    if (i < kEdges_us.size()) {
      std::snprintf(buf, sizeof buf, "[%u,%u) us: %llu\n", lo, kEdges_us[i],
                    static_cast<unsigned long long>(counts[i]));
      lo = kEdges_us[i];
    } else {
      std::snprintf(buf, sizeof buf, ">= %u us: %llu\n", lo, static_cast<unsigned long long>(counts[i]));
    }
    out += buf;
  }
  std::snprintf(buf, sizeof buf, "samples %llu, mean %.1f us, max %.1f us\n",
                static_cast<unsigned long long>(samples),
                samples ? sum_ns / static_cast<double>(samples) / 1000.0 : 0.0,
                static_cast<double>(max_ns) / 1000.0);
  out += buf;
  return out;
}

PeriodicTimer::PeriodicTimer(std::uint64_t period_ns)
    : fd_(timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC)), period_ns_(period_ns) {}

PeriodicTimer::~PeriodicTimer() {
  if (fd_ >= 0) ::close(fd_);
}

bool PeriodicTimer::start() {
  if (fd_ < 0) return false;
  start_ns_ = monotonic_ns();
  const std::int64_t first = start_ns_ + static_cast<std::int64_t>(period_ns_);
  itimerspec spec{};
  spec.it_value.tv_sec = first / 1'000'000'000;
  spec.it_value.tv_nsec = first % 1'000'000'000;
  spec.it_interval.tv_sec = static_cast<time_t>(period_ns_ / 1'000'000'000u);
  spec.it_interval.tv_nsec = static_cast<long>(period_ns_ % 1'000'000'000u);
  ticks_ = 0;
  misses_ = 0;
  return timerfd_settime(fd_, TFD_TIMER_ABSTIME, &spec, nullptr) == 0;
}

std::uint64_t PeriodicTimer::wait() {
  std::uint64_t expirations = 0;
  for (;;) {
    const ssize_t n = ::read(fd_, &expirations, sizeof expirations);
    if (n == static_cast<ssize_t>(sizeof expirations)) break;
    if (n < 0 && errno == EINTR) continue;
    return 0;
  }
  const std::int64_t now = monotonic_ns();
  ticks_ += expirations;
  misses_ += expirations - 1;
  // The deadline of the latest expiration: start + ticks * period.
  const std::int64_t deadline = start_ns_ + static_cast<std::int64_t>(ticks_ * period_ns_);
  jitter_.add(now - deadline);
  return expirations;
}

}  // namespace maglev::can
