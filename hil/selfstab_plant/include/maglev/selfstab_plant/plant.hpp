#pragma once
// 6-DOF rigid rotor of paper 001 over nine coils, integrated by RK4.
//
// Pose (x, y, z, alpha, beta, gamma) of the rotor (origin = centre of mass)
// in the stator frame, fixed angles: R = Rz(gamma) Ry(beta) Rx(alpha).
// State (0-based): [0..5] pose, [6..8] velocity [m/s], [9..11] angular
// velocity in the BODY frame [rad/s], [12..20] the nine coil currents [A].
//
// Coils are VOLTAGE-driven (eq (7)): L di/dt = u - R i - d(lambda)/dt. The
// passive damping of (13) is this back-emf and exists only so (docs). With
// L = 0 the currents follow u = R i + e algebraically. CoilDrive::kCurrent
// models an ideal current amplifier instead (i = command): no damping.
// Forces come from the nonlinear law of force_law.hpp at the actual pose.
#include <array>

#include "maglev/selfstab_plant/force_law.hpp"
#include "maglev/selfstab_plant/params.hpp"

namespace maglev::selfstab_plant {

inline constexpr int kStateSize = 21;
using State = std::array<double, kStateSize>;
using CoilVector = std::array<double, kCoils>;
using Vec3 = std::array<double, 3>;
using Pose = std::array<double, 6>;

enum class CoilDrive { kVoltage, kCurrent };

// Geometry of coil j at the nominal pose (ours, from the signs of (11)).
struct CoilGeometry {
  Vec3 coil_centre_m;   // mid-plane centre, stator frame
  Vec3 axis;            // unit; the force on the magnet is along +axis
  Vec3 magnet_body_m;   // magnet centre, rotor body frame
};
CoilGeometry Geometry(const StageParams& p, int coil);

// Nominal currents (0.535 A out-of-plane, 0.4273 A in-plane) and the
// voltages R i that hold them at rest.
CoilVector NominalCurrents(const StageParams& p);
CoilVector NominalVoltages(const StageParams& p);
// The Table 2 nominal point: pose 0, at rest, nominal currents.
State NominalState(const StageParams& p);

// Net force (stator frame) and torque about the centre of mass (stator
// frame) from the coils and gravity, and the back-emf of each coil.
struct Wrench {
  Vec3 force_N{};
  Vec3 torque_N_m{};
  CoilVector emf_V{};
  CoilVector flux_linkage_Wb{};
};
// velocity6 = [v (stator frame), omega (stator frame)].
Wrench ComputeWrench(const StageParams& p, const Pose& pose, const std::array<double, 6>& velocity6,
                     const CoilVector& currents_A);
// Currents of voltage-driven coils with L = 0: i = (u - e) / R.
CoilVector QuasiStaticCurrents(const StageParams& p, const Pose& pose,
                               const std::array<double, 6>& velocity6, const CoilVector& voltages_V);

// Right-hand side. u: voltages (kVoltage) or currents (kCurrent).
State Derivative(const StageParams& p, const State& x, const CoilVector& u, CoilDrive drive);

// Generalized acceleration [a (stator), d(omega_s)/dt] at zero angular
// velocity-product terms; used by the linearization.
std::array<double, 6> Accelerations(const StageParams& p, const Pose& pose,
                                    const std::array<double, 6>& velocity6, const CoilVector& currents_A);

// Static equilibrium near `guess` with the given currents (Newton on the
// six accelerations, numerical Jacobian). Returns false if it did not converge.
bool FindEquilibrium(const StageParams& p, const CoilVector& currents_A, Pose* pose);

// PSD spot coordinates: per sensor (tangential, vertical) [m], exact
// line-plane intersection of the rotor's radial beam with the PSD plane,
// quantized to the A/D count and clamped to the +-range/2 active area.
using PsdReading = std::array<double, 6>;
PsdReading MeasurePsd(const StageParams& p, const Pose& pose, bool quantize = true);
// Kinematic transform R of Fig. 8: pose from the six spot coordinates
// (linear, the Jacobian of MeasurePsd at the nominal pose inverted).
Pose PoseFromPsd(const StageParams& p, const PsdReading& y);

class Plant {
 public:
  explicit Plant(const StageParams& p, CoilDrive drive = CoilDrive::kVoltage,
                 double max_substep_s = 20e-6);

  void Reset(const State& x0);
  // Unpowered at rest on the docking stop.
  void ResetDocked();
  const State& state() const { return x_; }
  Pose pose() const;
  const StageParams& params() const { return p_; }
  bool docked() const { return docked_; }

  // Holds u (voltages or currents, by drive) for dt_s and advances the state
  // by RK4 substeps of at most max_substep_s (the coil time constant L/R is
  // ~0.1 ms). The docking stop holds the rotor while the coils do not lift it.
  void Step(const CoilVector& u, double dt_s);

  PsdReading Measure() const { return MeasurePsd(p_, pose()); }

 private:
  void ApplyDock(const CoilVector& u);
  StageParams p_;
  CoilDrive drive_;
  double max_substep_s_;
  State x_{};
  bool docked_ = false;
};

}  // namespace maglev::selfstab_plant
