#include "maglev/bench/overrides.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>

#include "maglev/bench/axes.hpp"
#include "maglev/bench/metrics_registry.hpp"
#include "maglev/bench/profile_check.hpp"
#include "maglev/bench/timeline.hpp"
#include "maglev/bench/units.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/modbus/controller_binding.hpp"
#include "maglev/plant/plant_profile.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/register_schema/register_map.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

#ifndef MAGLEV_PROFILE_DIR
#define MAGLEV_PROFILE_DIR "hil/profiles"
#endif

namespace maglev::bench {

namespace {
// A scenario key bounded by a register's range (one source: a scenario may
// not set what Modbus would refuse). Empty when x is within REG's [min, max],
// else what to report.
std::string outside_register_range(const std::string& reg, double x) {
  const modbus::RegisterDef* d = modbus::find_by_name(reg.c_str());
  if (d != nullptr && x >= d->min && x <= d->max) return {};
  return "outside " + reg + "'s range [" +
         (d ? std::to_string(d->min) + ", " + std::to_string(d->max) : std::string("?")) + "]";
}
}  // namespace

void apply_paper_controller(kernel::KernelConfig* c) {
  // Paper 000's published PIDs, (27) x and y, (28) theta_z, (32) z, (33)
  // theta_x and theta_y, C(s) = kp + kd s + ki / s on the error r - y: the
  // proportional and derivative terms both see the reference (setpoint
  // weights b = c = 1), no acceleration feed-forward, no output filters.
  // Our defaults use the same gains with b < 1, c = 0 and feed-forward.
  // Kept from the defaults: the derivative's 1 kHz filter (a pure derivative
  // cannot be discretized; the paper does not give its realization) and the
  // back-calculation anti-windup, which acts only while the current limit
  // does.
  for (int a = 0; a < kernel::kAxisCount; ++a) {
    kernel::AxisLoopConfig& axis = c->axis[a];
    axis.type = kernel::LoopType::kPid2Dof;
    axis.pid.setpoint_weight_p = 1.0f;
    axis.pid.setpoint_weight_d = 1.0f;
    for (kernel::BiquadConfig& f : axis.filters) f = kernel::BiquadConfig{};
  }
  c->acceleration_feedforward = false;
  // Nor did the paper's stage repair its displacement sensors' target steps
  // (ours, SensorsToPoseConfig::lds_target_*): its loops saw them.
  c->measurement.lds_target_repair = 0;
}

const char* const kPlantOptionsUsage =
    "                 [--plant default|ideal|nominal|as-built] [--error-seed N]   the plant model (docs/PLANT.md)\n"
    "                 [--floor CLASS]    the floor under the base: none, vc-e .. vc-a, operating-theatre,\n"
    "                                    residential, office, workshop (docs/PLANT.md section 12)\n"
    "                 [--floor-isolator-hz HZ]  the base on a passive isolator (0: rigid; 0.3-20 Hz)\n";

PlantOptionParse parse_plant_option(const std::string& option, const std::string& value, PlantOptions* p,
                                    std::string* err) {
  const auto bad = [&](const std::string& why) {
    *err = option + ": " + why;
    return PlantOptionParse::kBad;
  };
  if (option == "--plant") {
    hil::PlantModel m{};
    if (!hil::parse_plant_model(value, &m)) return bad("expected default, ideal, nominal or as-built, got '" + value + "'");
    p->model = m;
  } else if (option == "--error-seed") {
    // The [plant] error_seed key's range: a non-negative integer up to 9e15.
    char* end = nullptr;
    const unsigned long long n = std::strtoull(value.c_str(), &end, 10);
    if (value.empty() || value[0] == '-' || end == value.c_str() || *end != '\0' || n > 9000000000000000ull) {
      return bad("a non-negative integer, got '" + value + "'");
    }
    p->error_seed = n;
  } else if (option == "--floor") {
    p->floor = value;  // its class is checked with the scenario (apply_overrides)
  } else if (option == "--floor-isolator-hz") {
    char* end = nullptr;
    const double hz = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0') return bad("not a number: '" + value + "'");
    p->floor_isolator_hz = hz;  // its range is checked with the scenario (apply_overrides)
  } else {
    return PlantOptionParse::kNotPlantOption;
  }
  return PlantOptionParse::kTaken;
}

bool plant_for_stage(const hil::PlantConfig& base, const kernel::KernelConfig& controller,
                     const scenario::Scenario* sc, const PlantOptions& options, StagePlant* out,
                     std::vector<ScenarioError>* errs) {
  Overrides o;
  o.plant = base;
  o.controller = controller;
  o.command_line = options;
  const scenario::Scenario none{"<no scenario>", {}, {}, {}, {}, {}, {}, {}};
  const std::size_t before = errs->size();
  apply_overrides(sc != nullptr ? *sc : none, &o, errs);
  if (errs->size() != before) return false;
  out->plant = o.plant;
  out->model = o.plant_model;
  out->error_set = o.error_set;
  out->drawn_errors = o.drawn_errors;
  out->seed = o.seed;
  return true;
}

std::string offered_servo_rates() {
  std::string t;
  const std::size_t n = std::size(io::stage::kSupportedServoRates_Hz);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) t += i + 1 < n ? ", " : " or ";
    t += std::to_string(static_cast<long>(io::stage::kSupportedServoRates_Hz[i]));
  }
  return t + " Hz";
}

