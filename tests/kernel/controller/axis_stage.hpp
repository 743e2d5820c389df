// AxisStage: a small axis-level stage model that closes the loop around a
// Controller<Scalar> through the real I/O records (tests only).
//
//  * actuator side: DAC codes -> coil currents i_j = code / (codes per A) ->
//    the effort the coils really produce, U = A G with G_h = sum_j i_j sin psi_j / 2,
//    G_z = sum_j i_j cos psi_j / 2 over each forcer's two coils, plus the
//    tilt torque of each coil's vertical force about its forcer centre (the
//    coil centres of DefaultForceAllocationConfig, as the HIL plant places
//    them), psi from the same integer commutation as the kernel.
//  * plant, per axis (paper 000 eqs (25)-(31)): y'' + c' y' + k' y = (2 b*/m) U,
//    z with gravity and a floor (z >= 0); semi-implicit Euler, 8 sub-steps per tick.
//  * sensor side: the pose -> interferometer counts (beam layout of
//    DefaultSensorsToPoseConfig) and laser-displacement ADC codes (plane of
//    the three sensors), plus seeded Gaussian noise (sigma 1 nm on each beam,
//    20 nm on each height), constant plausible Hall codes.
// Deterministic for a given seed. Not the HIL plant (hil/plant): no field
// model, no amplifier dynamics -- enough to exercise levitated Ready.
#pragma once

#include <cmath>
#include <cstdint>

#include "maglev_test/resting_sample.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/io/stage_parameters.hpp"

namespace maglev::kernel::test {

class AxisStage {
 public:
  explicit AxisStage(std::uint64_t seed) : rng_(seed | 1u) {
    (void)ApplyForceAllocationConfig<float>(DefaultForceAllocationConfig(), &alloc_);
    s2p_ = DefaultSensorsToPoseConfig();
  }

  double pos[kAxisCount] = {};  // SI: x y theta_z z theta_x theta_y (z above rest)
  double vel[kAxisCount] = {};
  double extra_force[kAxisCount] = {};  // external disturbance (N or N m)
  double beam_noise_m = 1e-9;
  double height_noise_m = 20e-9;
  double last_effort[kAxisCount] = {};  // U the coils produced on the last tick

  io::SensorSample sample() {
    namespace st = io::stage;
    io::SensorSample s{};
    const double x = pos[0], y = pos[1], tz = pos[2];
    for (int b = 0; b < io::kInterferometerAxes; ++b) {
      const BeamConfig& beam = s2p_.beam[b];
      const double d = beam.mirror_distance_m * std::tan(tz) * std::tan(tz) / 2.0;
      const double m = beam.axis == BeamAxis::kX ? x - (beam.perpendicular_m - y) * std::tan(tz) + d
                                                 : y + (beam.perpendicular_m - x) * std::tan(tz) + d;
      const double counts = std::round((beam.sign * m + gauss() * beam_noise_m) / st::kInterferometerLsb_m);
      s.interferometer_counts[b] = base_[b] + static_cast<std::uint32_t>(static_cast<std::int64_t>(counts));
    }
    for (int k = 0; k < io::kDisplacementSensors; ++k) {
      const double h = pos[3] + pos[4] * st::kDisplacementSensorY_m[k] - pos[5] * st::kDisplacementSensorX_m[k] +
                       gauss() * height_noise_m;
      const double volts = (h - st::kDisplacementZeroHeight_m) / st::kDisplacementScale_m_per_V;
      s.displacement_adc[k] = static_cast<std::int16_t>(std::lround(volts / st::kAdcFullScale_V * 32768.0));
    }
    s.hall_adc[0] = 6000;
    s.hall_adc[1] = 6000;
    s.hall_adc[2] = 10000;
    s.hall_adc[3] = 10000;
    maglev::test::set_monitored_currents(last_command_, &s);
    return s;
  }

