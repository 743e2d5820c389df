#pragma once
// Host closed-loop simulation of paper 002's air-gap step (Fig. 4): the
// pmlsm_plant bench model + the reference controller at 1 kHz, in double.
#include "maglev/control_design/paper002_controller.hpp"

namespace maglev::control_design {

struct GapStepScenario {
  double gap_start_m = 20e-3;
  double gap_step_m = 7e-3;        // Fig. 4's large step
  double hold_before_s = 1.0;      // regulate at the start gap first
  double duration_after_s = 10.0;
  bool rotation_loops_enabled = false;  // as in the paper's 3-DOF test
  bool quantize_encoders = true;
  double rk4_substeps = 1.0;       // plant RK4 steps per servo period
};

struct GapStepResult {
  double overshoot_fraction = 0.0;  // (peak - final ref) / step
  double settling_time_s = 0.0;     // |e| goes and stays below 0.1 mm
  double encoder_time_s = 0.0;      // |e| goes and stays below 10 um
  double peak_direct_current_A = 0.0;  // max |i_d| delivered to any motor
  int saturated_ticks = 0;          // ticks with a phase at the 7 A clamp
  double final_error_m = 0.0;       // |e| at the end
  bool hit_stop = false;            // the gap reached a mechanical stop
};

GapStepResult RunGapStep(const GapStepScenario& s, const Paper002ControllerConfig& c);

}  // namespace maglev::control_design
