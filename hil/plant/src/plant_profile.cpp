#include "maglev/plant/plant_profile.hpp"

#include <algorithm>
#include <cmath>

namespace maglev::hil {

void ApplyServoRate(double servo_rate_Hz, PlantConfig* c) {
  c->integration.servo_rate_Hz = servo_rate_Hz;
  // Issue 16 (2.5 to 20 kHz): substeps_per_tick keeps a sub-step at most
  // kMaxSubstep_s (2 at 2.5 kHz as before, 1 at 5, 10, 20 kHz; kFast uses it
  // near the landing surface, kClassic always), and the current noise's band
  // is the per-tick sampling's Nyquist band, so its density (the identified
  // figure) holds at every rate.
  const double tick_s = 1.0 / servo_rate_Hz;
  c->integration.substeps_per_tick = std::max(1, static_cast<int>(std::ceil(tick_s / kMaxSubstep_s - 1e-9)));
  c->amplifier.current_noise_bandwidth_Hz = 0.5 * servo_rate_Hz;
}

bool PlantConfigForProfile(const stage_profile::StageProfile& p, const PlantConfig& base, PlantConfig* out,
                           std::string* why) {
  namespace sp = stage_profile;
  if (p.family != sp::ActuatorFamily::kHalbachLorentz) {
    *why = "the bench plant models the halbach_lorentz family only (profile family not built yet)";
    return false;
  }
  PlantConfig c = base;
  switch (p.halbach.layout) {
    case sp::ForcerLayout::kCross: c.body.layout = BodyConfig::Layout::kCross; break;
    case sp::ForcerLayout::kSquare: c.body.layout = BodyConfig::Layout::kSquare; break;
    case sp::ForcerLayout::kTriangle:
      c.body.layout = BodyConfig::Layout::kTriangle;
      c.body.triangle_alpha_rad = p.halbach.triangle_alpha_rad;
      break;
    default:
      *why = "the bench plant models the cross, square and triangle layouts; a custom layout's actuators are not "
             "built yet";
      return false;
  }
  c.body.mass_kg = p.body.mass_kg;
  for (int i = 0; i < 3; ++i) c.body.inertia_kgm2[i] = p.body.inertia_kgm2[i];
  c.body.lever_arm_m = p.halbach.lever_arm_m;
  c.body.gravity_m_per_s2 = p.body.gravity_m_per_s2;
  c.field.pitch_m = p.halbach.pitch_m;
  c.field.magnet_thickness_m = p.halbach.magnet_thickness_m;
  c.field.coil_effective_length_m = p.halbach.coil_effective_length_m;
  c.field.coil_side_width_m = p.halbach.coil_side_width_m;
  c.field.coil_thickness_m = p.halbach.coil_thickness_m;
  c.field.coil_turns = p.halbach.coil_turns;
  c.field.rest_gap_m = p.halbach.rest_gap_m;
  c.field.two_b_star_N_per_A = p.halbach.two_b_star_N_per_A;
  c.amplifier.current_limit_A = p.limits.hardware_current_A;
  // The sensors where the profile puts them: the kernel's pose solver reads
  // them from the profile (MakeKernelConfig), so the plant must measure
  // there too (it used to keep the seed stage's places whatever the profile
  // said). Same order and mapping as the kernel: interferometers -> beams,
  // laser displacement sensors -> heights, the first Hall sensor -> Hall A
  // (B a quarter pitch further in x and y).
  int beams = 0, heights = 0, halls = 0;
  for (int s = 0; s < p.sensor_count && s < sp::kMaxSensors; ++s) {
    const sp::Sensor& sensor = p.sensors[s];
    if (sensor.kind == sp::SensorKind::kInterferometer && beams < io::kInterferometerAxes) {
      const double cx = std::cos(sensor.direction_rad), sy = std::sin(sensor.direction_rad);
      const bool along_x = std::fabs(cx) > 0.5;
      if (along_x != (beams == 0)) {
        *why = "the bench plant models interferometer 1 along X and 2 and 3 along Y (sensor " +
               std::to_string(s + 1) + " is along " + (along_x ? "X" : "Y") + ")";
        return false;
      }
      if (along_x) {
        c.interferometer.x_beam_y_m = sensor.y_m;
      } else {
        c.interferometer.y_beam_x_m[beams - 1] = sensor.x_m;
      }
      c.interferometer.sign[beams] = (along_x ? cx : sy) < 0.0 ? -1 : 1;
      ++beams;
    } else if (sensor.kind == sp::SensorKind::kLaserDisplacement && heights < io::kDisplacementSensors) {
      c.displacement.sensor_x_m[heights] = sensor.x_m;
      c.displacement.sensor_y_m[heights] = sensor.y_m;
      ++heights;
    } else if (sensor.kind == sp::SensorKind::kHall && halls++ == 0) {
      c.hall.a_x_m = sensor.x_m;
      c.hall.a_y_m = sensor.y_m;
      c.hall.b_x_m = sensor.x_m + p.halbach.pitch_m / 4;
      c.hall.b_y_m = sensor.y_m + p.halbach.pitch_m / 4;
    }
  }
  ApplyServoRate(p.servo_rate_Hz, &c);
  *out = c;
  return true;
}

}  // namespace maglev::hil
