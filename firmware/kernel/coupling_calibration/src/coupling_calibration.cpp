#include "maglev/coupling_calibration/coupling_calibration.hpp"

#include <cmath>

#include "maglev/numeric/scalar_traits.hpp"

namespace maglev::kernel {

MAGLEV_ENUM_TO_STRING(CouplingCalibrationResult, MAGLEV_COUPLING_CALIBRATION_RESULTS)

namespace {

constexpr int kN = kAxisCount;

Cf mul(Cf a, Cf b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }

Cf div(Cf a, Cf b) {
  const float d = b.re * b.re + b.im * b.im;
  return {(a.re * b.re + a.im * b.im) / d, (a.im * b.re - a.re * b.im) / d};
}

float max_abs_entry(const float* a, int count) {
  float m = 0.0f;
  for (int i = 0; i < count; ++i) m = std::fmax(m, std::fabs(a[i]));
  return m;
}

// ||A||_1 of the scaled matrix A~_ij = A_ij r_j / r_i.
float scaled_norm1(const float a[kCouplingMatrixSize], const float r[kN]) {
  float n = 0.0f;
  for (int j = 0; j < kN; ++j) {
    float col = 0.0f;
    for (int i = 0; i < kN; ++i) col += std::fabs(a[i * kN + j] * r[j] / r[i]);
    n = std::fmax(n, col);
  }
  return n;
}

}  // namespace

bool invert_matrix(float* a, int n, float tiny) {
  constexpr int kMax = 12;
  if (n < 1 || n > kMax) return false;
  int perm[kMax];
  for (int i = 0; i < n; ++i) perm[i] = i;
  const float scale = max_abs_entry(a, n * n);
  if (!(scale > 0.0f) || !std::isfinite(scale)) return false;
  // In-place Gauss-Jordan (column pivoting by row swaps, recorded in perm).
  for (int c = 0; c < n; ++c) {
    int p = c;
    for (int r = c + 1; r < n; ++r) {
      if (std::fabs(a[r * n + c]) > std::fabs(a[p * n + c])) p = r;
    }
    const float pivot = a[p * n + c];
    if (!(std::fabs(pivot) > tiny * scale) || !std::isfinite(pivot)) return false;
    if (p != c) {
      for (int k = 0; k < n; ++k) {
        const float t = a[c * n + k];
        a[c * n + k] = a[p * n + k];
        a[p * n + k] = t;
      }
      const int t = perm[c];
      perm[c] = perm[p];
      perm[p] = t;
    }
    const float inv = 1.0f / pivot;
    a[c * n + c] = 1.0f;
    for (int k = 0; k < n; ++k) a[c * n + k] *= inv;
    for (int r = 0; r < n; ++r) {
      if (r == c) continue;
      const float f = a[r * n + c];
      a[r * n + c] = 0.0f;
      for (int k = 0; k < n; ++k) a[r * n + k] -= f * a[c * n + k];
    }
  }
  // Rows were swapped: the inverse's columns come back in the original order.
  float col[kMax];
  for (int r = 0; r < n; ++r) {
    for (int k = 0; k < n; ++k) col[perm[k]] = a[r * n + k];
    for (int k = 0; k < n; ++k) a[r * n + k] = col[k];
  }
  for (int i = 0; i < n * n; ++i) {
    if (!std::isfinite(a[i])) return false;
  }
  return true;
}

void CouplingIdentifier::reset() { *this = CouplingIdentifier{}; }

void CouplingIdentifier::accumulate(std::uint32_t phase, const float u[kN], const float y[kN]) {
  for (int k = 0; k < kCouplingLines; ++k) {
    // e^{-j w t}: (cos, -sin), the kernel's sine table (bit-identical host / target).
    const auto sc = numeric::ScalarTraits<float>::sin_cos(phase * static_cast<std::uint32_t>(k + 1));
    for (int a = 0; a < kN; ++a) {
      acc_u_[k][a].re += u[a] * sc.cos;
      acc_u_[k][a].im -= u[a] * sc.sin;
      acc_y_[k][a].re += y[a] * sc.cos;
      acc_y_[k][a].im -= y[a] * sc.sin;
    }
  }
}

void CouplingIdentifier::finish_experiment(int j) {
  if (j < 0 || j >= kN) return;
  for (int k = 0; k < kCouplingLines; ++k) {
    for (int a = 0; a < kN; ++a) {
      u_[k][a][j] = acc_u_[k][a];
      y_[k][a][j] = acc_y_[k][a];
      acc_u_[k][a] = Cf{};
      acc_y_[k][a] = Cf{};
    }
  }
}

CouplingCalibrationResult CouplingIdentifier::solve(const float radius_m[kN], float r_out[kCouplingMatrixSize],
                                                    float* coupling, float* inconsistency) const {
  float big[4 * kCouplingMatrixSize];  // 12 x 12 real form of U
  float r_line[kCouplingLines][kCouplingMatrixSize];
  for (int k = 0; k < kCouplingLines; ++k) {
    // U^-1 through the real form [[Ur, -Ui], [Ui, Ur]] (its inverse has the same form).
    constexpr int n2 = 2 * kN;
    for (int i = 0; i < kN; ++i) {
      for (int j = 0; j < kN; ++j) {
        const Cf u = u_[k][i][j];
        big[i * n2 + j] = u.re;
        big[i * n2 + j + kN] = -u.im;
        big[(i + kN) * n2 + j] = u.im;
        big[(i + kN) * n2 + j + kN] = u.re;
      }
    }
    if (!invert_matrix(big, n2)) return CouplingCalibrationResult::kFailedSingular;
    // G = Y U^-1, then R_k = diag(G)^-1 G (real part: the mixing is static).
    Cf g[kN][kN];
    for (int i = 0; i < kN; ++i) {
      for (int j = 0; j < kN; ++j) {
        Cf s{};
        for (int m = 0; m < kN; ++m) {
          const Cf inv{big[m * n2 + j], big[(m + kN) * n2 + j]};
          const Cf p = mul(y_[k][i][m], inv);
          s.re += p.re;
          s.im += p.im;
        }
        g[i][j] = s;
      }
    }
    for (int i = 0; i < kN; ++i) {
      const Cf d = g[i][i];
      if (!(d.re * d.re + d.im * d.im > 0.0f)) return CouplingCalibrationResult::kFailedSingular;
      for (int j = 0; j < kN; ++j) r_line[k][i * kN + j] = i == j ? 1.0f : div(g[i][j], d).re;
    }
  }
  float spread = 0.0f;
  for (int e = 0; e < kCouplingMatrixSize; ++e) {
    float s = 0.0f;
    for (int k = 0; k < kCouplingLines; ++k) s += r_line[k][e];
    r_out[e] = s / static_cast<float>(kCouplingLines);
    if (!std::isfinite(r_out[e])) return CouplingCalibrationResult::kFailedNotFinite;
  }
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      for (int k = 0; k < kCouplingLines; ++k) {
        const float d = std::fabs(r_line[k][i * kN + j] - r_out[i * kN + j]) * radius_m[j] / radius_m[i];
        spread = std::fmax(spread, d);
      }
    }
  }
  *coupling = scaled_coupling(r_out, radius_m);
  *inconsistency = spread;
  return CouplingCalibrationResult::kPassed;
}

