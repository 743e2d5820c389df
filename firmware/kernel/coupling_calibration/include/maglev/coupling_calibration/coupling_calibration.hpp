// Automatic cross-coupling calibration of the levitated stage (issue 15,
// item 5): identify the effective 6x6 mixing between the kernel's axis
// efforts and the measured pose, and form the correction C applied to the
// efforts before the force allocation (U' = C U).
//
// Why row-normalised FRFs and not "mass x acceleration": with the loops
// closed, each axis i of the stage answers an effort with its own dynamics
// p_i(w) (x, y, theta_z: mass; z, theta_x, theta_y: the out-of-plane
// suspension, 41-57 Hz, paper 003 (29)-(31); every axis: the same 1.5-tick
// delay), so at an excitation line the plant is G(w) = D(w) M with D diagonal
// and M the static mixing the errors make (coil yaw/roll, commutation phase,
// b* spread, CoM offset, sensor geometry). R = diag(G)^-1 G = diag(M)^-1 M
// does not depend on D: no mass, spring or delay model is needed, and the
// correction C = R^-1 = M^-1 diag(M) removes the coupling while every axis
// keeps its own gain (the loops' tuning is untouched).
//
// G comes from six experiments (axis j excited, the other loops reacting):
// with Y, U the 6x6 complex matrices of the DFTs (column j = experiment j),
// G = Y U^-1 holds whatever the feedback did (U is the effort that went into
// the allocation, d included).
//
// Float, static storage, no heap, no exceptions; host and Cortex-M7.
#pragma once

#include <cstdint>

#include "maglev/io/axis.hpp"
#include "maglev/io/enum_names.hpp"

