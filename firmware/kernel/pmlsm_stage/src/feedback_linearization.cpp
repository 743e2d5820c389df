#include "maglev/pmlsm_stage/feedback_linearization.hpp"

namespace maglev::pmlsm_stage {
namespace {

// sin(a) for the guides' tilt range (|a| <= 14 mrad): a - a^3/6 + a^5/120
// leaves < 1e-16 rad, far below float's resolution.
float small_sin(float a) {
  const float a2 = a * a;
  return a * (1.0f - a2 * (1.0f / 6.0f) * (1.0f - a2 * (1.0f / 20.0f)));
}

float lerp(const float* v, int i, float f) { return v[i] + (v[i + 1] - v[i]) * f; }

}  // namespace

GapTerms LookUpGapTerms(const ForceLawTable& t, float gap_m) {
  float s = (gap_m - t.gap0_m) / t.step_m;
  if (!(s > 0.0f)) s = 0.0f;  // also NaN
  const float last = static_cast<float>(kGapTablePoints - 1);
  if (s > last) s = last;
  int i = static_cast<int>(s);
  if (i > kGapTablePoints - 2) i = kGapTablePoints - 2;
  const float f = s - static_cast<float>(i);
  return {lerp(t.attraction_N, i, f), lerp(t.direct_N_per_A, i, f), lerp(t.quadratic_N_per_A2, i, f),
          lerp(t.thrust_N_per_A, i, f)};
}

void AirGaps(const PmlsmKernelConfig& c, const float y[kAxes], float g[kMotors]) {
  const float sphi = c.radius_m * small_sin(y[static_cast<int>(Axis::kPhi)]);
  const float sth = c.radius_m * small_sin(y[static_cast<int>(Axis::kTheta)]);
  const float x1 = y[static_cast<int>(Axis::kGap)];
  g[0] = x1 - sphi;
  g[1] = x1 + sth;
  g[2] = x1 + sphi;
  g[3] = x1 - sth;
}

LinearizedCurrents FeedbackLinearize(const PmlsmKernelConfig& c, const float y[kAxes], const float w[kAxes],
                                     bool rotation_loops) {
  LinearizedCurrents out{};
  float g[kMotors];
  AirGaps(c, y, g);
  GapTerms t[kMotors];
  for (int m = 0; m < kMotors; ++m) t[m] = LookUpGapTerms(c.force, g[m]);
  // (12), horizontal part first: F_H = -K_h L_h i_q; motors 2, 4 move X, 1, 3 Z.
  const float h_x = -(t[1].thrust_N_per_A + t[3].thrust_N_per_A) / c.mass_x_kg;
  const float h_z = -(t[0].thrust_N_per_A + t[2].thrust_N_per_A) / c.mass_z_kg;
  out.u_x_raw_A = w[static_cast<int>(Axis::kX)] / h_x;
  out.u_z_raw_A = w[static_cast<int>(Axis::kZ)] / h_z;
  const float lim = c.horizontal_limit_A;
  out.u_x_A = out.u_x_raw_A > lim ? lim : (out.u_x_raw_A < -lim ? -lim : out.u_x_raw_A);
  out.u_z_A = out.u_z_raw_A > lim ? lim : (out.u_z_raw_A < -lim ? -lim : out.u_z_raw_A);
  if (!(out.u_x_A == out.u_x_A)) out.u_x_A = 0.0f;  // NaN in: nothing out
  if (!(out.u_z_A == out.u_z_A)) out.u_z_A = 0.0f;
  const float iq[kMotors] = {out.u_z_A, out.u_x_A, out.u_z_A, out.u_x_A};
  // Vertical force of each motor at i_d = 0 (the i_q^2 attraction kept, as (11)).
  float F0[kMotors], D[kMotors];
  for (int m = 0; m < kMotors; ++m) {
    F0[m] = -t[m].attraction_N - t[m].quadratic_N_per_A2 * iq[m] * iq[m];
    D[m] = t[m].direct_N_per_A;
  }
  const float My = c.mass_gap_kg, r = c.radius_m;
  const float a1 = c.gravity_m_per_s2 + (F0[0] + F0[1] + F0[2] + F0[3]) / My;
  const float a3 = (D[0] + D[1] + D[2] + D[3]) / (2.0f * My);
  float vy = 0.0f, vphi = 0.0f, vth = 0.0f;
  if (rotation_loops) {
    const float a2 = (D[0] - D[2]) / (2.0f * My);
    const float a7 = (D[3] - D[1]) / (2.0f * My);
    const float b1 = r * (F0[2] - F0[0]) / c.inertia_phi_kgm2 - c.torsion_phi_per_s2 * y[3];
    const float b3 = r * (D[2] - D[0]) / (2.0f * c.inertia_phi_kgm2);
    const float b2 = -r * (D[2] + D[0]) / (2.0f * c.inertia_phi_kgm2);
    const float c1 = r * (F0[1] - F0[3]) / c.inertia_theta_kgm2 - c.torsion_theta_per_s2 * y[4];
    const float c3 = r * (D[1] - D[3]) / (2.0f * c.inertia_theta_kgm2);
    const float c2 = -r * (D[1] + D[3]) / (2.0f * c.inertia_theta_kgm2);
    // [a3 a2 a7; b3 b2 0; c3 0 c2] v = rhs, eliminated in closed form (b2, c2 < 0).
    const float r1 = w[0] - a1, r2 = w[3] - b1, r3 = w[4] - c1;
    vy = (r1 - a2 * r2 / b2 - a7 * r3 / c2) / (a3 - a2 * b3 / b2 - a7 * c3 / c2);
    vphi = (r2 - b3 * vy) / b2;
    vth = (r3 - c3 * vy) / c2;
  } else {
    vy = (w[0] - a1) / a3;
  }
  // (8): u_y1 = (vy + vphi)/2, u_y2 = (vy - vth)/2, u_y3 = (vy - vphi)/2, u_y4 = (vy + vth)/2.
  const float id[kMotors] = {0.5f * (vy + vphi), 0.5f * (vy - vth), 0.5f * (vy - vphi), 0.5f * (vy + vth)};
  for (int m = 0; m < kMotors; ++m) {
    float i = id[m];
    if (c.exact_vertical_inverse && t[m].quadratic_N_per_A2 > 0.0f && D[m] > 0.0f) {
      // (2) with its i_d^2 term: D i - Q i^2 = D i_lin, the root through
      // i_lin -> 0, in the cancellation-free form 2 i_lin / (1 + sqrt(1 - 4 Q i_lin / D)).
      float disc = 1.0f - 4.0f * t[m].quadratic_N_per_A2 * i / D[m];
      if (disc < 0.0f) disc = 0.0f;  // beyond the force the motor can give: its maximum
      i = 2.0f * i / (1.0f + __builtin_sqrtf(disc));
    }
    out.i_d_A[m] = (i == i) ? i : 0.0f;
    out.i_q_A[m] = iq[m];
  }
  return out;
}

}  // namespace maglev::pmlsm_stage
