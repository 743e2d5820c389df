// Test helpers: gain/phase by correlation over whole periods, and an exact
// ZOH simulation of one paper-000 axis.
#pragma once

#include <cmath>
#include <complex>

namespace loops_test {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kFs = 2500.0;
inline constexpr double kT = 1.0 / kFs;

// Drives tick(x) with x_k = amp sin(w k T) for settle + n ticks and returns
// the complex gain at w from the last n ticks (n T must span whole periods;
// any constant offset in the output cancels).
template <typename Tick>
std::complex<double> measure_gain(Tick&& tick, double f_Hz, double amp, int settle, int n) {
  const double w = 2.0 * kPi * f_Hz;
  double s_acc = 0.0, c_acc = 0.0;
  for (int k = 0; k < settle + n; ++k) {
    const double ph = w * k * kT;
    const double y = tick(amp * std::sin(ph));
    if (k >= settle) {
      s_acc += y * std::sin(ph);
      c_acc += y * std::cos(ph);
    }
  }
  return std::complex<double>(s_acc, c_acc) * (2.0 / (n * amp));
}

inline double phase_deg(std::complex<double> z) { return std::arg(z) * 180.0 / kPi; }
inline double rel_err(std::complex<double> a, std::complex<double> b) { return std::abs(a - b) / std::abs(b); }

// y'' + c y' + k y = g u with u held over each tick, integrated exactly
// enough (RK4 with 8 substeps; the double integrator case is exact).
struct AxisSim {
  double g, c, k;
  double y = 0.0, v = 0.0;
  void step(double u) {
    if (c == 0.0 && k == 0.0) {
      const double a = g * u;
      y += v * kT + 0.5 * a * kT * kT;
      v += a * kT;
      return;
    }
    const double h = kT / 8.0;
    for (int i = 0; i < 8; ++i) {
      auto acc = [&](double yy, double vv) { return g * u - c * vv - k * yy; };
      const double k1y = v, k1v = acc(y, v);
      const double k2y = v + 0.5 * h * k1v, k2v = acc(y + 0.5 * h * k1y, v + 0.5 * h * k1v);
      const double k3y = v + 0.5 * h * k2v, k3v = acc(y + 0.5 * h * k2y, v + 0.5 * h * k2v);
      const double k4y = v + h * k3v, k4v = acc(y + h * k3y, v + h * k3v);
      y += h / 6.0 * (k1y + 2 * k2y + 2 * k3y + k4y);
      v += h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    }
  }
};

}  // namespace loops_test
