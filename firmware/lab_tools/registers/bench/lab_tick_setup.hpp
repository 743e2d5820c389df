// The lab tools' tick-cost scenario, shared by lab-tick-bench (host,
// callgrind) and maglev-qemu-lab-tick (QEMU Cortex-M7, -icount): a recorder
// armed with 8 channels and a level trigger that never fires (its heaviest
// steady tick) and three generators (28-tone multisine, sine, log sweep).
#pragma once

#include "maglev/lab_tools/recorder.hpp"
#include "maglev/lab_tools/wave_generator.hpp"

namespace maglev::lab {

inline bool setup_lab_tick_scenario(Recorder& recorder, WaveGenerator& multisine, WaveGenerator& sine,
                                    WaveGenerator& sweep) {
  RecorderConfig c{};
  c.channel_count = 8;
  const char* names[8] = {"x.pose", "x.reference", "x.error", "x.effort", "coil1.current", "coil1.current_cmd", "state", "fault"};
  for (int i = 0; i < 8; ++i) c.channel[i] = find_signal(names[i]);
  c.length = 16384;
  c.pretrigger = 1000;
  c.mode = TriggerMode::kLevel;
  c.trigger_signal = find_signal("z.pose");
  c.level = 1.0f;  // never reached: the armed steady state
  if (recorder.configure(c) != RecorderError::kOk || recorder.arm() != RecorderError::kOk) return false;
  const kernel::KernelConfig k = kernel::default_kernel_config();
  WaveConfig w = LoopResponseMultisine();
  if (multisine.start(w, k) != WaveError::kOk) return false;
  w.shape = WaveShape::kSine;
  if (sine.start(w, k) != WaveError::kOk) return false;
  w.shape = WaveShape::kSweep;
  w.duration_s = 600.0f;
  return sweep.start(w, k) == WaveError::kOk;
}

}  // namespace maglev::lab
