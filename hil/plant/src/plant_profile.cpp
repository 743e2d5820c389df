#include "maglev/plant/plant_profile.hpp"

#include "maglev/stage_profile/apply_profile.hpp"

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
  // The sensors where the profile puts them, from the same mapping the
  // kernel's pose solver gets (stage_profile::SetSensorGeometry): the plant
  // used to keep the seed stage's places whatever the profile said. Hall B
  // sits a quarter pitch from A in x and y, as the kernel assumes.
  kernel::SensorsToPoseConfig m = kernel::DefaultSensorsToPoseConfig();
  sp::SetSensorGeometry(p, &m);
  for (int b = 0; b < io::kInterferometerAxes; ++b) {
    const kernel::BeamAxis want = b == 0 ? kernel::BeamAxis::kX : kernel::BeamAxis::kY;
    if (m.beam[b].axis != want) {
      *why = "the bench plant models interferometer 1 along X and 2 and 3 along Y (interferometer " +
             std::to_string(b + 1) + " is along " + (want == kernel::BeamAxis::kX ? "Y" : "X") + ")";
      return false;
    }
    c.interferometer.sign[b] = m.beam[b].sign;
  }
  // Their scales too: the counter's interpolation and the heights' m per V.
  c.interferometer.interpolation = m.interpolation;
  c.displacement.scale_m_per_V = m.displacement_scale_m_per_V;
  c.interferometer.x_beam_y_m = m.beam[0].perpendicular_m;
  c.interferometer.y_beam_x_m[0] = m.beam[1].perpendicular_m;
  c.interferometer.y_beam_x_m[1] = m.beam[2].perpendicular_m;
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    c.displacement.sensor_x_m[i] = m.displacement_sensor_x_m[i];
    c.displacement.sensor_y_m[i] = m.displacement_sensor_y_m[i];
  }
  c.hall.a_x_m = m.hall_a_x_m;
  c.hall.a_y_m = m.hall_a_y_m;
  c.hall.b_x_m = m.hall_a_x_m + p.halbach.pitch_m / 4;
  c.hall.b_y_m = m.hall_a_y_m + p.halbach.pitch_m / 4;
  // The sensors' own noise figures, for the component noise models (the
  // default model keeps the bench's own; docs/PLANT.md section 11), sensor by
  // sensor in the order sp::SetSensorGeometry gives them their beams and
  // heights (the profile's interferometers, then its laser displacement
  // sensors, each kind in order).
  int beams = 0, heights = 0;
  for (double& v : c.interferometer.component_noise_m) v = 0.0;
  for (double& v : c.displacement.component_noise_m) v = 0.0;
  for (double& v : c.interferometer.sensor_noise_m) v = 0.0;
  for (double& v : c.displacement.sensor_noise_m) v = 0.0;
  for (int s = 0; s < p.sensor_count && s < sp::kMaxSensors; ++s) {
    const sp::Sensor& sensor = p.sensors[s];
    if (sensor.kind == sp::SensorKind::kInterferometer && beams < io::kInterferometerAxes) {
      c.interferometer.component_noise_m[beams++] = sensor.noise;
    } else if (sensor.kind == sp::SensorKind::kLaserDisplacement && heights < io::kDisplacementSensors) {
      c.displacement.component_noise_m[heights++] = sensor.noise;
    }
  }
  // Hall A's height and sensitivity as the check judged them
  // (HallSignalSwing: the profile's, or the family's when not given).
  for (int s = 0; s < p.sensor_count && s < sp::kMaxSensors; ++s) {
    if (p.sensors[s].kind != sp::SensorKind::kHall) continue;
    const sp::HallSwing w = sp::HallSignalSwing(p, p.sensors[s]);
    c.hall.height_above_magnets_m = w.height_m;
    c.hall.sensitivity_V_per_T = w.sensitivity_V_per_T;
    break;
  }
  ApplyServoRate(p.servo_rate_Hz, &c);
  *out = c;
  return true;
}

}  // namespace maglev::hil
