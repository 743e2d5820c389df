#include "maglev/virtual_can/virtual_can.hpp"

#include <chrono>
#include <map>

namespace maglev::can {

std::shared_ptr<VirtualBus> VirtualBus::get(const std::string& name) {
  static std::mutex registry_mu;
  static std::map<std::string, std::weak_ptr<VirtualBus>> registry;
  std::lock_guard<std::mutex> lock(registry_mu);
  auto& slot = registry[name];
  if (auto bus = slot.lock()) return bus;
  auto bus = std::make_shared<VirtualBus>(name);
  slot = bus;
  return bus;
}

std::unique_ptr<VirtualCanPort> VirtualBus::open_endpoint(std::size_t rx_queue_depth) {
  auto port = std::make_unique<VirtualCanPort>(shared_from_this(), rx_queue_depth);
  const auto held = lock();
  endpoints_.push_back(port.get());
  return port;
}

void VirtualBus::set_fault_hook(FaultHook hook) {
  const auto held = lock();
  hook_ = std::move(hook);
}

std::uint64_t VirtualBus::frames_sent() const {
  const auto held = lock();
  return seq_;
}

void VirtualBus::detach(VirtualCanPort* p) {
  const auto held = lock();
  std::erase(endpoints_, p);
  std::erase_if(delayed_, [p](const Delayed& d) { return d.sender == p; });
}

void VirtualBus::deliver_locked(VirtualCanPort* sender, const CanFrame& f) {
  for (auto* ep : endpoints_) {
    if (ep == sender) continue;
    if (ep->rx_.size() >= ep->depth_) {
      ++ep->counters_.rx_overruns;
      continue;
    }
    ep->rx_.push_back(f);
  }
}

void VirtualBus::transmit(VirtualCanPort* sender, const CanFrame& f) {
  {
    const auto held = lock();
    const std::uint64_t seq = seq_++;
    FaultAction action = hook_ ? hook_(f, seq) : FaultAction{};
    switch (action.kind) {
      case FaultAction::kDeliver: deliver_locked(sender, f); break;
      case FaultAction::kDrop: break;
      case FaultAction::kCorrupt: {
        CanFrame c = f;
        if (c.len > 0) {
          const std::uint32_t bit = action.corrupt_bit % (8u * c.len);
          c.data[bit / 8u] = static_cast<std::uint8_t>(c.data[bit / 8u] ^ (1u << (bit % 8u)));
        }
        deliver_locked(sender, c);
        break;
      }
      case FaultAction::kDuplicate:
        deliver_locked(sender, f);
        deliver_locked(sender, f);
        break;
      case FaultAction::kDelay: delayed_.push_back({f, sender, seq + action.delay_frames}); break;
    }
    // Release held-back frames whose turn has come (after this frame).
    for (auto it = delayed_.begin(); it != delayed_.end();) {
      if (it->release_at_seq <= seq) {
        deliver_locked(it->sender, it->frame);
        it = delayed_.erase(it);
      } else {
        ++it;
      }
    }
  }
  if (!one_thread_) cv_.notify_all();
}

VirtualCanPort::VirtualCanPort(std::shared_ptr<VirtualBus> bus, std::size_t depth)
    : bus_(std::move(bus)), depth_(depth), name_("virtual:" + bus_->name()) {}

VirtualCanPort::~VirtualCanPort() { bus_->detach(this); }

PortStatus VirtualCanPort::send(const CanFrame& frame) {
  if (!is_valid_fd_len(frame.len) || ((frame.flags & kFlagFd) == 0 && frame.len > 8)) {
    ++counters_.tx_errors;
    return PortStatus::kBadFrame;
  }
  ++counters_.tx_frames;
  bus_->transmit(this, frame);
  return PortStatus::kOk;
}

PortStatus VirtualCanPort::receive(CanFrame& frame, std::uint32_t timeout_us) {
  auto lock = bus_->lock();
  // A zero timeout is a poll: no condition-variable wait at all (a timed
  // futex wait, even an expired one, costs a syscall plus the kernel's 50 us
  // timer slack -- it was most of a lockstep HIL tick's wall time). On a
  // kOneThread bus nobody else can send while this thread waits: a poll too.
  const bool got = (timeout_us == 0 || bus_->one_thread_ || !rx_.empty())
                       ? !rx_.empty()
                       : bus_->cv_.wait_for(lock, std::chrono::microseconds(timeout_us),
                                            [this] { return !rx_.empty(); });
  if (!got) {
    ++counters_.rx_timeouts;
    return PortStatus::kTimeout;
  }
  frame = rx_.front();
  rx_.pop_front();
  ++counters_.rx_frames;
  return PortStatus::kOk;
}

std::size_t VirtualCanPort::pending() const {
  const auto held = bus_->lock();
  return rx_.size();
}

}  // namespace maglev::can
