// app::HostCommandQueue: decoded host_command frames handed from the CAN
// receive path (the HIL board's CanSensorSource, in the servo interrupt) to
// app::Application::service (thread mode), which executes them on the kernel
// and answers host_command_ack. Single producer, single consumer; the
// consumer runs inside hooks.critical_enter/exit, the indices are atomic so a
// producer on another context never sees a half-written slot. Full -> the
// newest command is dropped and counted (the host sees no ack and retries).
// Heap-free, exception-free; host + Cortex-M7. Depends on can_link only.
#pragma once

#include <atomic>
#include <cstdint>

#include "maglev/can_link/codec.hpp"

namespace maglev::app {

class HostCommandQueue {
 public:
  static constexpr std::uint32_t kCapacity = 8;  // a burst of operator commands per service pass

  bool push(const can::HostCommandFrame& cmd) {
    const std::uint32_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= kCapacity) {
      ++dropped_;
      return false;
    }
    slots_[head % kCapacity] = cmd;
    head_.store(head + 1u, std::memory_order_release);
    return true;
  }
  bool pop(can::HostCommandFrame& out) {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail % kCapacity];
    tail_.store(tail + 1u, std::memory_order_release);
    return true;
  }
  std::uint32_t size() const { return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire); }
  std::uint32_t dropped() const { return dropped_; }

 private:
  can::HostCommandFrame slots_[kCapacity] = {};
  std::atomic<std::uint32_t> head_{0};
  std::atomic<std::uint32_t> tail_{0};
  std::uint32_t dropped_ = 0;
};

}  // namespace maglev::app
