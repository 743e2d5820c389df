// Host-only in-process virtual CAN bus: deterministic, any number of
// endpoints per bus, each endpoint receives every other endpoint's frames (not
// its own), in send order. Thread-safe (a plant thread and a controller
// thread may share a bus), unless made with Threading::kOneThread: the
// owner's promise that every port of the bus is used from one thread (the
// bench's in-process lockstep run), which saves the lock of every send and
// receive (~8 a tick: ~3 % of a bench tick's wall time). Optional fault injection on every sent frame:
// drop, corrupt (flip one bit), duplicate, delay (hold back until N later
// frames have been sent on the bus) -- deterministic, no clocks involved.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "maglev/can_port/host_can_port.hpp"

namespace maglev::can {

struct FaultAction {
  enum Kind : std::uint8_t { kDeliver, kDrop, kCorrupt, kDuplicate, kDelay } kind = kDeliver;
  std::uint16_t corrupt_bit = 0;     // kCorrupt: bit index into data (bit % (8*len))
  std::uint32_t delay_frames = 1;    // kDelay: delivered after this many later frames
};

// Called for every frame sent on the bus; seq counts frames sent on the bus.
using FaultHook = std::function<FaultAction(const CanFrame& frame, std::uint64_t seq)>;

class VirtualCanPort;

class VirtualBus : public std::enable_shared_from_this<VirtualBus> {
 public:
  // Named buses are shared per process: get("bench") twice gives one bus.
  static std::shared_ptr<VirtualBus> get(const std::string& name);
  enum class Threading : std::uint8_t { kShared, kOneThread };
  explicit VirtualBus(std::string name, Threading threading = Threading::kShared)
      : name_(std::move(name)), one_thread_(threading == Threading::kOneThread) {}

  std::unique_ptr<VirtualCanPort> open_endpoint(std::size_t rx_queue_depth = 4096);
  void set_fault_hook(FaultHook hook);
  const std::string& name() const { return name_; }
  std::uint64_t frames_sent() const;

 private:
  friend class VirtualCanPort;
  struct Delayed {
    CanFrame frame;
    VirtualCanPort* sender;
    std::uint64_t release_at_seq;
  };
  void transmit(VirtualCanPort* sender, const CanFrame& f);
  void deliver_locked(VirtualCanPort* sender, const CanFrame& f);
  void detach(VirtualCanPort* p);
  // mu_, locked unless the bus is kOneThread.
  std::unique_lock<std::mutex> lock() const {
    return one_thread_ ? std::unique_lock<std::mutex>(mu_, std::defer_lock) : std::unique_lock<std::mutex>(mu_);
  }

  std::string name_;
  const bool one_thread_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::vector<VirtualCanPort*> endpoints_;
  std::deque<Delayed> delayed_;
  FaultHook hook_;
  std::uint64_t seq_ = 0;
};

class VirtualCanPort final : public OwnedCanPort {
 public:
  VirtualCanPort(std::shared_ptr<VirtualBus> bus, std::size_t depth);
  ~VirtualCanPort() override;
  PortStatus send(const CanFrame& frame) override;
  PortStatus receive(CanFrame& frame, std::uint32_t timeout_us) override;
  const PortCounters& counters() const override { return counters_; }
  const char* name() const override { return name_.c_str(); }
  std::size_t pending() const;

 private:
  friend class VirtualBus;
  std::shared_ptr<VirtualBus> bus_;
  std::size_t depth_;
  std::deque<CanFrame> rx_;  // guarded by bus_->mu_
  PortCounters counters_{};
  std::string name_;
};

}  // namespace maglev::can
