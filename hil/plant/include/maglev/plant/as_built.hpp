// Plant models and error sets (docs/PLANT.md "Plant models and error sets").
//
//   ideal     no noise, no errors (regression tests, linearization);
//   default   today's bench (what a scenario gets when it names no model):
//             hand-set small imperfections and the FITTED current-noise density;
//   nominal   the stage exactly as drawn, noise from component figures;
//   as-built  nominal noise + one error set drawn from physically bounded
//             tolerances (error_seed, error_scale, one magnitude per term).
//
// Every error term is one row of kErrorTerms: its scenario key, how it is
// drawn, its default magnitude, the physical bound above which a scenario is
// refused, and where the magnitude comes from. The draw is a pure function of
// (terms, error_seed): the same seed gives the same stage, whatever the noise
// seed of the run.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "maglev/plant/plant_config.hpp"

namespace maglev::hil {

enum class PlantModel : std::uint8_t { kDefault = 0, kIdeal = 1, kNominal = 2, kAsBuilt = 3 };
// "default", "ideal", "nominal", "as-built"; false if unknown.
bool parse_plant_model(const std::string& s, PlantModel* out);
const char* to_string(PlantModel m);

// How a term's magnitude M is used.
enum class Draw : std::uint8_t {
  kUniform = 0,      // uniform in [-M, +M] (a tolerance class: "+-1 %")
  kNormal = 1,       // normal, sigma = M
  kBand = 2,         // |value| uniform in [lo_fraction M, M], random sign ("2-5 mm")
  kBandPositive = 3  // uniform in [lo_fraction M, M] ("3-8 mm above")
};

struct ErrorTerm {
  const char* key;        // scenario [plant] key, SI units in the name
  Draw draw;
  double magnitude;       // the as-built default
  double lo_fraction;     // kBand*: lower end of the band as a fraction of M
  double max;             // physical bound: a larger M is refused
  const char* source;     // where the magnitude comes from (docs/PLANT.md)
};

inline constexpr int kErrorTermCount = 19;
extern const ErrorTerm kErrorTerms[kErrorTermCount];
// Index of key in kErrorTerms, -1 if none.
int find_error_term(const std::string& key);

struct ErrorSet {
  std::uint64_t error_seed = 1;
  double error_scale = 1.0;  // multiplies every magnitude (0 = nominal geometry)
  double magnitude[kErrorTermCount] = {};
  ErrorSet();  // the defaults of kErrorTerms
};

// The errors actually drawn: (name, value) in SI, for metrics.json
// ("plant_error_<name>").
using DrawnErrors = std::vector<std::pair<std::string, double>>;

// The stage as drawn, component noise (no errors).
PlantConfig NominalPlant(const PlantConfig& base);
// Component noise figures (docs/PLANT.md "Noise from component figures").
void ApplyComponentNoise(PlantConfig* c);
// Draws one error set onto *c (a nominal plant) and returns what was drawn.
DrawnErrors DrawAsBuilt(const ErrorSet& set, PlantConfig* c);

// --- component noise figures (each cited in docs/PLANT.md) ------------------
struct ComponentNoise {
  // AD5764 output noise spectral density (datasheet: 60 nV/sqrt(Hz) at 10 kHz)
  // through the 0.5 A/V amplifier.
  double dac_V_per_rtHz = 60e-9;
  // PA12A input noise (datasheet: 10 uV rms in 10 kHz, i.e. 100 nV/sqrt(Hz)),
  // referred to the input of the 0.5 A/V transconductance stage.
  double amplifier_V_per_rtHz = 100e-9;
  // Current-sense chain, referred to the loop input like the two above: an
  // instrumentation-amplifier front end of 10 nV/sqrt(Hz) (INA-class
  // datasheets: 8-13 nV/sqrt(Hz)); a sense resistor's Johnson noise
  // (0.09 nV/sqrt(Hz) at 0.5 Ohm) is negligible beside it.
  double current_sense_V_per_rtHz = 10e-9;
  // HP 10706B + 5517D, electronics lambda/(4*256): quantization is modelled
  // by the counter; the rest is electronics + air turbulence over a short
  // (< 0.2 m) enclosed path: 0.3 nm rms per sample (Agilent/Keysight laser
  // system guide: resolution 0.3-0.6 nm; turbulence "< 1 nm" enclosed).
  double interferometer_m = 0.3e-9;
  // Laser displacement sensor, Keyence LK-G10-class (+-1 mm range):
  // repeatability 10 nm (datasheet; quoted with averaging, so a per-sample
  // floor, not an upper bound).
  double displacement_m = 10e-9;
};
ComponentNoise component_noise();
// The force-producing current-noise density [A/sqrt(Hz)] the figures give:
// gain x sqrt(dac^2 + amplifier^2 + sense^2).
double component_current_noise_density_A_per_rtHz(const ComponentNoise& n, double gain_A_per_V);

}  // namespace maglev::hil
