// kernel::ControllerStatus -> can::ControllerStatusFrame (the catalog's
// controller_status message, 250 Hz). Pose64 (1 pm / 1 prad per LSB) becomes
// nm / nrad rounded to nearest and saturated to int32 (+-2.1 m: never reached);
// currents A -> mA rounded, saturated to int16; k -> k * 1e4 rounded, clamped
// to 0..65535. saturation_flags: the kernel limits the whole current vector
// (one k for all coils), so when it reports `saturated` the coils at the
// largest |i| -- the ones that hit the limit -- get their bit set.
#pragma once

#include "maglev/can_link/codec.hpp"
#include "maglev/controller/controller.hpp"

namespace maglev::app {

can::ControllerStatusFrame to_status_frame(const kernel::ControllerStatus& status);

}  // namespace maglev::app
