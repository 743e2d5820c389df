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

// A step on any axis from a base set-point (Fig. 5 is theta from a 25 mm
// gap). Thresholds: 0.1 mm / 10 um on translations, 0.1 mrad / 20 urad on
// rotations (Section IV-A (3), (4)). The result's fields carry the axis's units.
struct AxisStepScenario {
  Axis axis = Axis::kTheta;
  std::array<double, 5> start{25e-3, 0, 0, 0, 0};
  double step = 5e-3;
  double hold_before_s = 1.0;
  double duration_after_s = 10.0;
  bool rotation_loops_enabled = true;
  bool quantize_encoders = true;
};
GapStepResult RunAxisStep(const AxisStepScenario& s, const Paper002ControllerConfig& c);

// Sinusoidal tracking of Section IV-B at omega_0 = 1.5 pi rad/s:
//   x1 = 5 mm sin(w t - pi/2) + 25 mm, x3 = 30 mm sin(w t - pi/2), x5 = 30 mm sin(w t)
// (the 3-DOF ellipse, Fig. 6), plus x9 = 10 mrad sin(w t) with the rotation
// loops on in the 4-DOF run (Figs. 7, 8; the paper's second "x7" is x5).
struct TrackingScenario {
  bool four_dof = false;
  double settle_s = 10.0;   // transient left out of the average
  double measure_s = 60.0;  // the paper averages over 60 s
  bool quantize_encoders = true;
};
struct TrackingResult {
  std::array<double, 5> mean_abs_error{};  // y order: x1, x3, x5 [m], x7, x9 [rad]
  bool hit_stop = false;
};
TrackingResult RunTracking(const TrackingScenario& s, const Paper002ControllerConfig& c);

}  // namespace maglev::control_design
