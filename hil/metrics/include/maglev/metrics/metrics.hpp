// Metrics of the HIL bench, in their own module so the report and the tests
// compute every number the same way. Host-only; plain doubles in SI units.
//
// Definitions follow the papers where they define a quantity:
//  * step metrics (overshoot, rise/peak/2%-settling time): paper 000 Fig. 7,
//    classical definitions, stated per function below;
//  * CCQ: paper 003 Section 3.3, CCQ = t_p * (p-p perturbation / primary
//    displacement), units from its Table 3;
//  * loop margins from a frequency response measured on the running loop.
#pragma once

#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace maglev::metrics {

// Root-mean-square about the mean (the "rms noise" of paper 000 Fig. 7(a)).
double rms_about_mean(std::span<const double> v);
// Root-mean-square about a given value (tracking error about zero, etc.).
double rms_about(std::span<const double> v, double reference);
double peak_to_peak(std::span<const double> v);
double max_abs(std::span<const double> v);
double mean(std::span<const double> v);
// Boxcar (moving) average over n samples, "valid" part only (size - n + 1
// values). Used for the in-band noise: a 25-sample (10 ms at 2.5 kHz) average
// has an equivalent noise bandwidth of 1/(2 * 10 ms) = 50 Hz, so it shows the
// noise a ~25-50 Hz loop can resolve, without the sensors' white noise above.
std::vector<double> moving_average(std::span<const double> v, std::size_t n);

// Indices [first, last) of the samples with t in [t_begin, t_end).
struct Window {
  std::size_t first;
  std::size_t last;
  [[nodiscard]] std::size_t size() const { return last - first; }
};
Window window(std::span<const double> t_s, double t_begin_s, double t_end_s);
std::span<const double> slice(std::span<const double> v, Window w);

struct StepMetrics {
  double initial_value;      // mean over the pre-step window
  double final_value;        // mean over the last 10% of the analysis window
  double step_size;          // commanded: target - initial
  double overshoot_percent;  // max excursion beyond final_value, % of |step|; >= 0
  double rise_time_s;        // 10% -> 90% of the step
  double peak_time_s;        // from the step command to the peak (see .cpp)
  double settling_time_s;    // last entry into the +-2% band of |step| around final_value
  bool rise_found;
  bool settled;              // response stays inside the 2% band by the window end
};

// y sampled at t; the step is commanded at t_step_s from `initial` to
// `target`; analysis runs to t_end_s. `pre_window_s` before the step
// gives the initial value. The settling band is band_fraction (2%) of
// |target - initial|.
StepMetrics analyze_step(std::span<const double> t_s, std::span<const double> y,
                         double t_step_s, double t_end_s, double target,
                         double pre_window_s = 0.05, double band_fraction = 0.02);

// Ensemble average of repeated steps, each turned into the direction of its
// own step and measured from its own pre-step level. A 10 nm step sits 3-4x
// above the 3 nm rms noise (paper 000 Fig. 7(a)): one response's overshoot
// and settling are the noise's; the average of N responses has 1/sqrt(N) of
// the noise (uncorrelated between steps) and keeps the loop's response.
struct AveragedStep {
  std::vector<double> t_s;       // from the step command (negative: before it), uniform
  std::vector<double> y;         // mean of sign * (y - pre-step level): 0 before, ~|step| after
  std::vector<double> measured;  // each step's own plateau (last 20% of its window) above its level
  std::size_t count = 0;
};
// Steps at step_times_s (sign: +1/-1 each), sampled uniformly at t_s; pre_s
// before each step gives its level, post_s after it is averaged. Steps whose
// window leaves the samples are skipped.
AveragedStep average_steps(std::span<const double> t_s, std::span<const double> y,
                           std::span<const double> step_times_s, std::span<const double> signs,
                           double pre_s, double post_s);

enum class AxisKind { kTranslational, kRotational };

struct Ccq {
  double value;      // SI: s, rad*s/m, m*s/rad
  std::string unit;  // paper 003 Table 3
};

// CCQ = t_p * pp_perturbed / |primary_displacement| (paper 003 Sec. 3.3).
Ccq cross_coupling_quantity(double peak_time_s, double perturbed_peak_to_peak,
                            double primary_displacement, AxisKind primary,
                            AxisKind perturbed);
std::string ccq_unit(AxisKind primary, AxisKind perturbed);

// Complex response of `output` relative to `input` at each frequency, by
// correlation with sin/cos over the largest whole number of periods that
// fits the samples (uniform sampling at fs_Hz assumed). Exact for sinusoids
// whose period fits a whole number of times; multisines with frequencies on
// the grid k/T_record are separated exactly.
std::vector<std::complex<double>> frequency_response(std::span<const double> input,
                                                     std::span<const double> output,
                                                     double fs_Hz,
                                                     std::span<const double> freqs_Hz);

// H1 estimate over consecutive whole segments of `segment` samples (one
// period of a periodic excitation): per segment the DFT X_s, Y_s of input and
// output at each frequency, then H = sum Y X* / sum |X|^2 and the coherence
// gamma^2 = |sum Y X*|^2 / (sum |X|^2 sum |Y|^2) (1: output fully explained by
// the input; needs >= 2 segments to mean anything).
struct FrfPoint {
  std::complex<double> h;
  double coherence;
};
std::vector<FrfPoint> frequency_response_segments(std::span<const double> input, std::span<const double> output,
                                                  double fs_Hz, std::span<const double> freqs_Hz,
                                                  std::size_t segment);

struct LoopMargins {
  double crossover_Hz;        // |L| = 1 (first crossing from above, log-interpolated)
  double phase_margin_deg;    // 180 + angle(L) at crossover
  double closed_loop_bandwidth_Hz;  // |T| = L/(1+L) first falls below -3 dB
  double closed_loop_peak_dB;       // max |T|
  double closed_loop_peak_Hz;
  bool crossover_found;
  bool bandwidth_found;
  // Gain margin: -20 log10 |L| where angle(L) crosses -180 deg (either way;
  // the crossing nearest the crossover). Negative: a lower gain margin (a
  // conditionally stable loop goes unstable if its gain drops by that much).
  double phase_crossover_Hz = 0.0;
  double gain_margin_dB = 0.0;
  bool gain_margin_found = false;
};

// From open-loop samples L(j w_k) at increasing frequencies.
LoopMargins loop_margins(std::span<const double> freqs_Hz,
                         std::span<const std::complex<double>> open_loop);

}  // namespace maglev::metrics
