#include "maglev/pmlsm_plant/amplifier.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace maglev::pmlsm_plant {
namespace {
constexpr double kTwoThirdsPi = 2.0 * std::numbers::pi / 3.0;
}

double ElectricalAngle_rad(const MotorParams& m, double position_m) {
  return std::numbers::pi * position_m / m.pole_pitch_tau_m;
}

PhaseCurrents InverseParkClarke(const DqCurrents& dq, double th) {
  PhaseCurrents p;
  for (int k = 0; k < 3; ++k) {
    const double a = th - kTwoThirdsPi * k;
    p.abc_A[static_cast<std::size_t>(k)] = dq.d_A * std::cos(a) - dq.q_A * std::sin(a);
  }
  return p;
}

DqCurrents ParkClarke(const PhaseCurrents& p, double th) {
  DqCurrents dq;
  for (int k = 0; k < 3; ++k) {
    const double a = th - kTwoThirdsPi * k;
    const double i = p.abc_A[static_cast<std::size_t>(k)];
    dq.d_A += 2.0 / 3.0 * i * std::cos(a);
    dq.q_A -= 2.0 / 3.0 * i * std::sin(a);
  }
  return dq;
}

AmplifierOutput DriveMotor(const AmplifierParams& a, const DqCurrents& command, double th) {
  AmplifierOutput out;
  out.phases = InverseParkClarke(command, th);
  double peak = 0.0;
  for (double i : out.phases.abc_A) peak = std::max(peak, std::abs(i));
  if (peak > a.phase_peak_A) {
    // The star-connected winding forces i_a + i_b + i_c = 0, so an amplifier
    // at its limit scales the whole current vector: direction kept,
    // magnitude cut until the largest phase sits at the limit.
    const double s = a.phase_peak_A / peak;
    for (double& i : out.phases.abc_A) i *= s;
    out.saturated = true;
  }
  out.delivered = ParkClarke(out.phases, th);
  return out;
}

}  // namespace maglev::pmlsm_plant
