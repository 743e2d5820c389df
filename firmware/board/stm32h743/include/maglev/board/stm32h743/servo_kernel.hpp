// The kernel the board's servo interrupt runs: maglev::kernel::Controller<float>
// (firmware/kernel/controller). float, not Q7.24: the M7 has a
// double-precision FPU and the kernel's float32 path is the reference one.
#pragma once

#include "maglev/controller/controller.hpp"

namespace maglev::board::stm32h743 {
using ServoKernel = kernel::Controller<float>;
}
