#include "maglev/can_link/receiver.hpp"

namespace maglev::can {

RxStatus LinkReceiver::accept(const CanFrame& frame, const Message* expected) {
  const Message* m = nullptr;
  RxStatus status = check_frame(frame, expected, &m);
  last_message_ = nullptr;
  if (status == RxStatus::kOk) {
    auto& st = counters_[static_cast<std::size_t>(m - kCatalog.data())];
    const std::uint8_t counter = frame_counter(frame);
    if (!st.valid) {
      st.valid = true;
      st.last = counter;
    } else {
      const auto delta = static_cast<std::int8_t>(static_cast<std::uint8_t>(counter - st.last));
      if (delta == 0) {
        status = RxStatus::kRepeated;
      } else if (delta < 0 && delta >= -static_cast<int>(m->max_delta_counter)) {
        status = RxStatus::kOutOfOrder;
      } else if (delta < 0 || delta > m->max_delta_counter) {
        status = RxStatus::kSequenceJump;
        st.last = counter;  // resync: the next consecutive frame is accepted
      } else {
        stats_.lost += static_cast<std::uint32_t>(delta - 1);
        st.last = counter;
      }
    }
  }
  if (status == RxStatus::kOk) {
    ++stats_.accepted;
    last_message_ = m;
  } else {
    ++stats_.rejected[static_cast<std::size_t>(status)];
  }
  return status;
}

void LinkReceiver::reset() {
  counters_ = {};
  stats_ = {};
  last_message_ = nullptr;
}

}  // namespace maglev::can
