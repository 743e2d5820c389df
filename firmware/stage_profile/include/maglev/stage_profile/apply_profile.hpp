// A stage profile -> the kernel's configuration, and the boot-time check that
// the profile can run on this controller. Heap-free; host and Cortex-M7.
#pragma once

#include "maglev/axis_loops/loop_check.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/stage_profile/stage_profile.hpp"

namespace maglev::stage_profile {

struct ProfileCheck {
  ProfileError error = ProfileError::kOk;
  std::int8_t axis = -1;  // the axis concerned (kernel::Axis index), -1 none
  // Allocation on the active axes (singular values of A restricted to them).
  int allocation_rank = 0;
  double allocation_condition = 0.0;
};

// The loop check (kernel axis_loops/loop_check.hpp) of one active axis with
// the profile's gains and the axis plant g / (s^2 + c s + k), g = 2 b* /
// (mass or inertia).
using kernel::LoopMargins;
LoopMargins AxisLoopMargins(const StageProfile& p, int axis);
// y'' + c y' + k y: plant gain per A of effort (m/s^2 or rad/s^2 per A).
double AxisPlantGain(const StageProfile& p, int axis);

// A Hall sensor's swing on its ADC channel, with the platen at rest (where
// the field is strongest). The array's fundamental at the sensor's height
// follows from the profile's 2 b* and coil geometry (paper 000 eqs (3), (19):
// 2 b*(gap) = 4 N L S_1 c_1 M_0 e^{-gamma_1 gap}, S_1 the coil side's
// averaging factor, so B_1(h) = 2 b* e^{-gamma_1 (h - gap)} / (4 N L S_1));
// the 5th and 9th harmonics add (1/n)(1 - e^{-n gamma_1 t})/(1 -
// e^{-gamma_1 t}) e^{-(n-1) gamma_1 h} of it each (HalbachHarmonicRatio).
struct HallSwing {
  double height_m;             // above the magnets, at rest (the profile's, or the family's)
  double sensitivity_V_per_T;  // the profile's, or the family's
  double fundamental_T;        // B_1 at that height
  double peak_V;               // sensitivity x (B_1 + B_5 + B_9): harmonics in phase, the worst case
  double amplitude_fraction;   // sensitivity x B_1 / full scale: the Hall solve's amplitude
  double peak_fraction;        // peak_V / full scale
};
HallSwing HallSignalSwing(const StageProfile& p, const Sensor& hall);
// What CheckStageProfile admits (kHallSignalRange): the peak at most 97 % of
// full scale -- 3 % left before the ADC rails for 3 sigma of the magnets' 1 %
// remanence spread -- and the amplitude at least 20 %, twice the pose
// solver's 10 % floor below which it takes a sensor for detached.
inline constexpr double kHallMaxPeakFraction = 0.97;
inline constexpr double kHallMinAmplitudeFraction = 0.20;
// How far Hall B may sit from a quarter pitch beyond Hall A (x and y): the
// Hall solve takes the two as a quadrature pair; 10 um is 0.07 deg of phase.
inline constexpr double kHallQuadratureTolerance_m = 10e-6;

// An interferometer's `resolution` (m per count) is the family's wavelength /
// (fold x N) for a whole interpolation N: the profile's figure may be rounded
// (the seed's 0.618e-9 for 632.991 nm / 1024 = 0.61815e-9) by this much
// relative. N = InterferometerInterpolation(resolution) (0 when none fits:
// kUnsupportedSensors). A resolution of 0 keeps the family's counter.
inline constexpr double kResolutionRounding = 1e-3;
int InterferometerInterpolation(double resolution_m);

// Validates the profile against this firmware (family, controllers, sensors
// per active axis, allocation rank and condition, limits inside the
// hardware, start-up sequence). Nothing is applied.
ProfileCheck CheckStageProfile(const StageProfile& p);

// The kernel configuration for the profile: the family's baseline
// (default_kernel_config()) with every field the profile describes set from
// it. For the default profile (nk2017-cross) the result equals
// default_kernel_config() field for field. Runs CheckStageProfile first; on
// an error *out is untouched.
ProfileCheck MakeKernelConfig(const StageProfile& p, kernel::KernelConfig* out);

// The sensor geometry of the profile into a pose solver configuration (the
// part of MakeKernelConfig that places the sensors, unchecked): its sensors
// in order of kind -- interferometers -> the three beams (axis, perpendicular
// offset, counting sign), laser displacement sensors -> the three heights,
// the first Hall sensor -> Hall A -- and the pitch; and their scales: the
// interferometers' interpolation from their resolution, the laser
// displacement sensors' m per V (both only when given, else the family's).
// The bench's plant places and scales its sensors from the same call, so the
// two cannot disagree.
void SetSensorGeometry(const StageProfile& p, kernel::SensorsToPoseConfig* m);

}  // namespace maglev::stage_profile
