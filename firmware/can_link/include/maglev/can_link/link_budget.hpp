// The servo rate the CAN FD link can carry (docs/CAN.md "Bus budget"): every
// periodic catalog frame's bus time (bus_load.hpp, worst-case stuffing, the
// configured bit rates) per servo tick; the load grows in proportion to the
// servo rate because the catalog's periods are in ticks. Used by the DBC/doc
// generator and by the two-process bench, which refuses a rate above it.
#pragma once

#include "maglev/can_link/bus_load.hpp"
#include "maglev/can_link/catalog.hpp"

namespace maglev::can {

// Share of the bus the periodic frames may take: the rest is for sporadic
// host commands and acks, error frames and retransmissions.
inline constexpr double kLinkUsableFraction = 0.8;

// Bus time of the periodic frames per servo tick, in ns (both directions:
// sensor, current_monitor, heartbeat_plant from the plant; actuator, status,
// sync, heartbeat_controller from the controller).
constexpr double periodic_ns_per_tick(BusTiming t = {}) {
  double ns = 0.0;
  for (const auto& m : kCatalog) {
    if (m.period_ticks == 0) continue;  // sporadic
    ns += static_cast<double>(frame_time_ns(can_frame_bits(m.length, true, true), t)) /
          static_cast<double>(m.period_ticks);
  }
  return ns;
}

// The highest servo rate (Hz, not rounded) at which the periodic frames take
// `usable` of the bus.
constexpr double max_servo_rate_Hz(double usable = kLinkUsableFraction, BusTiming t = {}) {
  return usable * 1e9 / periodic_ns_per_tick(t);
}

// docs/CAN.md's figures (1 Mbit/s nominal, 5 Mbit/s data): full at 4472 Hz,
// 80 % at 3578 Hz. 5 kHz and above cannot run over this link.
static_assert(max_servo_rate_Hz(1.0) > 4472.0 && max_servo_rate_Hz(1.0) < 4473.0);
static_assert(max_servo_rate_Hz() > 3578.0 && max_servo_rate_Hz() < 3579.0);

}  // namespace maglev::can
