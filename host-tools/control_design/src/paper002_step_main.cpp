// maglev-paper002-step: paper 002's 7 mm air-gap step (Fig. 4) on the bench
// plant with the reference controller; prints the measured transient.
// Usage: maglev-paper002-step [start_gap_mm step_mm [ideal|quantized [filter_rad_per_s]]]
//   ideal: no encoder quantization; filter: derivative filter bandwidth.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "maglev/control_design/paper002_sim.hpp"

int main(int argc, char** argv) {
  using namespace maglev::control_design;
  GapStepScenario s;
  if (argc >= 3) {
    s.gap_start_m = std::atof(argv[1]) * 1e-3;
    s.gap_step_m = std::atof(argv[2]) * 1e-3;
  }
  if (argc >= 4 && std::strcmp(argv[3], "ideal") == 0) s.quantize_encoders = false;
  const double target = s.gap_start_m + s.gap_step_m;
  if (CheckReference({s.gap_start_m, 0, 0, 0, 0}) != ReferenceError::kOk ||
      CheckReference({target, 0, 0, 0, 0}) != ReferenceError::kOk) {
    std::fprintf(stderr, "invalid gap reference: the gap must stay within 18..31 mm\n");
    return 2;
  }
  Paper002ControllerConfig c = MakePaperConfig();
  if (argc >= 5) c.derivative_filter_rad_per_s = std::atof(argv[4]);
  const GapStepResult r = RunGapStep(s, c);
  std::printf("gap step %.1f -> %.1f mm (%s encoders), derivative filter %.0f rad/s, rotation loops off, 1 kHz\n",
              s.gap_start_m * 1e3, target * 1e3, s.quantize_encoders ? "quantized" : "ideal",
              c.derivative_filter_rad_per_s);
  std::printf("overshoot        %.2f %%   (paper 14.3 %%, spec < 30 %%)\n", 100.0 * r.overshoot_fraction);
  std::printf("t_s (0.1 mm)     %.3f s   (paper < 3 s)\n", r.settling_time_s);
  std::printf("t_enc (10 um)    %.3f s   (paper ~5 s, spec < 10 s)\n", r.encoder_time_s);
  std::printf("peak |i_d|       %.2f A   saturated ticks %d   hit stop %s\n", r.peak_direct_current_A,
              r.saturated_ticks, r.hit_stop ? "yes" : "no");
  std::printf("final |e|        %.2f um\n", r.final_error_m * 1e6);
  return 0;
}