bool apply_overrides(const scenario::Scenario& sc, Overrides* o, std::vector<ScenarioError>* errs) {
  const std::size_t before = errs->size();
  auto fail = [&](const std::string& what) { errs->push_back({sc.source + ": " + what}); };
  auto num = [&](const std::string& sect, const std::string& key, const std::string& v, Dim d, double* dst) {
    std::string e;
    const auto r = parse_quantity(v, d, &e);
    if (!r) {
      fail("[" + sect + "] " + key + ": " + e);
      return false;
    }
    *dst = *r;
    return true;
  };
  auto flag = [&](const std::string& sect, const std::string& key, const std::string& v, bool* dst) {
    if (v == "on" || v == "true" || v == "1" || v == "yes") { *dst = true; return; }
    if (v == "off" || v == "false" || v == "0" || v == "no") { *dst = false; return; }
    fail("[" + sect + "] " + key + ": expected on/off, got '" + v + "'");
  };
  // [scenario]
  for (const auto& [k, v] : sc.scenario) {
    if (k == "seed") {
      double s = 0;
      if (num("scenario", k, v, Dim::kNumber, &s)) {
        if (s < 0 || s != std::floor(s)) fail("[scenario] seed must be a non-negative integer");
        o->seed = static_cast<std::uint64_t>(s);
      }
    } else if (k == "kernel") {
      if (!hil::parse_kernel_kind(v, &o->kernel)) fail("[scenario] kernel: expected float32 or q7.24, got '" + v + "'");
    } else if (k != "name" && k != "title" && k != "duration_s" && k != "paper" && k != "primary" &&
               k != "description" && k != "profile") {
      fail("[scenario] unknown key '" + k +
           "' (name, title, description, duration_s, kernel, seed, paper, primary, profile)");
    }
  }
  if (const auto it = sc.scenario.find("primary"); it != sc.scenario.end()) {
    Axis p{};
    if (!parse_axis(it->second, &p)) fail("[scenario] primary: unknown axis '" + it->second + "'");
  }
  // [plant]: a baseline first (model, noise), then the single-value
  // overrides, then (as-built) the error set drawn on top. Every bad [plant]
  // line is reported as file:line: key: reason.
  auto plant_fail = [&](const std::string& key, const std::string& why) {
    const auto ln = sc.plant_line.find(key);
    errs->push_back({sc.source + ":" + (ln != sc.plant_line.end() ? std::to_string(ln->second) : std::string("0")) +
                     ": " + key + ": " + why});
  };
  if (const auto it = sc.plant.find("model"); it != sc.plant.end()) {
    if (!hil::parse_plant_model(it->second, &o->plant_model)) {
      plant_fail("model", "expected default, ideal, nominal or as-built, got '" + it->second + "'");
    }
  }
  if (o->command_line.model) o->plant_model = *o->command_line.model;
  switch (o->plant_model) {
    // The stage's own plant (its profile's), made ideal: until 2026-11-29
    // this took the default stage's ideal plant whatever the profile, and
    // `--profile nk2020-square --plant ideal` faulted (the square kernel on
    // the cross plant).
    case hil::PlantModel::kIdeal: o->plant = hil::PlantConfig::IdealOf(o->plant); break;
    case hil::PlantModel::kNominal:
    case hil::PlantModel::kAsBuilt: o->plant = hil::NominalPlant(o->plant); break;
    default: break;
  }
  // Whatever the model, the plant steps at the controller's servo rate (the
  // ideal model starts from the defaults).
  hil::ApplyServoRate(static_cast<double>(o->controller.servo_rate_Hz), &o->plant);
  // noise = component | fitted: the fitted density (docs/BENCH.md) stays a
  // named option; nominal and as-built default to the component figures.
  o->noise_fitted = o->plant_model == hil::PlantModel::kDefault;
  if (const auto it = sc.plant.find("noise"); it != sc.plant.end()) {
    o->noise_fitted = it->second == "fitted";
    if (it->second == "fitted") {
      const hil::PlantConfig fitted{};
      o->plant.amplifier.current_noise_density_A_per_rtHz = fitted.amplifier.current_noise_density_A_per_rtHz;
      o->plant.interferometer.set_noise_m(fitted.interferometer.noise_m);
      o->plant.displacement.set_noise_m(fitted.displacement.noise_m);
    } else if (it->second == "component") {
      hil::ApplyComponentNoise(&o->plant);
    } else {
      plant_fail("noise", "expected component or fitted, got '" + it->second + "'");
    }
  }
  // The error set: error_seed, error_scale and one magnitude per term, each
  // within its physical bound (kErrorTerms).
  bool error_keys = false;
  for (const auto& [k, v] : sc.plant) {
    const int term = hil::find_error_term(k);
    if (k != "error_seed" && k != "error_scale" && term < 0) continue;
    error_keys = true;
    const auto x = scenario::parse_number(v);
    if (!x) {
      plant_fail(k, "not a number: '" + v + "'");
      continue;
    }
    if (k == "error_seed") {
      if (*x < 0 || *x != std::floor(*x) || *x > 9.0e15) plant_fail(k, "must be a non-negative integer");
      else o->error_set.error_seed = static_cast<std::uint64_t>(*x);
    } else if (k == "error_scale") {
      if (!(*x >= 0.0 && *x <= 2.0)) plant_fail(k, "must be within [0, 2] (and every scaled term within its bound)");
      else o->error_set.error_scale = *x;
    } else {
      const hil::ErrorTerm& t = hil::kErrorTerms[term];
      if (!(*x >= 0.0)) plant_fail(k, "a magnitude, must be >= 0");
      else if (*x > t.max) plant_fail(k, v + " is above its physical bound " + std::to_string(t.max) + " (" + t.source + ")");
      else o->error_set.magnitude[term] = *x;
    }
  }
  for (int i = 0; i < hil::kErrorTermCount; ++i) {
    const double scaled = o->error_set.magnitude[i] * o->error_set.error_scale;
    if (scaled > hil::kErrorTerms[i].max * (1.0 + 1e-12)) {
      plant_fail(sc.plant.count("error_scale") ? "error_scale" : hil::kErrorTerms[i].key,
                 std::string("scales ") + hil::kErrorTerms[i].key + " to " + std::to_string(scaled) +
                     ", above its physical bound " + std::to_string(hil::kErrorTerms[i].max));
    }
  }
  if (error_keys && o->plant_model != hil::PlantModel::kAsBuilt && !o->command_line.model) {
    for (const auto& [k, v] : sc.plant) {
      if (k == "error_seed" || k == "error_scale" || hil::find_error_term(k) >= 0) {
        plant_fail(k, "an error-set key needs model = as-built");
        break;
      }
    }
  }
  if (o->command_line.error_seed) {
    // An error seed draws the as-built model's errors: on any other model it
    // would change nothing, and the run would not be the stage asked for.
    if (o->plant_model != hil::PlantModel::kAsBuilt) {
      fail("--error-seed " + std::to_string(*o->command_line.error_seed) + ": the plant model is " +
           hil::to_string(o->plant_model) +
           ", and an error seed draws the as-built model's errors (--plant as-built, or [plant] model = as-built)");
    }
    o->error_set.error_seed = *o->command_line.error_seed;
  }
  // The floor under the base (docs/PLANT.md section 12): a named class or a
  // band velocity of the lab's own, and an optional isolator. Any model.
  {
    hil::FloorVibrationConfig& f = o->plant.floor;
    using FC = hil::FloorVibrationConfig;
    auto floor_num = [&](const std::string& key, double lo, double hi, const char* what, double* dst) {
      const auto it = sc.plant.find(key);
      if (it == sc.plant.end()) return;
      const auto x = scenario::parse_number(it->second);
      if (!x) plant_fail(key, "not a number: '" + it->second + "'");
      else if (!(*x >= lo && *x <= hi)) plant_fail(key, it->second + " is outside " + what);
      else *dst = *x;
    };
    std::optional<std::string> name;
    if (const auto it = sc.plant.find("floor"); it != sc.plant.end()) name = it->second;
    if (o->command_line.floor) {
      // The command line wins, visibly: a run that replaces the scenario's
      // floor says so (metrics.json records the level used).
      for (const char* key : {"floor", "floor_band_velocity_m_per_s"}) {
        if (const auto it = sc.plant.find(key); it != sc.plant.end()) {
          std::fprintf(stderr, "note: --floor %s replaces the scenario's [plant] %s = %s\n",
                       o->command_line.floor->c_str(), key, it->second.c_str());
        }
      }
      name = *o->command_line.floor;
    }
    if (name) {
      const int c = hil::find_floor_class(*name);
      if (c < 0) {
        if (o->command_line.floor) fail("--floor: expected " + std::string(hil::floor_class_names()) + ", got '" + *name + "'");
        else plant_fail("floor", "expected " + std::string(hil::floor_class_names()) + ", got '" + *name + "'");
      } else {
        f.band_velocity_m_per_s = hil::kFloorClasses[c].band_velocity_m_per_s;
      }
    }
    if (sc.plant.count("floor_band_velocity_m_per_s") != 0 && sc.plant.count("floor") != 0) {
      plant_fail("floor_band_velocity_m_per_s", "give floor or floor_band_velocity_m_per_s, not both");
    } else {
      // Checked under --floor too: a bad key is refused whatever replaces it.
      double band = f.band_velocity_m_per_s;
      floor_num("floor_band_velocity_m_per_s", 0.0, FC::kMaxBandVelocity_m_per_s,
                "[0, 2e-3] m/s (0: none; 2e-3 is 2.5x the workshop curve)", &band);
      if (!o->command_line.floor) f.band_velocity_m_per_s = band;
    }
    // The isolator: the scenario's key, then --floor-isolator-hz; one range.
    if (const auto it = sc.plant.find("floor_isolator_hz"); it != sc.plant.end()) {
      const auto x = scenario::parse_number(it->second);
      if (!x) plant_fail("floor_isolator_hz", "not a number: '" + it->second + "'");
      else if (!FC::isolator_hz_ok(*x)) plant_fail("floor_isolator_hz", std::string(FC::kIsolatorRange) + ", got " + it->second);
      else f.isolator_hz = *x;
    }
    if (o->command_line.floor_isolator_hz) {
      const double hz = *o->command_line.floor_isolator_hz;
      if (const auto it = sc.plant.find("floor_isolator_hz"); it != sc.plant.end()) {
        std::fprintf(stderr, "note: --floor-isolator-hz %g replaces the scenario's [plant] floor_isolator_hz = %s\n", hz,
                     it->second.c_str());
      }
      if (!FC::isolator_hz_ok(hz)) fail("--floor-isolator-hz: " + std::string(FC::kIsolatorRange) + ", got " + std::to_string(hz));
      else f.isolator_hz = hz;
    }
    floor_num("floor_isolator_damping", FC::kMinIsolatorDamping, FC::kMaxIsolatorDamping, "[0.01, 2]",
              &f.isolator_damping);
  }
  for (const auto& [k, v] : sc.plant) {
    auto& p = o->plant;
    if (k == "model" || k == "noise" || k == "error_seed" || k == "error_scale" || hil::find_error_term(k) >= 0) continue;
    if (k == "floor" || k == "floor_band_velocity_m_per_s" || k == "floor_isolator_hz" || k == "floor_isolator_damping") {
      continue;
    }
    if (k == "current_noise_scale" || k == "current_noise_density_A_per_rtHz") o->noise_fitted = false;  // its own
    if (k == "payload_kg") num("plant", k, v, Dim::kMass, &p.body.payload_kg);
    else if (k == "current_noise_scale") num("plant", k, v, Dim::kNumber, &p.amplifier.current_noise_scale);
    else if (k == "current_noise_density_A_per_rtHz")
      num("plant", k, v, Dim::kNumber, &p.amplifier.current_noise_density_A_per_rtHz);
    else if (k == "interferometer_noise_m" || k == "displacement_noise_m") {
      // One figure for every sensor of the kind: each beam, or each height.
      const auto one_figure = [&](auto& kind) {
        double n = kind.noise_m;
        num("plant", k, v, Dim::kLength, &n);
        kind.set_noise_m(n);
      };
      if (k == "interferometer_noise_m") one_figure(p.interferometer);
      else one_figure(p.displacement);
    }
    else if (k == "sensor_noise") flag("plant", k, v, &p.sensor_noise_enabled);
    else if (k == "initial_x_m" || k == "initial_y_m") {
      // Where the platen rests at power-on: on the magnet array, inside the
      // travel (initial_x_m = 1 once levitated to Ready a metre off the stage).
      const int i = k == "initial_x_m" ? 0 : 1;
      const Axis a = i == 0 ? Axis::kX : Axis::kY;
      double pos = 0.0;
      if (num("plant", k, v, Dim::kLength, &pos)) {
        const double lo = static_cast<double>(o->controller.references.position_min[index(a)]);
        const double hi = static_cast<double>(o->controller.references.position_max[index(a)]);
        if (!(pos >= lo && pos <= hi)) {
          fail("[plant] " + k + " = " + v + ": outside the travel [" + std::to_string(lo) + ", " + std::to_string(hi) + "] m");
        } else {
          p.initial.position_m[i] = pos;
        }
      }
    }
    else if (k == "substeps_per_tick") {
      double n = 0;
      if (num("plant", k, v, Dim::kNumber, &n)) {
        if (n < 1 || n > 64 || n != std::floor(n)) fail("[plant] substeps_per_tick must be an integer 1..64");
        p.integration.substeps_per_tick = static_cast<int>(n);
      }
    } else if (k == "integrator") {
      if (v == "fast") p.integration.method = hil::IntegrationConfig::Method::kFast;
      else if (v == "classic") p.integration.method = hil::IntegrationConfig::Method::kClassic;
      else fail("[plant] integrator = " + v + ": expected fast or classic");
    } else if (k == "noise_generator") {
      if (v == "ziggurat") p.noise_generator = hil::NormalMethod::kZiggurat;
      else if (v == "polar") p.noise_generator = hil::NormalMethod::kPolar;
      else fail("[plant] noise_generator = " + v + ": expected ziggurat or polar");
    } else {
      plant_fail(k, "unknown key (model, noise, error_seed, error_scale, an error term of docs/PLANT.md, payload_kg, "
                    "current_noise_scale, current_noise_density_A_per_rtHz, interferometer_noise_m, displacement_noise_m, "
                    "sensor_noise, initial_x_m, initial_y_m, substeps_per_tick, integrator, noise_generator, floor, "
                    "floor_band_velocity_m_per_s, floor_isolator_hz, floor_isolator_damping)");
    }
  }
  if (o->plant_model == hil::PlantModel::kAsBuilt) {
    if (o->plant.body.layout == hil::BodyConfig::Layout::kTriangle) {
      fail("[plant] model = as-built: the error set is modelled for the cross and square layouts only");
    } else {
      o->drawn_errors = hil::DrawAsBuilt(o->error_set, &o->plant);
    }
  }
  // The supervisor's frozen-sample check (FaultCode::kFrozenSample) rests on
  // live sensors never repeating every bit of a sample. A plant whose sensors
  // read without noise (model = ideal, sensor_noise = off) breaks that
  // assumption, not the stage: once the loops settle its samples repeat, and
  // the check would land it. On such a plant the check is off, and
  // metrics.json says so (frozen_sample_check = 0).
  if (!o->plant.sensor_noise_enabled) o->controller.supervisor.max_identical_samples = 0;

  // [controller] preset first, so that AXIS.FIELD keys refine it.
  if (const auto it = sc.controller.find("preset"); it != sc.controller.end()) {
    if (it->second == "paper") {
      apply_paper_controller(&o->controller);
    } else if (it->second != "default") {
      fail("[controller] preset = " + it->second + ": expected default or paper");
    }
  }
  // [controller]: kernel config fields, SI. Per-axis gains as AXIS.FIELD.
  for (const auto& [k, v] : sc.controller) {
    auto& c = o->controller;
    if (k == "preset") continue;
    if (k == "servo_rate_Hz") {
      // Applied with the profile (apply_profile: the kernel configuration is
      // made at this rate); checked here so that validate() reports it.
      double r = 0;
      if (num("controller", k, v, Dim::kFrequency, &r) && !io::stage::is_supported_servo_rate(r)) {
        fail("[controller] servo_rate_Hz = " + v + ": the controller offers " + offered_servo_rates());
      }
      continue;
    }
    // A key that takes one of two words, each a value of a kernel field.
    const auto one_of_two = [&](const char* a, std::uint8_t value_a, const char* b, std::uint8_t value_b,
                                std::uint8_t* field) {
      if (v == a || v == b) {
        *field = v == a ? value_a : value_b;
      } else {
        fail("[controller] " + k + " = " + v + ": expected " + a + " or " + b);
      }
    };
    if (k == "lds_target_steps") {
      // repair (the kernel's default) | off (the paper's stage: its loops
      // saw every block step of the magnet array).
      one_of_two("repair", 1, "off", 0, &c.measurement.lds_target_repair);
      continue;
    }
    if (k == "z_point") {
      // centre (the kernel's default) | sensor_centroid: z = the mean of the
      // three height sensors, as a controller that averages them measures
      // and regulates it (docs/KERNEL.md "Where z is measured").
      one_of_two("centre", 0, "sensor_centroid", 1, &c.measurement.lds_z_point);
      continue;
    }
    if (k == "lds_target_step_min" || k == "lds_target_window") {
      // The repair's threshold and window (a length: "2 um", "0.8 mm"), within
      // the registers lds.target_step_min / lds.target_window's ranges (um).
      double m = 0;
      if (!num("controller", k, v, Dim::kLength, &m)) continue;
      const double um = m * 1e6;
      const std::string why =
          outside_register_range(k == "lds_target_step_min" ? "lds.target_step_min" : "lds.target_window", um);
      if (!why.empty()) {
        fail("[controller] " + k + " = " + v + ": " + why + " um");
        continue;
      }
      (k == "lds_target_step_min" ? c.measurement.lds_target_step_min_um : c.measurement.lds_target_window_um) =
          static_cast<float>(um);
      continue;
    }
    if (k == "payload_kg") {
      double m = 0;
      if (num("controller", k, v, Dim::kMass, &m)) c.payload_mass_kg = static_cast<float>(m);
      continue;
    }
    const auto dot = k.find('.');
    Axis p{};
    if (dot == std::string::npos || !parse_axis(k.substr(0, dot), &p)) {
      fail("[controller] unknown key '" + k +
           "' (preset, payload_kg, servo_rate_Hz, lds_target_steps, lds_target_step_min, lds_target_window, z_point, AXIS.kp|ki|kd|b|derivative_filter_Hz|loop, or AXIS.filterN.type|frequency_Hz|q|depth_dB|pole_Hz)");
      continue;
    }
    const std::string field = k.substr(dot + 1);
    // AXIS.filterN.FIELD: output filter stage N (1..2) of the axis, the
    // registers filter.AXIS.N.* (same ranges: one source).
    if (field.rfind("filter", 0) == 0 && field.size() > 8 && field[7] == '.' &&
        (field[6] == '1' || field[6] == '2')) {
      const int stage = field[6] - '1';
      const std::string sub = field.substr(8);
      kernel::BiquadConfig& f = c.axis[index(p)].filters[stage];
      const std::string reg_prefix = std::string("filter.") + axis_name(p) + "." + field[6] + ".";
      if (sub == "type") {
        static const std::pair<const char*, kernel::BiquadType> kTypes[] = {
            {"none", kernel::BiquadType::kNone}, {"notch", kernel::BiquadType::kNotch},
            {"low_pass", kernel::BiquadType::kLowPass}, {"lead_lag", kernel::BiquadType::kLeadLag}};
        bool found = false;
        for (const auto& [name, type] : kTypes) {
          if (v == name) {
            f.type = type;
            found = true;
          }
        }
        if (!found) fail("[controller] " + k + " = " + v + ": expected none, notch, low_pass or lead_lag");
        continue;
      }
      static const std::pair<const char*, const char*> kFilterFields[] = {
          {"frequency_Hz", "frequency"}, {"q", "q"}, {"depth_dB", "depth"}, {"pole_Hz", "pole"}};
      const char* reg_field = nullptr;
      for (const auto& [scenario_field, register_field] : kFilterFields) {
        if (sub == scenario_field) reg_field = register_field;
      }
      if (reg_field == nullptr) {
        fail("[controller] unknown field '" + sub + "' in '" + k + "' (type, frequency_Hz, q, depth_dB, pole_Hz)");
        continue;
      }
      double x = 0;
      const Dim dim = sub == "frequency_Hz" || sub == "pole_Hz" ? Dim::kFrequency : Dim::kNumber;
      if (!num("controller", k, v, dim, &x)) continue;
      const std::string why = outside_register_range(reg_prefix + reg_field, x);
      if (!why.empty()) {
        fail("[controller] " + k + " = " + v + ": " + why);
        continue;
      }
      const float xf = static_cast<float>(x);
      if (sub == "frequency_Hz") f.frequency_Hz = xf;
      else if (sub == "q") f.q = xf;
      else if (sub == "depth_dB") f.depth_dB = xf;
      else f.pole_Hz = xf;
      continue;
    }
    // AXIS.loop: the axis' regulator, the profile's `controller` key (paper
    // 000's 2-DOF PID or paper 002's internal-model regulator, designed on
    // the profile's axis plant).
    if (field == "loop") {
      if (v == "pid2dof") c.axis[index(p)].type = kernel::LoopType::kPid2Dof;
      else if (v == "internal_model") c.axis[index(p)].type = kernel::LoopType::kInternalModel;
      else fail("[controller] " + k + " = " + v + ": expected pid2dof or internal_model");
      continue;
    }
    double x = 0;
    if (!num("controller", k, v, Dim::kNumber, &x)) continue;
    // The same bounds as the register map (one source): a scenario may not
    // set what Modbus would refuse (z.kp = 1e30 once pinned the coils at 4 A).
    static const std::pair<const char*, const char*> kRegisterOf[] = {
        {"kp", "kp"}, {"ki", "ki"}, {"kd", "kd"}, {"b", "setpoint_weight_p"}, {"derivative_filter_Hz", "derivative_filter"}};
    for (const auto& [scenario_field, register_field] : kRegisterOf) {
      if (field != scenario_field) continue;
      const std::string reg = std::string("gain.") + axis_name(p) + "." + register_field;
      const modbus::RegisterDef* d = modbus::find_by_name(reg.c_str());
      if (d != nullptr && !(x >= d->min && x <= d->max)) {
        fail("[controller] " + k + " = " + v + ": outside " + reg + "'s range [" + std::to_string(d->min) + ", " +
             std::to_string(d->max) + "]");
        x = std::clamp(x, d->min, d->max);  // reported above: nothing runs
      }
    }
    auto& pid = c.axis[index(p)].pid;
    const float xf = static_cast<float>(x);
    if (field == "kp") pid.kp = xf;
    else if (field == "ki") pid.ki = xf;
    else if (field == "kd") pid.kd = xf;
    else if (field == "b") pid.setpoint_weight_p = xf;
    else if (field == "derivative_filter_Hz") pid.derivative_filter_hz = xf;
    else fail("[controller] unknown field '" + field + "' in '" + k +
              "' (kp, ki, kd, b, derivative_filter_Hz, loop, filter1.*, filter2.*)");
  }
  return errs->size() == before;
}

