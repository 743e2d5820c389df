// Paper 002's stage on the bench: the firmware's PmlsmController
// (firmware/kernel/pmlsm_stage) in lockstep with the pmlsm_plant physics,
// in process (encoder counts in, DAC codes out; the CAN link carries the
// Halbach family's frames only). `maglev-hil suite|run --profile
// fmp2009-pmlsm` and `maglev-hil record-pmlsm` land here (docs/PAPER-002.md).
#pragma once

#include <array>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "maglev/control_design/pmlsm_kernel_config.hpp"
#include "maglev/pmlsm_plant/plant.hpp"
#include "maglev/pmlsm_stage/pmlsm_controller.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::bench::pmlsm {

// What an experiment changes from the profile.
struct Variant {
  bool rotation_loops = true;        // false: phi, theta open (the paper's 3-DOF tests)
  bool antiwindup = true;            // false: E = 0 on X and Z
  bool exact_vertical_inverse = false;  // ours: (2) with its i_d^2 term
  double servo_rate_Hz = 0.0;        // 0: the profile's
  double encoder_scale = 1.0;        // resolution multiplier (ours: 0.1 = 1 um / 2 urad)
};

class PmlsmBench {
 public:
  bool Init(const stage_profile::StageProfile& profile, const Variant& v, std::string* why);
  pmlsm_stage::CommandResult Command(const pmlsm_stage::MotionCommand& c);
  void Tick();
  // Ticks until the kernel's reference ramps and sinusoids stop or `max_s` passes.
  void RunFor(double seconds);

  double t_s() const { return static_cast<double>(tick_) * period_s_; }
  double period_s() const { return period_s_; }
  const pmlsm_plant::State& state() const { return plant_->state(); }
  // True pose in the kernel's axis order (gap, X, Z, phi, theta).
  std::array<double, 5> pose() const;
  const pmlsm_stage::PmlsmStatus& status() const { return ctl_.status(); }
  const pmlsm_stage::PmlsmKernelConfig& config() const { return design_.config; }
  const control_design::PmlsmDesign& design() const { return design_; }
  const control_design::PmlsmStage& stage() const { return stage_; }
  double peak_phase_current_A() const { return peak_phase_A_; }
  long amplifier_clamp_ticks() const { return clamp_ticks_; }
  // Downward speed (m/s) of the platen the last time the gap reached the rest stop.
  double touchdown_speed_m_per_s() const { return touchdown_speed_; }

  // Simulated seconds of every bench in this process (the suite's real-time factor).
  static double total_simulated_s();

  // Replay vectors: every tick's command (if any) and sample, and the kernel's outputs.
  void StartRecording(std::vector<unsigned char>* inputs, std::vector<unsigned char>* outputs);
  // Trace: one CSV row every `every` ticks.
  void StartTrace(std::FILE* f, int every);

 private:
  control_design::PmlsmStage stage_{};
  control_design::PmlsmDesign design_{};
  std::unique_ptr<pmlsm_plant::Plant> plant_;
  pmlsm_stage::PmlsmController ctl_;
  double period_s_ = 1e-3;
  long tick_ = 0;
  double peak_phase_A_ = 0.0;
  long clamp_ticks_ = 0;
  double touchdown_speed_ = 0.0;
  bool has_pending_ = false;
  pmlsm_stage::MotionCommand pending_{};
  std::uint8_t pending_result_ = 255;
  std::vector<unsigned char>* rec_in_ = nullptr;
  std::vector<unsigned char>* rec_out_ = nullptr;
  std::FILE* trace_ = nullptr;
  int trace_every_ = 1;
};

// `maglev-hil suite --profile P` (only empty) or `maglev-hil run NAME
// --profile P` for a profile of the iron_core_pmlsm family. Writes
// OUT/<experiment>/{trace.csv,metrics.json} and OUT/verdicts.json; prints
// the verdict table. 0: every experiment ran and every verdict holds.
int suite_main(const stage_profile::StageProfile& profile, const std::string& out_dir, const std::string& only);
// The experiments' names and titles (`maglev-hil list --profile P`).
void list_experiments();
// `maglev-hil record-pmlsm VECTORS OUTPUTS [--profile P]`: a closed-loop
// session (lift-off, steps on every axis, a 4-DOF sinusoid, landing) for
// the bit-exact M7 replay.
int record_main(const stage_profile::StageProfile& profile, const std::string& vectors, const std::string& outputs);
// `maglev-hil check-profile` for this family: the design's poles.
int check_profile_main(const stage_profile::StageProfile& profile);

}  // namespace maglev::bench::pmlsm
