#include "maglev/bench/profile_check.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>

#include "maglev/bench/axes.hpp"
#include "maglev/bench/overrides.hpp"
#include "maglev/bench/selfstab_suite.hpp"
#include "maglev/control_design/pmlsm_kernel_config.hpp"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/plant/plant_profile.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/modbus/controller_binding.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

namespace maglev::bench {

namespace sp = stage_profile;

namespace {

const char* mode_name(sp::AxisMode m) {
  switch (m) {
    case sp::AxisMode::kActive: return "active";
    case sp::AxisMode::kPassive: return "passive";
    case sp::AxisMode::kAbsent: return "absent";
  }
  return "?";
}

// Largest coil current over a grid of positions across one pitch, for an
// effort vector, through the kernel's own allocation and commutation.
double peak_coil_current(const kernel::KernelConfig& kc, const float effort[kAxes]) {
  kernel::ForceAllocationState<float> st{};
  if (kernel::ApplyForceAllocationConfig<float>(kc.allocation, &st) != kernel::ForceAllocationError::kOk) return -1.0;
  return kernel::PeakCoilCurrent_A(effort, st, kc.allocation.pitch_m, 16);
}

}  // namespace

int list_profiles_main() {
  const auto names = profile::list_profiles(profile_dir());
  if (names.empty()) {
    std::fprintf(stderr, "maglev-hil: no .profile files in %s\n", profile_dir().c_str());
    return 1;
  }
  int bad = 0;
  for (const auto& n : names) {
    const profile::ProfileParse p = profile::find_profile(n, profile_dir());
    if (!p.ok()) {
      std::printf("  %-20s (errors: %s)\n", n.c_str(), p.errors.front().c_str());
      ++bad;
      continue;
    }
    if (p.profile.family == sp::ActuatorFamily::kIronCorePmlsm) {
      // Paper 002's family runs on its own kernel (firmware/kernel/pmlsm_stage).
      control_design::PmlsmDesign d;
      std::string why;
      std::printf("  %-20s %-9s %s\n", n.c_str(),
                  control_design::BuildPmlsmKernelConfig(p.profile, &d, &why) ? "runs" : "REFUSED", p.profile.title);
      continue;
    }
    kernel::KernelConfig kc{};
    bool runs = sp::MakeKernelConfig(p.profile, &kc).error == sp::ProfileError::kOk;
    // Paper 001's family runs on its own kernel (selfstab_suite.hpp).
    if (p.profile.family == sp::ActuatorFamily::kSolenoidMagnet) runs = selfstab_accepts(p.profile);
    std::printf("  %-20s %-9s %s\n", n.c_str(), runs ? "runs" : "REFUSED", p.profile.title);
  }
  return bad == 0 ? 0 : 1;
}

std::string register_range_refusal(const kernel::KernelConfig& kc) {
  const modbus::RegisterDef* d = modbus::FirstRegisterOutOfRange(kc);
  if (d == nullptr) return {};
  double v = 0.0;
  (void)modbus::get_config_field(kc, d->id, &v);
  char text[200];
  std::snprintf(text, sizeof text, "%s (%s is %g, outside the register's range %g..%g)",
                stage_profile::to_string(stage_profile::ProfileError::kRegisterRange), d->name, v, d->min, d->max);
  return text;
}

int check_profile_main(const std::string& name_or_path) {
  const profile::ProfileParse parsed = profile::find_profile(name_or_path, profile_dir());
  if (!parsed.ok()) {
    for (const auto& e : parsed.errors) std::fprintf(stderr, "%s\n", e.c_str());
    return 2;
  }
  const sp::StageProfile& p = parsed.profile;
  std::printf("profile %s: %s\n", p.name, p.title);
  const sp::ProfileCheck check = sp::CheckStageProfile(p);

  // 1. Allocation on the active axes.
  std::printf("  allocation (active axes): rank %d, condition number %.4g\n", check.allocation_rank,
              check.allocation_condition);
  // 2. Passive axes: eigenvalues of y'' + c y' + k y = 0.
  bool any_passive = false;
  for (Axis a : kDisplayOrder) {
    const sp::Axis& ax = p.axis[index(a)];
    if (ax.mode != sp::AxisMode::kPassive) continue;
    any_passive = true;
    const std::complex<double> disc = std::sqrt(std::complex<double>(
        ax.open_loop_damping_per_s * ax.open_loop_damping_per_s - 4.0 * ax.open_loop_stiffness_per_s2, 0.0));
    const std::complex<double> l1 = (-ax.open_loop_damping_per_s + disc) / 2.0;
    const std::complex<double> l2 = (-ax.open_loop_damping_per_s - disc) / 2.0;
    const bool stable = l1.real() < 0.0 && l2.real() < 0.0;
    const double wn = std::sqrt(std::fabs(ax.open_loop_stiffness_per_s2));
    std::printf("  passive %-8s eigenvalues %.4g%+.4gi, %.4g%+.4gi  (f_n %.4g Hz, zeta %.4g): %s\n", axis_name(a),
                l1.real(), l1.imag(), l2.real(), l2.imag(), wn / (2.0 * 3.14159265358979323846),
                wn > 0 ? ax.open_loop_damping_per_s / (2.0 * wn) : 0.0, stable ? "passively stable" : "UNSTABLE");
  }
  if (!any_passive) std::printf("  passive axes: none (every degree of freedom is closed-loop)\n");
  // 3. Loops with the profile's gains.
  for (Axis a : kDisplayOrder) {
    const sp::Axis& ax = p.axis[index(a)];
    if (ax.mode != sp::AxisMode::kActive) {
      std::printf("  loop %-8s %s\n", axis_name(a), mode_name(ax.mode));
      continue;
    }
    const sp::LoopMargins lm = sp::AxisLoopMargins(p, index(a));
    if (lm.crossover_found) {
      std::printf("  loop %-8s crossover %7.2f Hz, phase margin %6.1f deg\n", axis_name(a), lm.crossover_Hz,
                  lm.phase_margin_deg);
    } else {
      std::printf("  loop %-8s no crossover below the Nyquist rate\n", axis_name(a));
    }
  }
  // 4. Current headroom: gravity alone, then gravity + the largest
  // acceleration the profile allows on each axis.
  kernel::KernelConfig kc{};
  const sp::ProfileCheck made = sp::MakeKernelConfig(p, &kc);
  if (made.error == sp::ProfileError::kOk) {
    float effort[kAxes] = {};
    effort[index(Axis::kZ)] = static_cast<float>(p.body.mass_kg * p.body.gravity_m_per_s2 / p.halbach.two_b_star_N_per_A);
    const double gravity_A = peak_coil_current(kc, effort);
    std::printf("  current: gravity alone needs %.3f A peak per coil of %.3f A (headroom %.3f A)\n", gravity_A,
                p.limits.peak_current_A, p.limits.peak_current_A - gravity_A);
    for (Axis a : kDisplayOrder) {
      if (a == Axis::kZ || p.axis[index(a)].mode != sp::AxisMode::kActive) continue;
      float e[kAxes] = {};
      e[index(Axis::kZ)] = effort[index(Axis::kZ)];
      e[index(a)] = static_cast<float>(p.axis[index(a)].max_acceleration / sp::AxisPlantGain(p, index(a)));
      const double need = peak_coil_current(kc, e);
      std::printf("  current: gravity + max acceleration on %-8s %.3f A (headroom %.3f A)%s\n", axis_name(a), need,
                  p.limits.peak_current_A - need, need > p.limits.peak_current_A ? "  BEYOND THE LIMIT" : "");
    }
  }
  // 5. The Hall sensors' swing at rest (homing), as the check judges it.
  if (p.family == sp::ActuatorFamily::kHalbachLorentz) {
    for (int i = 0; i < p.sensor_count && i < sp::kMaxSensors; ++i) {
      if (p.sensors[i].kind != sp::SensorKind::kHall) continue;
      const sp::HallSwing w = sp::HallSignalSwing(p, p.sensors[i]);
      const bool ok = w.peak_fraction <= sp::kHallMaxPeakFraction && w.amplitude_fraction >= sp::kHallMinAmplitudeFraction;
      std::printf("  hall sensor %d: B_1 %.4f T at %.4g mm x %.4g V/T: peak %.3f V = %.1f %% of full scale "
                  "(admitted <= %.0f %%), amplitude %.1f %% (admitted >= %.0f %%)%s\n",
                  i + 1, w.fundamental_T, w.height_m * 1e3, w.sensitivity_V_per_T, w.peak_V, 100.0 * w.peak_fraction,
                  100.0 * sp::kHallMaxPeakFraction, 100.0 * w.amplitude_fraction, 100.0 * sp::kHallMinAmplitudeFraction,
                  ok ? "" : w.peak_fraction > sp::kHallMaxPeakFraction
                                ? "  RAILS THE ADC: lower sensitivity_V_per_T or raise height_m"
                                : "  TOO WEAK: raise sensitivity_V_per_T or lower height_m");
    }
  }
  // 5b. The counters' and heights' scales (one interpolator, one ADC scale).
  if (p.family == sp::ActuatorFamily::kHalbachLorentz) {
    for (int i = 0; i < p.sensor_count && i < sp::kMaxSensors; ++i) {
      const sp::Sensor& s = p.sensors[i];
      if (s.kind == sp::SensorKind::kInterferometer) {
        const int n = sp::InterferometerInterpolation(s.resolution);
        if (s.resolution == 0.0) {
          std::printf("  interferometer %d: resolution not given: the family's %.5g m per count\n", i + 1,
                      io::stage::kInterferometerLsb_m);
        } else if (n == 0) {
          std::printf("  interferometer %d: resolution %.5g m per count is no wavelength / (%d x N) within %.1f %%: "
                      "NOT SUPPORTED\n",
                      i + 1, s.resolution, io::stage::kInterferometerFold, 100.0 * sp::kResolutionRounding);
        } else {
          std::printf("  interferometer %d: resolution %.5g m per count = wavelength / (%d x %d) = %.6g m\n", i + 1,
                      s.resolution, io::stage::kInterferometerFold, n,
                      io::stage::kWavelength_m / (io::stage::kInterferometerFold * n));
        }
      } else if (s.kind == sp::SensorKind::kLaserDisplacement) {
        std::printf("  laser displacement %d: %.5g m per V (%s)\n", i + 1,
                    s.resolution != 0.0 ? s.resolution : io::stage::kDisplacementScale_m_per_V,
                    s.resolution != 0.0 ? "the profile's" : "the family's");
      }
    }
  }
  // 6. Verdict, and whether the bench can build its plant.
  if (p.family == sp::ActuatorFamily::kSolenoidMagnet) return selfstab_check_profile(p);
  if (check.error != sp::ProfileError::kOk) {
    std::printf("  controller: REFUSES this profile: %s%s%s\n", sp::to_string(check.error),
                check.axis >= 0 ? " on axis " : "", check.axis >= 0 ? axis_name(static_cast<Axis>(check.axis)) : "");
    return 1;
  }
  if (const std::string refusal = made.error == sp::ProfileError::kOk ? register_range_refusal(kc) : std::string();
      !refusal.empty()) {
    std::printf("  controller: REFUSES this profile: %s\n", refusal.c_str());
    return 1;
  }
  hil::PlantConfig plant{};
  std::string why;
  if (!hil::PlantConfigForProfile(p, hil::PlantConfig::Default(), &plant, &why)) {
    std::printf("  controller: accepts this profile\n  bench: cannot build its plant yet: %s\n", why.c_str());
    return 1;
  }
  std::printf("  controller: accepts this profile; bench: plant built from it\n");
  return 0;
}

bool in_suite(const scenario::Scenario& sc, const std::string& profile) {
  const auto it = sc.scenario.find("profile");
  if (it != sc.scenario.end()) return it->second == profile;
  const profile::ProfileParse mine = profile::find_profile(profile, profile_dir());
  const profile::ProfileParse dflt = profile::find_profile(kDefaultProfile, profile_dir());
  return mine.ok() && dflt.ok() && mine.profile.family == dflt.profile.family;
}

}  // namespace maglev::bench