std::string profile_dir() { return MAGLEV_PROFILE_DIR; }

std::string profile_of(const scenario::Scenario& sc) {
  const auto it = sc.scenario.find("profile");
  return it == sc.scenario.end() ? kDefaultProfile : it->second;
}

std::optional<double> servo_rate_of(const scenario::Scenario& sc) {
  const auto it = sc.controller.find("servo_rate_Hz");
  if (it == sc.controller.end()) return std::nullopt;
  std::string e;
  const auto r = parse_quantity(it->second, Dim::kFrequency, &e);
  if (!r) return std::nullopt;
  return *r;
}

bool apply_profile(const std::string& name_or_path, Overrides* o, std::vector<ScenarioError>* errs,
                   std::optional<double> servo_rate_Hz) {
  profile::ProfileParse parsed = profile::find_profile(name_or_path, profile_dir());
  if (!parsed.ok()) {
    for (const auto& e : parsed.errors) errs->push_back({e});
    return false;
  }
  if (servo_rate_Hz) {
    if (!io::stage::is_supported_servo_rate(*servo_rate_Hz)) {
      errs->push_back({"servo rate " + std::to_string(*servo_rate_Hz) + " Hz: the controller offers " +
                       offered_servo_rates()});
      return false;
    }
    parsed.profile.servo_rate_Hz = *servo_rate_Hz;
  }
  kernel::KernelConfig kc{};
  const stage_profile::ProfileCheck check = stage_profile::MakeKernelConfig(parsed.profile, &kc);
  if (check.error != stage_profile::ProfileError::kOk) {
    errs->push_back({name_or_path + ": the controller refuses this profile: " + stage_profile::to_string(check.error) +
                     (check.axis >= 0 ? std::string(" (axis ") + axis_name(static_cast<Axis>(check.axis)) + ")" : "")});
    return false;
  }
  // As the firmware's stage selection (KernelConfigOfProfile): a value the
  // register map cannot hold could not be saved on the board.
  if (const std::string refusal = register_range_refusal(kc); !refusal.empty()) {
    errs->push_back({name_or_path + ": the controller refuses this profile: " + refusal});
    return false;
  }
  std::string why;
  hil::PlantConfig plant{};
  if (!hil::PlantConfigForProfile(parsed.profile, o->plant, &plant, &why)) {
    errs->push_back({name_or_path + ": " + why});
    return false;
  }
  o->profile_name = parsed.profile.name;
  o->profile = parsed.profile;
  o->controller = kc;
  o->plant = plant;
  return true;
}

