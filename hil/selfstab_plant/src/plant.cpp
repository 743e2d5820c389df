// 6-DOF rotor of paper 001: geometry, wrench from the nonlinear law, RK4,
// docking stop, PSD sensors (see plant.hpp).
#include "maglev/selfstab_plant/plant.hpp"

#include <cmath>
#include <cstddef>

namespace maglev::selfstab_plant {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
using Mat3 = std::array<Vec3, 3>;
using std::size_t;

Vec3 Add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 Scale(const Vec3& a, double k) { return {a[0] * k, a[1] * k, a[2] * k}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 Mul(const Mat3& R, const Vec3& v) { return {Dot(R[0], v), Dot(R[1], v), Dot(R[2], v)}; }
Vec3 MulT(const Mat3& R, const Vec3& v) {
  return {R[0][0] * v[0] + R[1][0] * v[1] + R[2][0] * v[2], R[0][1] * v[0] + R[1][1] * v[1] + R[2][1] * v[2],
          R[0][2] * v[0] + R[1][2] * v[1] + R[2][2] * v[2]};
}

// Fixed angles X-Y-Z (the paper's "fixed angle criterion"): R = Rz Ry Rx.
Mat3 Rotation(double a, double b, double g) {
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
  const double cg = std::cos(g), sg = std::sin(g);
  return Mat3{{{cg * cb, cg * sb * sa - sg * ca, cg * sb * ca + sg * sa},
               {sg * cb, sg * sb * sa + cg * ca, sg * sb * ca - cg * sa},
               {-sb, cb * sa, cb * ca}}};
}

const SolenoidParams& Solenoid(const StageParams& p, int coil) {
  return IsOutOfPlane(coil) ? p.out_of_plane : p.in_plane;
}

Pose PoseOf(const State& x) { return {x[0], x[1], x[2], x[3], x[4], x[5]}; }

// Solves A x = b (n = 6) by Gaussian elimination with partial pivoting.
bool Solve6(std::array<std::array<double, 6>, 6> A, std::array<double, 6> b, std::array<double, 6>* x) {
  for (size_t c = 0; c < 6; ++c) {
    size_t piv = c;
    for (size_t r = c + 1; r < 6; ++r)
      if (std::fabs(A[r][c]) > std::fabs(A[piv][c])) piv = r;
    if (std::fabs(A[piv][c]) < 1e-300) return false;
    std::swap(A[c], A[piv]);
    std::swap(b[c], b[piv]);
    for (size_t r = c + 1; r < 6; ++r) {
      const double f = A[r][c] / A[c][c];
      for (size_t k = c; k < 6; ++k) A[r][k] -= f * A[c][k];
      b[r] -= f * b[c];
    }
  }
  for (size_t c = 6; c-- > 0;) {
    double s = b[c];
    for (size_t k = c + 1; k < 6; ++k) s -= A[c][k] * (*x)[k];
    (*x)[c] = s / A[c][c];
  }
  return true;
}

}  // namespace

CoilGeometry Geometry(const StageParams& p, int coil) {
  CoilGeometry g{};
  if (IsOutOfPlane(coil)) {
    // A at 90 deg, B at 210, C at 330: gives alpha ~ (I_A - I_B/2 - I_C/2)
    // and beta ~ (I_B - I_C) with the signs of (11).
    const double th = (90.0 + 120.0 * coil) * kDeg;
    g.magnet_body_m = {p.r1_m * std::cos(th), p.r1_m * std::sin(th), 0.0};
    g.axis = {0.0, 0.0, 1.0};
    g.coil_centre_m = Sub(g.magnet_body_m, Scale(g.axis, p.out_of_plane.nominal_position_m));
    return g;
  }
  // Frames D at 150 deg, E at 270, F at 30; axis along the clockwise tangent
  // t = (sin phi, -cos phi): x gain (1/2)(dm-dn) - (em-en) ..., y gain
  // (sqrt3/2)((dm-dn) - (fm-fn)) and gamma gain -r2 k_ipi as in (11).
  const int k = coil - kDm;
  const int frame = k / 2;
  const bool n_coil = (k % 2) == 1;
  const double phi = (150.0 + 120.0 * frame) * kDeg;
  const Vec3 rhat{std::cos(phi), std::sin(phi), 0.0};
  const Vec3 t{std::sin(phi), -std::cos(phi), 0.0};
  const double sign = n_coil ? -1.0 : 1.0;
  g.magnet_body_m = Add(Scale(rhat, p.r2_m), Scale(t, sign * p.L_m));
  g.axis = Scale(t, sign);  // m pushes its magnet along +t, n along -t: outward
  g.coil_centre_m = Sub(g.magnet_body_m, Scale(g.axis, p.in_plane.nominal_position_m));
  return g;
}

CoilVector NominalCurrents(const StageParams& p) {
  CoilVector i{};
  for (size_t j = 0; j < kCoils; ++j)
    i[j] = IsOutOfPlane(static_cast<int>(j)) ? p.out_of_plane.nominal_current_A : p.in_plane.nominal_current_A;
  return i;
}

CoilVector NominalVoltages(const StageParams& p) {
  CoilVector u = NominalCurrents(p);
  for (double& v : u) v *= p.coil.resistance_R_ohm;
  return u;
}

State NominalState(const StageParams& p) {
  State x{};
  const CoilVector i = NominalCurrents(p);
  for (size_t j = 0; j < kCoils; ++j) x[12 + j] = i[j];
  return x;
}

Wrench ComputeWrench(const StageParams& p, const Pose& pose, const std::array<double, 6>& vel,
                     const CoilVector& cur) {
  Wrench w;
  const Mat3 R = Rotation(pose[3], pose[4], pose[5]);
  const Vec3 c{pose[0], pose[1], pose[2]};
  const Vec3 v{vel[0], vel[1], vel[2]};
  const Vec3 om{vel[3], vel[4], vel[5]};
  const double m = p.magnet.moment_A_m2();
  const double kappa = p.model.radial_to_axial_ratio_kappa;
  for (size_t j = 0; j < kCoils; ++j) {
    const int coil = static_cast<int>(j);
    const CoilGeometry g = Geometry(p, coil);
    const Vec3 arm = Mul(R, g.magnet_body_m);
    const Vec3 P = Add(c, arm);
    const Vec3 d = Sub(P, g.coil_centre_m);
    const double s = Dot(g.axis, d);
    const Vec3 rho_vec = Sub(d, Scale(g.axis, s));
    const double rho = std::sqrt(Dot(rho_vec, rho_vec));
    const PairInteraction pi = ComputePair(Solenoid(p, coil), m, kappa, s, rho);
    // grad(lambda): the axial part and the radial part (rho_vec carries rho).
    const Vec3 g_ax = Scale(g.axis, pi.dlambda_ds_Wb_per_m);
    const Vec3 g_rad = Scale(rho_vec, pi.dlambda_drho_over_rho_Wb_per_m2);
    const Vec3 vP = Add(v, Cross(om, arm));
    w.emf_V[j] = Dot(g_ax, vP) + Dot(g_rad, vP);
    w.flux_linkage_Wb[j] = pi.flux_linkage_Wb;
    const Vec3 F_ax = Scale(g_ax, cur[j]);
    const Vec3 F_rad = Scale(g_rad, cur[j]);
    w.force_N = Add(w.force_N, Add(F_ax, F_rad));
    if (p.model.prestress_lever) {
      // Full rigid-body mechanics: every force acts at the magnet.
      w.torque_N_m = Add(w.torque_N_m, Cross(arm, Add(F_ax, F_rad)));
    } else {
      // (11)'s virtual springs: the force the coil exerts at the nominal pose
      // with this current, F0 = i k_i(s0) a, acts at the magnet's NOMINAL
      // lever; only the change F - F0 acts at the actual magnet. The
      // linearization then has no prestress (geometric) stiffness, as (11).
      const Vec3 F0 = Scale(g.axis, -cur[j] * m * FieldGradient_T_per_A_m(Solenoid(p, coil),
                                                                         Solenoid(p, coil).nominal_position_m));
      const Vec3 dF = Sub(Add(F_ax, F_rad), F0);
      w.torque_N_m = Add(w.torque_N_m, Add(Cross(arm, dF), Cross(g.magnet_body_m, F0)));
    }
    if (p.model.dipole_torque) {
      // Eq (2), T = m x B, with the near-axis harmonic field
      // B = i (b a - (1/2) b' rho_vec); the moment is anti-parallel to the axis.
      const Vec3 mvec = Scale(Mul(R, g.axis), -m);
      const Vec3 B = Scale(Sub(Scale(g.axis, pi.field_axial_T_per_A),
                               Scale(rho_vec, 0.5 * pi.field_gradient_T_per_A_m)),
                           cur[j]);
      w.torque_N_m = Add(w.torque_N_m, Cross(mvec, B));
    }
  }
  w.force_N[2] -= p.mass_kg * p.gravity_m_per_s2;
  return w;
}

CoilVector QuasiStaticCurrents(const StageParams& p, const Pose& pose, const std::array<double, 6>& vel,
                               const CoilVector& u) {
  const Wrench w = ComputeWrench(p, pose, vel, CoilVector{});
  CoilVector i{};
  for (size_t j = 0; j < kCoils; ++j) i[j] = (u[j] - w.emf_V[j]) / p.coil.resistance_R_ohm;
  return i;
}

namespace {
// Body-frame angular acceleration from a stator-frame torque (Euler).
Vec3 AngularAccelBody(const StageParams& p, const Mat3& R, const Vec3& torque_s, const Vec3& om_b) {
  const Vec3 tb = MulT(R, torque_s);
  const Vec3 I{p.inertia_xx_kg_m2, p.inertia_yy_kg_m2, p.inertia_zz_kg_m2};
  const Vec3 Iw{I[0] * om_b[0], I[1] * om_b[1], I[2] * om_b[2]};
  const Vec3 gyro = Cross(om_b, Iw);
  return {(tb[0] - gyro[0]) / I[0], (tb[1] - gyro[1]) / I[1], (tb[2] - gyro[2]) / I[2]};
}
}  // namespace

std::array<double, 6> Accelerations(const StageParams& p, const Pose& pose, const std::array<double, 6>& vel,
                                    const CoilVector& cur) {
  const Wrench w = ComputeWrench(p, pose, vel, cur);
  const Mat3 R = Rotation(pose[3], pose[4], pose[5]);
  const Vec3 om_b = MulT(R, Vec3{vel[3], vel[4], vel[5]});
  const Vec3 dom_s = Mul(R, AngularAccelBody(p, R, w.torque_N_m, om_b));
  return {w.force_N[0] / p.mass_kg, w.force_N[1] / p.mass_kg, w.force_N[2] / p.mass_kg,
          dom_s[0], dom_s[1], dom_s[2]};
}

State Derivative(const StageParams& p, const State& x, const CoilVector& u, CoilDrive drive) {
  const Pose pose = PoseOf(x);
  const Mat3 R = Rotation(pose[3], pose[4], pose[5]);
  const Vec3 om_b{x[9], x[10], x[11]};
  const Vec3 om_s = Mul(R, om_b);
  const std::array<double, 6> vel{x[6], x[7], x[8], om_s[0], om_s[1], om_s[2]};
  const bool dynamic_coils = drive == CoilDrive::kVoltage && p.coil.inductance_L_H > 0.0;
  CoilVector cur{};
  if (drive == CoilDrive::kCurrent) {
    cur = u;
  } else if (dynamic_coils) {
    for (size_t j = 0; j < kCoils; ++j) cur[j] = x[12 + j];
  } else {
    cur = QuasiStaticCurrents(p, pose, vel, u);
  }
  const Wrench w = ComputeWrench(p, pose, vel, cur);
  State dx{};
  dx[0] = x[6];
  dx[1] = x[7];
  dx[2] = x[8];
  // Fixed-angle rates from the stator-frame angular velocity:
  // omega_s = a' Rz Ry x + b' Rz y + g' z.
  const double cb = std::cos(pose[4]), sb = std::sin(pose[4]);
  const double cg = std::cos(pose[5]), sg = std::sin(pose[5]);
  dx[3] = (cg * om_s[0] + sg * om_s[1]) / cb;
  dx[4] = -sg * om_s[0] + cg * om_s[1];
  dx[5] = om_s[2] + dx[3] * sb;
  for (size_t k = 0; k < 3; ++k) dx[6 + k] = w.force_N[k] / p.mass_kg;
  const Vec3 dom = AngularAccelBody(p, R, w.torque_N_m, om_b);
  for (size_t k = 0; k < 3; ++k) dx[9 + k] = dom[k];
  if (dynamic_coils) {
    for (size_t j = 0; j < kCoils; ++j)
      dx[12 + j] = (u[j] - p.coil.resistance_R_ohm * cur[j] - w.emf_V[j]) / p.coil.inductance_L_H;
  }
  return dx;
}

bool FindEquilibrium(const StageParams& p, const CoilVector& cur, Pose* pose) {
  const std::array<double, 6> zero{};
  for (int it = 0; it < 40; ++it) {
    const std::array<double, 6> f = Accelerations(p, *pose, zero, cur);
    std::array<std::array<double, 6>, 6> J{};
    const double h = 1e-7;
    for (size_t k = 0; k < 6; ++k) {
      Pose a = *pose, b = *pose;
      a[k] += h;
      b[k] -= h;
      const auto fa = Accelerations(p, a, zero, cur);
      const auto fb = Accelerations(p, b, zero, cur);
      for (size_t r = 0; r < 6; ++r) J[r][k] = (fa[r] - fb[r]) / (2 * h);
    }
    std::array<double, 6> rhs{}, step{};
    for (size_t r = 0; r < 6; ++r) rhs[r] = -f[r];
    if (!Solve6(J, rhs, &step)) return false;
    double norm = 0;
    for (size_t k = 0; k < 6; ++k) {
      (*pose)[k] += step[k];
      norm = std::fmax(norm, std::fabs(step[k]));
    }
    if (norm < 1e-13) return true;
  }
  return false;
}

PsdReading MeasurePsd(const StageParams& p, const Pose& pose, bool quantize) {
  PsdReading y{};
  const Mat3 R = Rotation(pose[3], pose[4], pose[5]);
  const Vec3 c{pose[0], pose[1], pose[2]};
  const double lsb = p.psd.lsb_m();
  const double half = 0.5 * p.psd.range_m;
  for (size_t k = 0; k < 3; ++k) {
    const double psi = p.psd.first_angle_rad + 120.0 * kDeg * static_cast<double>(k);
    const Vec3 n{std::cos(psi), std::sin(psi), 0.0};
    const Vec3 t{-std::sin(psi), std::cos(psi), 0.0};
    const Vec3 dir = Mul(R, n);
    const Vec3 o = Add(c, Scale(dir, p.psd.led_radius_m));
    const double lam = (p.psd.ring_radius_m - Dot(n, o)) / Dot(n, dir);
    const Vec3 spot = Add(o, Scale(dir, lam));
    y[2 * k] = Dot(t, spot);
    y[2 * k + 1] = spot[2];
  }
  if (quantize) {
    for (double& v : y) v = std::fmin(half, std::fmax(-half, std::round(v / lsb) * lsb));
  }
  return y;
}

Pose PoseFromPsd(const StageParams& p, const PsdReading& y) {
  std::array<std::array<double, 6>, 6> J{};
  const double h = 1e-7;
  for (size_t k = 0; k < 6; ++k) {
    Pose a{}, b{};
    a[k] = h;
    b[k] = -h;
    const PsdReading ya = MeasurePsd(p, a, false), yb = MeasurePsd(p, b, false);
    for (size_t r = 0; r < 6; ++r) J[r][k] = (ya[r] - yb[r]) / (2 * h);
  }
  Pose pose{};
  std::array<double, 6> rhs{};
  for (size_t r = 0; r < 6; ++r) rhs[r] = y[r];
  Solve6(J, rhs, &pose);
  return pose;
}

Plant::Plant(const StageParams& p, CoilDrive drive, double max_substep_s)
    : p_(p), drive_(drive), max_substep_s_(max_substep_s) {
  x_ = NominalState(p_);
}

void Plant::Reset(const State& x0) {
  x_ = x0;
  docked_ = false;
}

void Plant::ResetDocked() {
  x_ = State{};
  x_[2] = p_.dock_z_m;
  docked_ = true;
}

Pose Plant::pose() const { return PoseOf(x_); }

void Plant::ApplyDock(const CoilVector& u) {
  // A hard stop that also holds x, y and the angles (the docking mechanism
  // "guarantees the repeatable initial position and rest position").
  if (x_[2] > p_.dock_z_m) {
    docked_ = false;
    return;
  }
  for (size_t k = 0; k < 12; ++k) x_[k] = 0.0;
  x_[2] = p_.dock_z_m;
  docked_ = true;
  if (drive_ == CoilDrive::kVoltage && !(p_.coil.inductance_L_H > 0.0)) {
    const CoilVector i = QuasiStaticCurrents(p_, PoseOf(x_), {}, u);
    for (size_t j = 0; j < kCoils; ++j) x_[12 + j] = i[j];
  }
}

void Plant::Step(const CoilVector& u, double dt_s) {
  const int n = static_cast<int>(std::ceil(dt_s / max_substep_s_ - 1e-9));
  const double h = dt_s / (n > 0 ? n : 1);
  for (int s = 0; s < (n > 0 ? n : 1); ++s) {
    const State k1 = Derivative(p_, x_, u, drive_);
    State t{};
    for (size_t i = 0; i < kStateSize; ++i) t[i] = x_[i] + 0.5 * h * k1[i];
    const State k2 = Derivative(p_, t, u, drive_);
    for (size_t i = 0; i < kStateSize; ++i) t[i] = x_[i] + 0.5 * h * k2[i];
    const State k3 = Derivative(p_, t, u, drive_);
    for (size_t i = 0; i < kStateSize; ++i) t[i] = x_[i] + h * k3[i];
    const State k4 = Derivative(p_, t, u, drive_);
    for (size_t i = 0; i < kStateSize; ++i) x_[i] += h / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    if (drive_ == CoilDrive::kCurrent) {
      for (size_t j = 0; j < kCoils; ++j) x_[12 + j] = u[j];
    } else if (!(p_.coil.inductance_L_H > 0.0)) {
      const Mat3 R = Rotation(x_[3], x_[4], x_[5]);
      const Vec3 om_s = Mul(R, Vec3{x_[9], x_[10], x_[11]});
      const CoilVector i = QuasiStaticCurrents(p_, PoseOf(x_), {x_[6], x_[7], x_[8], om_s[0], om_s[1], om_s[2]}, u);
      for (size_t j = 0; j < kCoils; ++j) x_[12 + j] = i[j];
    }
    ApplyDock(u);
  }
}

}  // namespace maglev::selfstab_plant