  // Applies one tick of the command; x_pm, y_pm = the kernel's commutation position.
  void advance(const io::ActuatorCommand& cmd, std::int64_t x_pm, std::int64_t y_pm) {
    namespace st = io::stage;
    last_command_ = cmd;
    double u[kAxisCount] = {};
    if (cmd.amplifier_enable) {
      std::uint32_t phase[io::kCoils];
      CommutationPhases(x_pm, y_pm, alloc_.commutation, phase);
      double g[kForcerForces] = {};
      const ForceAllocationConfig geometry = DefaultForceAllocationConfig();
      for (int j = 0; j < io::kCoils; ++j) {
        const double i = static_cast<double>(cmd.dac_code[j]) / alloc_.dac_codes_per_A;
        const double psi = static_cast<double>(phase[j]) * (2.0 * 3.14159265358979323846 / 4294967296.0);
        g[2 * (j / 2)] += 0.5 * i * std::sin(psi);
        g[2 * (j / 2) + 1] += 0.5 * i * std::cos(psi);
        // Coil j's vertical force acts at its own centre, off the forcer's.
        u[4] += geometry.coil_centre_offset_m[j][1] * 0.5 * i * std::cos(psi);
        u[5] -= geometry.coil_centre_offset_m[j][0] * 0.5 * i * std::cos(psi);
      }
      for (int a = 0; a < kAxisCount; ++a) {
        for (int r = 0; r < kForcerForces; ++r) u[a] += alloc_.tables.a[a][r] * g[r];
      }
    }
    for (int a = 0; a < kAxisCount; ++a) last_effort[a] = u[a];
    const double two_b = st::kTwoBStarIdentified_N_per_A;
    const double inertia[kAxisCount] = {st::kMass_kg, st::kMass_kg, st::kIz_kgm2,
                                        st::kMass_kg, st::kIx_kgm2, st::kIy_kgm2};
    const double k[kAxisCount] = {0, 0, 0, st::kZStiffness_N_per_m, st::kTiltStiffness_Nm_per_rad,
                                  st::kTiltStiffness_Nm_per_rad};
    const double c[kAxisCount] = {0, 0, 0, st::kZDamping_Ns_per_m, st::kTiltDamping_Nms_per_rad,
                                  st::kTiltDamping_Nms_per_rad};
    constexpr int kSub = 8;
    const double h = 1.0 / (st::kServoRate_Hz * kSub);
    for (int n = 0; n < kSub; ++n) {
      for (int a = 0; a < kAxisCount; ++a) {
        double f = two_b * u[a] + extra_force[a] - c[a] * vel[a] - k[a] * pos[a];
        if (a == 3) f -= st::kMass_kg * st::kGravity_m_per_s2;
        vel[a] += h * f / inertia[a];
        pos[a] += h * vel[a];
        if (a == 3 && pos[a] <= 0.0) {  // the floor
          pos[a] = 0.0;
          if (vel[a] < 0.0) vel[a] = 0.0;
        }
      }
    }
  }

  template <typename Scalar>
  io::ActuatorCommand tick(Controller<Scalar>& c) {
    const io::ActuatorCommand cmd = c.step(sample(), false);
    advance(cmd, c.status().pose[maglev::kernel::Axis::kX], c.status().pose[maglev::kernel::Axis::kY]);
    return cmd;
  }

  template <typename Scalar>
  bool run_until(Controller<Scalar>& c, SequencerState s, int max_ticks) {
    for (int n = 0; n < max_ticks; ++n) {
      tick(c);
      if (c.status().state == s) return true;
    }
    return false;
  }

 private:
  io::ActuatorCommand last_command_ = io::kSafeActuatorCommand;
  double gauss() {  // Box-Muller on a 64-bit xorshift*
    const double u1 = (static_cast<double>(next() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    const double u2 = (static_cast<double>(next() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.14159265358979323846 * u2);
  }
  std::uint64_t next() {
    rng_ ^= rng_ >> 12;
    rng_ ^= rng_ << 25;
    rng_ ^= rng_ >> 27;
    return rng_ * 0x2545F4914F6CDD1DULL;
  }

  std::uint64_t rng_;
  ForceAllocationState<float> alloc_{};
  SensorsToPoseConfig s2p_{};
  std::uint32_t base_[3] = {1000u, 2000u, 3000u};
};

}  // namespace maglev::kernel::test