namespace maglev::kernel {

inline constexpr int kCouplingLines = 4;  // excitation lines k f0, k = 1..4
inline constexpr int kCouplingMatrixSize = kAxisCount * kAxisCount;

// Entry e (row-major) of the 6x6 identity.
constexpr float identity_entry(int e) { return e % (kAxisCount + 1) == 0 ? 1.0f : 0.0f; }

// The correction applied to the efforts, row-major: U'_i = sum_j C_ij U_j.
// Off (enabled = 0) by default; the kernel then skips it entirely.
struct CouplingCorrection {
  std::uint8_t enabled = 0;
  std::uint8_t reserved[3] = {};  // explicit, always zero
  float matrix[kCouplingMatrixSize] = {1, 0, 0, 0, 0, 0,  //
                                       0, 1, 0, 0, 0, 0,  //
                                       0, 0, 1, 0, 0, 0,  //
                                       0, 0, 0, 1, 0, 0,  //
                                       0, 0, 0, 0, 1, 0,  //
                                       0, 0, 0, 0, 0, 1};
};

// Result / reason of the last calibration: value and name of every
// enumerator, defined once. Values cross a register: never renumber, only append.
#define MAGLEV_COUPLING_CALIBRATION_RESULTS(X) \
  X(kNone, 0, "None")  /* never run since power-on */ \
  X(kRunning, 1, "Running") \
  X(kPassed, 2, "Passed")  /* identified, checked, verified, stored */ \
  X(kRefusedNotReady, 3, "RefusedNotReady")  /* requested while not levitated in Ready */ \
  X(kRefusedBusy, 4, "RefusedBusy")  /* a profile, excitation or injection was running */ \
  X(kAbandonedFault, 5, "AbandonedFault")  /* a fault or a state change interrupted it: nothing changed */ \
  X(kAbandonedInterrupted, 6, "AbandonedInterrupted")  /* hold / stop / another motion command interrupted it */ \
  X(kFailedSingular, 7, "FailedSingular")  /* the effort matrix U of a line is singular (no response) */ \
  X(kFailedNotFinite, 8, "FailedNotFinite") \
  X(kFailedInconsistent, 9, "FailedInconsistent")  /* R differs between lines: not a static mixing */ \
  X(kFailedCorrectionTooLarge, 10, "FailedCorrectionTooLarge")  /* |C - I| beyond max_correction */ \
  X(kFailedIllConditioned, 11, "FailedIllConditioned")  /* cond_1(R) beyond max_condition */ \
  X(kFailedVerification, 12, "FailedVerification")  /* with C applied the coupling did not drop */

enum class CouplingCalibrationResult : std::uint8_t {
  MAGLEV_COUPLING_CALIBRATION_RESULTS(MAGLEV_ENUMERATOR)
};
const char* to_string(CouplingCalibrationResult r);

struct CouplingCalibrationConfig {
  // Lines at k f0, k = 1..kCouplingLines: 20-80 Hz, around the loops'
  // crossovers (50-83 Hz) where the closed loop passes most of d to Y, below
  // the amplifiers (5 kHz) and far from Nyquist (1250 Hz).
  float fundamental_Hz = 20.0f;
  // Peak of the multisine per axis (A of effort, <= ExcitationLimits):
  // measured on the as-built bench, 2.3 um p-p in x, y, 0.8 um in z, 23 urad
  // in each rotation -- 13x inside the tilt envelope even on a platen that
  // could not be levelled; 10x less leaves 10x more residual coupling (noise),
  // 10x more tripped the envelope (docs/KERNEL.md, docs/PERFORMANCE.md).
  float amplitude_A[kAxisCount] = {0.05f, 0.05f, 0.005f, 0.1f, 0.003f, 0.003f};
  float settle_s = 0.25f;        // after each start, before the DFT window
  std::uint16_t periods = 40;    // DFT window: whole periods of f0 (2 s at 20 Hz)
  // Checks (dimensionless: rotational efforts scaled by the axis' radius of
  // gyration, so a translation and a rotation compare as forces).
  float max_inconsistency = 0.05f;  // max |R~_k - R~| over lines, off-diagonal
  float max_correction = 0.5f;      // max |C~ - I|
  float max_condition = 4.0f;       // cond_1(R~)
  float min_improvement = 2.0f;     // verification: coupling must drop by this factor
};

// Complex number of the identification (float, no <complex>: its division
// pulls libgcc helpers with NaN handling the target does not need).
struct Cf {
  float re = 0.0f;
  float im = 0.0f;
};

// Inverts the n x n row-major matrix a (n <= 12) in place by Gauss-Jordan
// with partial pivoting; false (a unspecified) if a pivot is below
// tiny * (largest |entry|) or not finite.
bool invert_matrix(float* a, int n, float tiny = 1e-6f);

// The identification: accumulate() once per tick of an experiment's DFT
// window; finish_experiment() closes experiment j; solve() forms R.
class CouplingIdentifier {
 public:
  void reset();
  // phase: the fundamental's phase word this tick (2^32 = one turn); line k
  // uses (k+1) * phase. u: the efforts (A), y: the measured pose minus its
  // value at the window's start (m, rad).
  void accumulate(std::uint32_t phase, const float u[kAxisCount], const float y[kAxisCount]);
  void finish_experiment(int j);
  // R (row-major, unit diagonal, real), its scaled coupling (max off-diagonal)
  // and line spread; radius[a] = the axis' radius of gyration (1 for translations).
  CouplingCalibrationResult solve(const float radius_m[kAxisCount], float r_out[kCouplingMatrixSize],
                                  float* coupling, float* inconsistency) const;

 private:
  Cf acc_u_[kCouplingLines][kAxisCount]{};
  Cf acc_y_[kCouplingLines][kAxisCount]{};
  Cf u_[kCouplingLines][kAxisCount][kAxisCount]{};  // [line][row i][experiment j]
  Cf y_[kCouplingLines][kAxisCount][kAxisCount]{};
};

// max over i != j of |A_ij| r_j / r_i (A row-major, dimensionless coupling).
float scaled_coupling(const float a[kCouplingMatrixSize], const float radius_m[kAxisCount]);

// Checks R and forms the correction C_new = C_old R^-1; kPassed when every
// check holds (c_new then valid), else the reason (c_new untouched).
CouplingCalibrationResult correction_from(const float r[kCouplingMatrixSize], const float c_old[kCouplingMatrixSize],
                                          const float radius_m[kAxisCount], const CouplingCalibrationConfig& cfg,
                                          float c_new[kCouplingMatrixSize]);

// A correction the kernel accepts in its configuration: finite, and within
// kMaxCorrectionMagnitude of the identity (scaled).
inline constexpr float kMaxCorrectionMagnitude = 1.0f;
bool correction_valid(const CouplingCorrection& c, const float radius_m[kAxisCount]);

}  // namespace maglev::kernel
