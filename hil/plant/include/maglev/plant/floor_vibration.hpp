// Floor vibration: the building's motion under the stage's base, in x, y and
// z (issue 15: what sets a real stage's rest noise beyond its components).
//
// The magnet array, the interferometers and the laser displacement sensors
// are all fixed to one base. The levitated platen touches nothing, so the
// base moving by u(t) is, in the base's frame (the plant's frame: every
// sensor and every field evaluation already lives in it), one extra force on
// the platen's centre of mass: the inertial force -m u''(t). The loops then
// see the floor through their sensitivity function, e = S u, which is why a
// levitated stage is quiet above its bandwidth only relative to the inertial
// frame, not to its own metrology.
//
// The floor's velocity is specified the way facilities are: an rms
// velocity per one-third-octave band (the generic vibration criteria, VC-A ..
// VC-E, and the ISO 2631-2-derived office / workshop curves, Gordon 1991 and
// Amick et al. 2005), flat in velocity from 1 to 80 Hz. A floor "of class C"
// meets the class: every band at most at its level. The model puts every band
// AT the level (the worst floor of that class). Optionally the base stands on
// a passive isolator (an optical table's pneumatic legs): a 1-DOF
// base-excitation transmissibility with natural frequency f0 and damping zeta.
//
// Realization: per axis and band, kLinesPerBand sinusoids at log-uniform
// random frequencies inside the band, random phases, each of velocity
// amplitude v_band |T(f)| sqrt(2 / K): the band's rms is v_band times the
// isolator's rms transmissibility over its lines. Deterministic per seed (its
// own generator: the plant's noise stream is not touched). The acceleration
// is held over each tick at its value at the tick's midpoint.
#pragma once

#include <cstdint>
#include <string_view>

namespace maglev::hil {

// The named floors, one record each: `[plant] floor = NAME` (docs/PLANT.md
// section 12). The band velocity is the criterion's rms velocity in every
// one-third-octave band from 1 to 80 Hz.
struct FloorClass {
  const char* name;
  double band_velocity_m_per_s;
  const char* source;
};
inline constexpr FloorClass kFloorClasses[] = {
    {"none", 0.0, "no floor motion (the default)"},
    {"workshop", 800e-6, "ISO 2631-2 workshop curve, as tabulated with the VC curves (Gordon 1991)"},
    {"office", 400e-6, "ISO 2631-2 office curve, as tabulated with the VC curves (Gordon 1991)"},
    {"residential", 200e-6, "ISO 2631-2 residential (day) curve, as tabulated with the VC curves (Gordon 1991)"},
    {"operating-theatre", 100e-6, "ISO 2631-2 operating theatre curve, as tabulated with the VC curves (Gordon 1991)"},
    {"vc-a", 50e-6, "VC-A (Gordon 1991; IEST-RP-CC012)"},
    {"vc-b", 25e-6, "VC-B (Gordon 1991; IEST-RP-CC012)"},
    {"vc-c", 12.5e-6, "VC-C (Gordon 1991; IEST-RP-CC012)"},
    {"vc-d", 6.25e-6, "VC-D (Gordon 1991; IEST-RP-CC012)"},
    {"vc-e", 3.12e-6, "VC-E (IEST-RP-CC012, 1994)"},
};
inline constexpr int kFloorClassCount = static_cast<int>(sizeof(kFloorClasses) / sizeof(kFloorClasses[0]));
// Index into kFloorClasses, or -1.
int find_floor_class(std::string_view name);
// "none, workshop, ..., vc-e" for messages.
const char* floor_class_names();

struct FloorVibrationConfig {
  // rms velocity per one-third-octave band, 1-80 Hz, each axis (x, y, z)
  // (m/s); 0: no floor motion (the default: every run before it is unchanged).
  double band_velocity_m_per_s = 0.0;
  // The base's isolator: natural frequency (Hz; 0: the base stands rigidly
  // on the floor) and damping ratio.
  double isolator_hz = 0.0;
  double isolator_damping = 0.1;
  // Bounds (the scenario keys are refused outside them).
  static constexpr double kMaxBandVelocity_m_per_s = 2e-3;  // 2.5x the workshop curve
  static constexpr double kMinIsolator_Hz = 0.3, kMaxIsolator_Hz = 20.0;
  static constexpr double kMinIsolatorDamping = 0.01, kMaxIsolatorDamping = 2.0;
  static constexpr const char* kIsolatorRange = "0 (no isolator) or [0.3, 20] Hz";
  static bool isolator_hz_ok(double hz) { return hz == 0.0 || (hz >= kMinIsolator_Hz && hz <= kMaxIsolator_Hz); }
  bool active() const { return band_velocity_m_per_s > 0.0; }
};

class FloorVibration {
 public:
  static constexpr int kAxes = 3;                 // x, y, z
  static constexpr int kBands = 20;               // 10^(n/10) Hz, n = 0..19: 1 .. 79.4 Hz
  static constexpr int kLinesPerBand = 8;
  static constexpr int kLines = kBands * kLinesPerBand;

  FloorVibration() = default;  // no floor motion
  FloorVibration(const FloorVibrationConfig& config, double tick_s, std::uint64_t seed);

  bool active() const { return active_; }
  // The base's acceleration (x, y, z; m/s^2) to hold over the tick of length
  // dt_s that starts now, then one tick on.
  void Next(double dt_s, double acc_m_per_s2[kAxes]);
  // At the midpoint of the next tick (tests): the base's displacement,
  // velocity and acceleration.
  double displacement_m(int axis) const;
  double velocity_m_per_s(int axis) const;
  double acceleration_m_per_s2(int axis) const;
  // The band's rms velocity as realized (lines' sqrt(sum V^2 / 2)).
  double band_rms_velocity_m_per_s(int axis, int band) const;

  static double BandCentre_Hz(int band);
  // |T(f)| of a 1-DOF base-excited isolator; 1 when f0 = 0 (no isolator).
  static double Transmissibility(double f_Hz, double f0_Hz, double zeta);

 private:
  void Rotate(double dt_s);
  bool active_ = false;
  double tick_s_ = 0.0;
  std::uint64_t ticks_ = 0;
  // Per axis and line: angular frequency, velocity amplitude, initial phase
  // (at the first tick's midpoint), and the phasor (cos, sin) of the phase now.
  double omega_[kAxes][kLines] = {}, amplitude_[kAxes][kLines] = {}, phase0_[kAxes][kLines] = {};
  double cos_[kAxes][kLines] = {}, sin_[kAxes][kLines] = {};
  // Rotation by omega * tick_s (the per-tick step).
  double step_cos_[kAxes][kLines] = {}, step_sin_[kAxes][kLines] = {};
  double elapsed_s_ = 0.0;  // time of the phasors since phase0
};

}  // namespace maglev::hil
