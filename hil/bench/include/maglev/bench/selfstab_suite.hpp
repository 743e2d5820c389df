// The bench of the solenoid_magnet family (paper 001, profile
// jb2002-selfstab): the selfstab kernel in lockstep with hil/selfstab_plant,
// in process (PSD ADC codes in, DAC codes out, no CAN), and the paper's
// experiments with a verdict each (docs/PAPER-001.md).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "maglev/selfstab_plant/params.hpp"
#include "maglev/selfstab_plant/plant.hpp"
#include "maglev/selfstab_stage/selfstab_stage.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::bench {

// True when `profile` (name or file) is a solenoid_magnet stage: then the
// command (run SCENARIO / suite) ran on this bench and *rc is its exit status.
bool selfstab_dispatch(const std::string& cmd, const std::vector<std::string>& positional,
                       const std::string& profile, const std::string& out_dir, int* rc);

// The bench plant for a profile: BenchParams() (Table 2 coils, the fits) with
// every value the profile carries (body, r1, r2, L, magnet, nominal currents,
// turns, R, PSD placement and resolution) taken from the profile.
selfstab_plant::StageParams SelfstabPlantParams(const stage_profile::StageProfile& p);

// check-profile / profiles for this family: whether the selfstab kernel
// takes the profile (MakeSelfstabKernelConfig), and the printout (its
// verdict, the z loop's margins over the schedule's range); 0 = accepted.
bool selfstab_accepts(const stage_profile::StageProfile& p);
int selfstab_check_profile(const stage_profile::StageProfile& p);

// The bench's I/O: the PSD spots as the A/D's codes (signed, 0 = centre,
// rounded, clamped to int16) and the amplifiers: each holds the voltage
// R i_cmd (voltage drive, so the back-emf damping of (9) acts; ours), 0 V
// when disabled.
selfstab::SelfstabSensorSample SelfstabSampleFromPsd(const selfstab_plant::PsdReading& y, double lsb_m);
selfstab_plant::CoilVector SelfstabAmplifierVoltages(const selfstab::SelfstabCoilCommand& cmd, float dac_A_per_code,
                                                     double R_ohm);

// The z axis of the plant linearized at height z0 (pose otherwise 0, the
// A, B, C currents raised to hold it there): z'' + c z' + k z = g u, u the
// effort (A added to each of A, B, C).
struct SelfstabAxisModel {
  double gain, stiffness_per_s2, damping_per_s, hold_current_A;
};
SelfstabAxisModel LinearizeZAt(const selfstab_plant::StageParams& p, double z0_m);

// The z gain schedule from the plant (at, kp_scale, kd_scale): at each
// height z the scales that give the kernel's z loop (base gains of k, its
// filter, hold and the coils' lag) around the plant linearized at z the same
// response at the nominal crossover as at z = 0 -- magnitude and phase, so
// the crossover and the phase margin stay the nominal ones at the points.
std::vector<std::array<double, 3>> SelfstabZSchedule(const selfstab::SelfstabKernelConfig& k,
                                                     const selfstab_plant::StageParams& p,
                                                     const std::vector<double>& at_m);

// Crossover and phase margin of the kernel's z loop (its exact discrete PID
// with the scales at z0, its feedback filter, the half-tick hold and the
// coils' L/R lag) around the plant linearized at z0.
struct SelfstabMargins {
  bool crossover_found;
  double crossover_Hz, phase_margin_deg;
};
SelfstabMargins ZLoopMargins(const selfstab::SelfstabKernelConfig& k, const selfstab_plant::StageParams& p,
                             double z0_m, bool scheduled);

struct SelfstabVerdict {
  std::string experiment, quantity;
  double value, reference, ratio, lo, hi;  // pass: lo <= ratio <= hi
  bool pass;
  std::string note;
};
struct SelfstabSuiteResult {
  std::vector<SelfstabVerdict> verdicts;
  std::map<std::string, double> metrics;
  bool all_pass() const;
};
// Experiments: free_vibration, z_step_10um, z_step_100um, lift_off,
// schedule_margins, filter_cost, ours. out_dir empty: no files.
std::vector<std::string> SelfstabExperiments();
bool RunSelfstabExperiment(const std::string& name, const stage_profile::StageProfile& p, const std::string& out_dir,
                           SelfstabSuiteResult* result);
void PrintSelfstabVerdicts(const SelfstabSuiteResult& r);

}  // namespace maglev::bench