float scaled_coupling(const float a[kCouplingMatrixSize], const float radius_m[kN]) {
  float m = 0.0f;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      if (i != j) m = std::fmax(m, std::fabs(a[i * kN + j]) * radius_m[j] / radius_m[i]);
    }
  }
  return m;
}

CouplingCalibrationResult correction_from(const float r[kCouplingMatrixSize], const float c_old[kCouplingMatrixSize],
                                          const float radius_m[kN], const CouplingCalibrationConfig& cfg,
                                          float c_new[kCouplingMatrixSize]) {
  float inv[kCouplingMatrixSize];
  for (int e = 0; e < kCouplingMatrixSize; ++e) inv[e] = r[e];
  if (!invert_matrix(inv, kN)) return CouplingCalibrationResult::kFailedSingular;
  const float cond = scaled_norm1(r, radius_m) * scaled_norm1(inv, radius_m);
  if (!std::isfinite(cond)) return CouplingCalibrationResult::kFailedNotFinite;
  if (cond > cfg.max_condition) return CouplingCalibrationResult::kFailedIllConditioned;
  float c[kCouplingMatrixSize];
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      float s = 0.0f;
      for (int m = 0; m < kN; ++m) s += c_old[i * kN + m] * inv[m * kN + j];
      c[i * kN + j] = s;
    }
  }
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      const float d = std::fabs(c[i * kN + j] - (i == j ? 1.0f : 0.0f)) * radius_m[j] / radius_m[i];
      if (!std::isfinite(d)) return CouplingCalibrationResult::kFailedNotFinite;
      if (d > cfg.max_correction) return CouplingCalibrationResult::kFailedCorrectionTooLarge;
    }
  }
  for (int e = 0; e < kCouplingMatrixSize; ++e) c_new[e] = c[e];
  return CouplingCalibrationResult::kPassed;
}

bool correction_valid(const CouplingCorrection& c, const float radius_m[kN]) {
  if (c.enabled > 1 || c.reserved[0] != 0 || c.reserved[1] != 0 || c.reserved[2] != 0) return false;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      const float v = c.matrix[i * kN + j];
      if (!std::isfinite(v)) return false;
      if (std::fabs(v - (i == j ? 1.0f : 0.0f)) * radius_m[j] / radius_m[i] > kMaxCorrectionMagnitude) return false;
    }
  }
  return true;
}

}  // namespace maglev::kernel