std::vector<ScenarioError> validate(const scenario::Scenario& sc) {
  std::vector<ScenarioError> errs;
  auto at = [&](int line, const std::string& m) { errs.push_back({sc.source + ":" + std::to_string(line) + ": " + m}); };
  std::vector<TimelineAction> actions;
  std::vector<std::string> timeline_errors;
  if (!parse_timeline(sc, &actions, &timeline_errors)) {
    for (auto& e : timeline_errors) errs.push_back({e});
  }
  for (const auto& m : sc.metrics) {
    MetricSpec s;
    std::string err;
    if (!parse_metric(m, &s, &err)) at(m.line, err);
    else if (s.t1 > sc.duration_s() + 1e-9) at(m.line, "metric window ends after duration_s");
  }
  Overrides o;
  apply_overrides(sc, &o, &errs);
  if (sc.duration_s() > 600.0) errs.push_back({sc.source + ": duration_s above 600 s"});
  // The name becomes a folder under --out: letters, digits, '_', '-', '.' only,
  // never a path (name = ../../x once wrote outside --out).
  const std::string& n = sc.name();
  const bool name_ok = !n.empty() && n != "." && n != ".." && n.size() <= 64 &&
                       std::all_of(n.begin(), n.end(), [](char ch) {
                         return std::isalnum(static_cast<unsigned char>(ch)) != 0 || ch == '_' || ch == '-' || ch == '.';
                       });
  if (!name_ok) errs.push_back({sc.source + ": [scenario] name '" + n + "': letters, digits, _ - . only (it names the output folder)"});
  return errs;
}

}  // namespace maglev::bench
