// maglev-lqr-design: designs paper 002's five internal-model regulators by
// LQR (weights derived from the printed poles, see imr_design.hpp) and prints
// weights, gains K_s, closed-loop poles and their discrete images at 1 kHz.
#include <cmath>
#include <cstdio>

#include "maglev/control_design/imr_design.hpp"

int main() {
  using namespace maglev::control_design;
  const ImrPlant plant = BuildImrPlant(kPaperOmega0_rad_per_s);
  int failures = 0;
  for (int i = 0; i < kAxes; ++i) {
    const Axis a = static_cast<Axis>(i);
    const AxisDesign d = DesignPaperAxis(a);
    if (d.error != DesignError::kOk) {
      std::printf("%s: design failed: %s\n", AxisName(a), ToString(d.error));
      ++failures;
      continue;
    }
    std::printf("axis %s  (R = 1, Q = h'h, residual %.2e)\n  diag(Q) =", AxisName(a), d.riccati_residual);
    for (int j = 0; j < 5; ++j) std::printf(" %.6g", d.Q(j, j));
    std::printf("\n  h       =  (profile: lqr_weight_h)");
    for (int j = 0; j < 5; ++j) std::printf(" %.10g", std::sqrt(d.Q(j, j)) * (d.Q(0, j) < 0 ? -1.0 : 1.0));
    std::printf("\n  K_s     =");
    for (double k : d.Ks) std::printf(" %.6g", k);
    std::printf("\n  poles   =");
    for (const auto& p : d.poles) std::printf(" (%.4f%+.4fi)", p.real(), p.imag());
    std::printf("\n  worst relative pole error vs paper: %.3e\n", WorstRelativePoleError(d.poles, PaperPoles(a)));
    const Discrete dz = DiscretizeZoh(plant.A, plant.B, kPaperServoPeriod_s);
    const Eigen::VectorXcd zp = (dz.Ad - dz.Bd * d.K).eigenvalues();
    std::printf("  |z| at 1 kHz (ZOH, continuous gains):");
    for (Eigen::Index j = 0; j < zp.size(); ++j) std::printf(" %.5f", std::abs(zp(j)));
    std::printf("\n");
  }
  return failures == 0 ? 0 : 1;
}
