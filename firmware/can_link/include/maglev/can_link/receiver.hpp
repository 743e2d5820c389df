// Receive-side E2E state: per catalog message the last accepted counter, and
// per reason the count of rejected frames. One LinkReceiver per node.
#pragma once

#include <array>
#include <cstdint>

#include "maglev/can_link/catalog.hpp"
#include "maglev/can_link/codec.hpp"
#include "maglev/can_port/can_port.hpp"

namespace maglev::can {

struct RxStats {
  std::uint32_t accepted = 0;
  std::uint32_t lost = 0;  // frames missing inside accepted counter jumps
  std::array<std::uint32_t, kRxStatusCount> rejected{};  // index = RxStatus (kOk unused)
  std::uint32_t rejected_total() const {
    std::uint32_t n = 0;
    for (auto r : rejected) n += r;
    return n;
  }
  std::uint32_t count(RxStatus s) const { return rejected[static_cast<std::size_t>(s)]; }
};

class LinkReceiver {
 public:
  // Checks a frame (check_frame) and its counter against the last accepted one
  // of the same message:
  //   delta = (counter - last) mod 256, as int8:
  //   0 -> kRepeated; -max_delta_counter..-1 -> kOutOfOrder (a late
  //   frame, state kept); 1..max_delta_counter -> kOk (delta-1 frames
  //   counted lost); anything else -> kSequenceJump (rejected, but the
  //   receiver resynchronises on it so the next consecutive frame is
  //   accepted). Read as "older", an outage of 128-253 frames used to lock
  //   the receiver out for up to 129 more valid frames (~52 ms at 2.5 kHz).
  // The first frame of a message after construction/reset is accepted.
  // `expected` (optional) restricts the frame to one message kind.
  RxStatus accept(const CanFrame& frame, const Message* expected = nullptr);
  const Message* last_message() const { return last_message_; }

  const RxStats& stats() const { return stats_; }
  void reset();

 private:
  struct CounterState {
    bool valid = false;
    std::uint8_t last = 0;
  };
  std::array<CounterState, kMessageCount> counters_{};
  RxStats stats_{};
  const Message* last_message_ = nullptr;
};

}  // namespace maglev::can
