#include "maglev/plant/plant_profile.hpp"

namespace maglev::hil {

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
  c.amplifier.current_limit_A = p.limits.hardware_current_A;
  c.integration.servo_rate_Hz = p.servo_rate_Hz;
  *out = c;
  return true;
}

}  // namespace maglev::hil
