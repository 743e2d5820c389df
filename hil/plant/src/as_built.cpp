#include "maglev/plant/as_built.hpp"

#include <cmath>
#include <random>

namespace maglev::hil {

// One row per error term. Sources: docs/PLANT.md "Error sets" (the same
// words, with the reasoning). Magnitudes are tolerance-class figures, never
// chosen from a bench result.
const ErrorTerm kErrorTerms[kErrorTermCount] = {
    {"amp_gain_error", Draw::kUniform, 0.01, 0, 0.02, "1 % resistor tolerance of the PA12A amplifiers (paper 003 Sec. 2.2)"},
    {"amp_offset_A", Draw::kUniform, 5e-3, 0, 20e-3, "uncalibrated DC drift (paper 003 Sec. 2.2; Table 1 floor 4.8 mA)"},
    {"amp_bandwidth_error", Draw::kUniform, 0.10, 0, 0.30, "current-loop RC parts, 5-10 % capacitor tolerance"},
    {"coil_position_m", Draw::kNormal, 0.1e-3, 0, 0.5e-3, "coil placement on the platen, machining/assembly class 0.1 mm (paper 003's epsilon)"},
    {"coil_yaw_rad", Draw::kNormal, 1.5e-3, 0, 5e-3, "coil pair squareness to the array, 1-2 mrad (issue 15; paper 000 Sec. I)"},
    {"coil_roll_rad", Draw::kNormal, 1.5e-3, 0, 5e-3, "coil plane tilt, 1-2 mrad (flatness of the coil sets' bottom surface)"},
    {"lever_arm_m", Draw::kNormal, 0.1e-3, 0, 0.5e-3, "forcer centre placement, 0.1 mm"},
    {"bstar_error", Draw::kNormal, 0.01, 0, 0.05, "per-forcer b*: turns fill factor and gap, 1 %"},
    {"com_xy_m", Draw::kBand, 5e-3, 0.4, 10e-3, "CoM 2-5 mm off centre: cables, sensor mounts, mirrors on two sides"},
    {"com_height_m", Draw::kBandPositive, 8e-3, 0.375, 15e-3, "CoM 3-8 mm above the coils' mid-plane (18 mm frame, mirrors, sensors)"},
    {"products_of_inertia_kgm2", Draw::kNormal, 2e-5, 0, 1e-4, "m * offsets (0.75 kg x 5 mm x 5 mm = 1.9e-5 kg m^2)"},
    {"magnet_pitch_error", Draw::kUniform, 5e-4, 0, 2e-3, "0.05 % cumulative pitch error of the bar array"},
    {"mirror_orthogonality_rad", Draw::kUniform, 0.3e-3, 0, 1e-3, "x/y mirror squareness 0.1-0.5 mrad (bonded mirrors)"},
    {"mirror_tilt_rad", Draw::kUniform, 0.3e-3, 0, 1e-3, "mirror tilt to the platen plane 0.1-0.5 mrad"},
    {"mirror_flatness_m", Draw::kUniform, 32e-9, 0, 160e-9, "lambda/20 flatness (precision plane mirror), bow at the ends"},
    {"abbe_offset_m", Draw::kNormal, 0.5e-3, 0, 3e-3, "beam height vs the CoM, 0.5 mm"},
    {"y_beam_separation_m", Draw::kNormal, 0.1e-3, 0, 0.5e-3, "y1/y2 beam separation, 0.1 mm (interferometer mounts)"},
    {"lds_position_m", Draw::kNormal, 0.15e-3, 0, 0.5e-3, "LDS positions on the platen 0.1-0.2 mm"},
    {"target_cell_height_m", Draw::kUniform, 50e-6, 0, 0.2e-3, "magnet block height tolerance +-0.05 mm (LDS target at the 12.7 mm bar pitch)"},
};

int find_error_term(const std::string& key) {
  for (int i = 0; i < kErrorTermCount; ++i) {
    if (key == kErrorTerms[i].key) return i;
  }
  return -1;
}

ErrorSet::ErrorSet() {
  for (int i = 0; i < kErrorTermCount; ++i) magnitude[i] = kErrorTerms[i].magnitude;
}

bool parse_plant_model(const std::string& s, PlantModel* out) {
  if (s == "default") *out = PlantModel::kDefault;
  else if (s == "ideal") *out = PlantModel::kIdeal;
  else if (s == "nominal") *out = PlantModel::kNominal;
  else if (s == "as-built" || s == "as_built") *out = PlantModel::kAsBuilt;
  else return false;
  return true;
}

const char* to_string(PlantModel m) {
  switch (m) {
    case PlantModel::kIdeal: return "ideal";
    case PlantModel::kNominal: return "nominal";
    case PlantModel::kAsBuilt: return "as-built";
    default: return "default";
  }
}

ComponentNoise component_noise() { return ComponentNoise{}; }

double component_current_noise_density_A_per_rtHz(const ComponentNoise& n, double gain_A_per_V) {
  return gain_A_per_V * std::sqrt(n.dac_V_per_rtHz * n.dac_V_per_rtHz + n.amplifier_V_per_rtHz * n.amplifier_V_per_rtHz +
                                  n.current_sense_V_per_rtHz * n.current_sense_V_per_rtHz);
}

void ApplyComponentNoise(PlantConfig* c) {
  const ComponentNoise n = component_noise();
  c->amplifier.current_noise_density_A_per_rtHz =
      component_current_noise_density_A_per_rtHz(n, c->amplifier.gain_A_per_V);
  c->amplifier.current_noise_scale = 1.0;
  // The stage's own sensors' figures, sensor by sensor, where its profile
  // gives them.
  c->interferometer.use_component_figures(n.interferometer_m);
  c->displacement.use_component_figures(n.displacement_m);
  c->sensor_noise_enabled = true;
}

PlantConfig NominalPlant(const PlantConfig& base) {
  // No hand-set imperfections: the stage as drawn.
  PlantConfig c = PlantConfig::AsDrawn(base);
  ApplyComponentNoise(&c);
  return c;
}

namespace {

// A fixed number of draws per term, whatever its magnitude: changing one
// term's magnitude never changes another term's values.
struct Drawer {
  explicit Drawer(std::uint64_t seed) : engine(seed ^ 0x9e3779b97f4a7c15ull) {}
  std::mt19937_64 engine;
  double Uniform01() { return std::uniform_real_distribution<double>(0.0, 1.0)(engine); }
  double Normal() { return std::normal_distribution<double>(0.0, 1.0)(engine); }
  // One value of a term of magnitude m (two raw draws always consumed).
  double Value(const ErrorTerm& t, double m) {
    const double u = Uniform01();
    const double g = Normal();
    switch (t.draw) {
      case Draw::kUniform: return m * (2.0 * u - 1.0);
      case Draw::kNormal: return m * g;
      case Draw::kBand: {
        const double mag = m * (t.lo_fraction + (1.0 - t.lo_fraction) * u);
        return g < 0.0 ? -mag : mag;
      }
      case Draw::kBandPositive: return m * (t.lo_fraction + (1.0 - t.lo_fraction) * u);
    }
    return 0.0;
  }
};

}  // namespace

DrawnErrors DrawAsBuilt(const ErrorSet& set, PlantConfig* c) {
  DrawnErrors out;
  Drawer d(set.error_seed);
  AsBuiltConfig& ab = c->as_built;
  ab.active = true;
  auto term = [&](const char* key) { return find_error_term(key); };
  auto draw = [&](const char* key, const std::string& name) {
    const int i = term(key);
    const double v = d.Value(kErrorTerms[i], set.magnitude[i] * set.error_scale);
    out.emplace_back(name, v);
    return v;
  };
  const std::string coil = "coil";
  for (int j = 0; j < kCoils; ++j) {
    const std::string n = std::to_string(j + 1);
    c->amplifier.gain_error[j] = draw("amp_gain_error", "amp" + n + "_gain_error");
    c->amplifier.offset_A[j] = draw("amp_offset_A", "amp" + n + "_offset_A");
    c->amplifier.bandwidth_error[j] = draw("amp_bandwidth_error", "amp" + n + "_bandwidth_error");
  }
  for (int j = 0; j < kCoils; ++j) {
    const std::string n = std::to_string(j + 1);
    ab.coil_shift_m[j] = draw("coil_position_m", coil + n + "_position_m");
    ab.coil_roll_rad[j] = draw("coil_roll_rad", coil + n + "_roll_rad");
  }
  for (int f = 0; f < kForcers; ++f) {
    const std::string n = std::to_string(f + 1);
    c->forcer_errors.misalignment_rad[f] = draw("coil_yaw_rad", "forcer" + n + "_yaw_rad");
    ab.forcer_lever_offset_m[f] = draw("lever_arm_m", "forcer" + n + "_lever_arm_m");
    ab.forcer_bstar_error[f] = draw("bstar_error", "forcer" + n + "_bstar_error");
  }
  ab.com_offset_m[0] = draw("com_xy_m", "com_x_m");
  ab.com_offset_m[1] = draw("com_xy_m", "com_y_m");
  c->body.com_above_coil_midplane_m += draw("com_height_m", "com_height_m");
  static const char* kPoi[3] = {"ixy_kgm2", "ixz_kgm2", "iyz_kgm2"};
  for (int a = 0; a < 3; ++a) ab.products_of_inertia_kgm2[a] = draw("products_of_inertia_kgm2", kPoi[a]);
  ab.magnet_pitch_error = draw("magnet_pitch_error", "magnet_pitch_error");
  ab.x_mirror_yaw_rad = draw("mirror_orthogonality_rad", "x_mirror_yaw_rad");
  ab.x_mirror_pitch_rad = draw("mirror_tilt_rad", "x_mirror_pitch_rad");
  ab.y_mirror_roll_rad = draw("mirror_tilt_rad", "y_mirror_roll_rad");
  ab.mirror_bow_m = draw("mirror_flatness_m", "mirror_bow_m");
  c->interferometer.beam_height_m += draw("abbe_offset_m", "beam_height_m");
  {
    // The separation error moves y1 and y2 apart by half each (halving is
    // exact: the same bits as -/+ (separation + error) / 2).
    const double e = draw("y_beam_separation_m", "y_beam_separation_error_m");
    c->interferometer.y_beam_x_m[0] -= 0.5 * e;
    c->interferometer.y_beam_x_m[1] += 0.5 * e;
  }
  for (int i = 0; i < io::kDisplacementSensors; ++i) {
    const std::string n = std::to_string(i + 1);
    c->displacement.sensor_x_m[i] += draw("lds_position_m", "lds" + n + "_dx_m");
    c->displacement.sensor_y_m[i] += draw("lds_position_m", "lds" + n + "_dy_m");
  }
  const int tc = term("target_cell_height_m");
  ab.target_cell_height_m = set.magnitude[tc] * set.error_scale;
  ab.target_seed = set.error_seed;
  out.emplace_back("target_cell_height_bound_m", ab.target_cell_height_m);
  out.emplace_back("error_seed", static_cast<double>(set.error_seed));
  out.emplace_back("error_scale", set.error_scale);
  return out;
}

}  // namespace maglev::hil
