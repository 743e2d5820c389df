#include "maglev/io/code_placement.hpp"
#include "maglev/controller/controller.hpp"

#include "maglev/axis_loops/loop_check.hpp"

#include <atomic>  // std::atomic_signal_fence: a compiler barrier, no library code
#include <cmath>
#include <cstring>

#include "maglev/io/stage_parameters.hpp"
#include "maglev/numeric/int64_double.hpp"
#include "maglev/numeric/saturation.hpp"

namespace maglev::kernel {
namespace {

namespace stage = io::stage;

using numeric::PicoToSi;

template <typename T>
bool same_bytes(const T& a, const T& b) {
  return same_value_bytes(a, b);
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

MAGLEV_ENUM_TO_STRING(CommandResult, MAGLEV_COMMAND_RESULTS)

MAGLEV_ENUM_TO_STRING(ConfigError, MAGLEV_CONFIG_ERRORS)

MAGLEV_CONFIG_CODE KernelConfig default_kernel_config() {
  KernelConfig c{};
  c.servo_rate_Hz = static_cast<float>(stage::kServoRate_Hz);
  c.measurement = DefaultSensorsToPoseConfig();
  for (Axis a : kAllAxes) c.axis[axis_index(a)] = default_axis_loop_config(a);
  c.allocation = DefaultForceAllocationConfig();
  // Travel limits (x +-28 mm, y +-17.5 mm: paper 000's 56 mm x 35 mm) and the
  // supervisor's window 1 mm beyond them are the structs' own defaults,
  // derived from io::stage::kTravelX_m / kTravelY_m.
  c.references = ReferenceLimits{};
  c.sequencer = SequencerConfig{};
  c.sequencer.nominal_height_m = static_cast<float>(stage::kNominalHeight_m);
  c.supervisor = SupervisorConfig{};
  c.supervisor.peak_current_A = static_cast<float>(stage::kPeakCoilCurrent_A);
  c.supervisor.rms_current_A = static_cast<float>(stage::kRmsCoilCurrent_A);
  c.supervisor.interferometer_lsb_m = static_cast<float>(stage::kInterferometerLsb_m);
  c.payload_mass_kg = 0.0f;
  c.live_tuning = false;
  c.acceleration_feedforward = true;
  c.antiwindup = true;
  for (float& j : c.payload_inertia_kgm2) j = 0.0f;
  c.excitation = ExcitationLimits{};
  c.coupling = CouplingCorrection{};  // off: the allocation as designed
  c.stage.peak_current_A = c.supervisor.peak_current_A;
  c.stage.rms_current_A = c.supervisor.rms_current_A;
  c.stage.x_min_m = -static_cast<float>(stage::kTravelX_m / 2 + kStageWindowBeyondTravel_m);
  c.stage.x_max_m = static_cast<float>(stage::kTravelX_m / 2 + kStageWindowBeyondTravel_m);
  c.stage.y_min_m = -static_cast<float>(stage::kTravelY_m / 2 + kStageWindowBeyondTravel_m);
  c.stage.y_max_m = static_cast<float>(stage::kTravelY_m / 2 + kStageWindowBeyondTravel_m);
  return c;
}

template <typename Scalar>
ConfigError DesignAxis(const KernelConfig& c, int a, Pid2DofCoefficients<Scalar>* pid,
                       InternalModelCoefficients<Scalar>* imr, BiquadCoefficients<Scalar> filter[kMaxBiquadStages]) {
  const double rate = static_cast<double>(c.servo_rate_Hz);
  const LoopType type = c.axis[a].type;
  if (type != LoopType::kPid2Dof && type != LoopType::kInternalModel) return ConfigError::kUnsupportedLoopType;
  // Gains the loop check finds unstable on this axis' plant are refused
  // (a z.kp of 1e7 once saturated the coils while the status said Ready).
  if (type == LoopType::kPid2Dof) {
    const InternalModelConfig& plant = c.axis[a].imr;  // the axis plant the kernel designs against
    const LoopPlant lp{static_cast<double>(plant.plant_gain), static_cast<double>(plant.plant_damping_per_s),
                       static_cast<double>(plant.plant_stiffness_per_s2)};
    if (!LoopIsAcceptable(Pid2DofLoopMargins(c.axis[a].pid, lp, rate, c.axis[a].filters, kMaxBiquadStages))) {
      return ConfigError::kUnstableLoop;
    }
  }
  // Only the selected loop must design; the other keeps zero coefficients.
  const LoopDesignError de = type == LoopType::kPid2Dof
                                 ? design_pid2dof<Scalar>(c.axis[a].pid, rate, pid)
                                 : design_internal_model<Scalar>(c.axis[a].imr, rate, imr);  // paper 002 (14)-(17)
  if (de != LoopDesignError::kOk) return ConfigError::kAxisLoop;
  for (int f = 0; f < kMaxBiquadStages; ++f) {
    if (design_biquad<Scalar>(c.axis[a].filters[f], rate, &filter[f]) != LoopDesignError::kOk) {
      return ConfigError::kAxisLoop;
    }
  }
  return ConfigError::kOk;
}

template ConfigError DesignAxis<float>(const KernelConfig&, int, Pid2DofCoefficients<float>*,
                                       InternalModelCoefficients<float>*, BiquadCoefficients<float>*);
template ConfigError DesignAxis<numeric::Q7_24>(const KernelConfig&, int, Pid2DofCoefficients<numeric::Q7_24>*,
                                                InternalModelCoefficients<numeric::Q7_24>*,
                                                BiquadCoefficients<numeric::Q7_24>*);

template <typename Scalar>
Controller<Scalar>::Controller() {
  sequencer_.reset();
  supervisor_.reset();
  const ConfigError e = apply_config(default_kernel_config());
  status_.last_config_error = e;
}

template <typename Scalar>
bool Controller<Scalar>::levitated_or_busy() const {
  const SequencerState s = sequencer_.output().state;
  return s != SequencerState::kIdle && s != SequencerState::kFault;
}

template <typename Scalar>
ConfigError Controller<Scalar>::apply_config(const KernelConfig& c) {
  const ConfigError e = prepare_config(c);
  return e != ConfigError::kOk ? e : commit_config(c);
}

template <typename Scalar>
MAGLEV_CONFIG_CODE double PeakCoilCurrent_A(const Scalar effort_A[kAxisCount], const ForceAllocationState<Scalar>& state,
                                            double pitch_m, int places_per_pitch) {
  using Traits = numeric::ScalarTraits<Scalar>;
  double peak = 0.0;
  for (int i = 0; i < places_per_pitch; ++i) {
    for (int j = 0; j < places_per_pitch; ++j) {
      AllocationOutput<Scalar> out;
      AllocateCurrents<Scalar>(effort_A, numeric::si_to_pico(pitch_m * i / places_per_pitch),
                               numeric::si_to_pico(pitch_m * j / places_per_pitch), state, &out);
      // The demand itself, before the current limit's common scale k.
      const double k = Traits::to_double(out.scale_k);
      for (const Scalar& cur : out.current_A) {
        const double a = std::fabs(Traits::to_double(cur)) / (k > 0.0 ? k : 1.0);
        peak = a > peak ? a : peak;
      }
    }
  }
  return peak;
}
template double PeakCoilCurrent_A<float>(const float[kAxisCount], const ForceAllocationState<float>&, double, int);
template double PeakCoilCurrent_A<numeric::Q7_24>(const numeric::Q7_24[kAxisCount],
                                                  const ForceAllocationState<numeric::Q7_24>&, double, int);

template <typename Scalar>
MAGLEV_CONFIG_CODE double HoverPeakCurrent_A(const ForceAllocationState<Scalar>& state, double pitch_m) {
  using Traits = numeric::ScalarTraits<Scalar>;
  Scalar effort[kAxisCount];
  for (Scalar& e : effort) e = Traits::zero();
  effort[axis_index(Axis::kZ)] = GravityFeedForward_A(Traits::one(), state);
  return PeakCoilCurrent_A(effort, state, pitch_m, 4);
}
template double HoverPeakCurrent_A<float>(const ForceAllocationState<float>&, double);
template double HoverPeakCurrent_A<numeric::Q7_24>(const ForceAllocationState<numeric::Q7_24>&, double);

template <typename Scalar>
ConfigError Controller<Scalar>::refuse_config(ConfigError e) {
  status_.last_config_error = e;
  return e;
}

template <typename Scalar>
ConfigError Controller<Scalar>::prepare_config(const KernelConfig& c) {
  prepared_ = false;
  status_.config_axis = 0xFF;
  // --- 1. validate the whole config into the scratch slot; nothing live changes.
  const double rate = static_cast<double>(c.servo_rate_Hz);
  // One of the offered rates (register servo.rate): the board's timers and
  // the bench's budgets are worked out for those alone.
  if (!stage::is_supported_servo_rate(rate)) return refuse_config(ConfigError::kBadServoRate);
  if (std::fabs(c.measurement.servo_rate_Hz - rate) > 1e-6 * rate) return refuse_config(ConfigError::kMeasurement);
  // (ApplySensorsToPoseConfig builds the whole state from the config: no
  // read of the live s2p_, which the tick writes.)
  if (ApplySensorsToPoseConfig(c.measurement, &s2p_next_) != SensorsToPoseError::kOk) {
    return refuse_config(ConfigError::kMeasurement);
  }
  Applied& scratch = applied_[1 - active_];
  for (int a = 0; a < kAxisCount; ++a) {
    const ConfigError de = DesignAxis<Scalar>(c, a, &scratch.pid[a], &scratch.imr[a], scratch.filter[a]);
    if (de != ConfigError::kOk) {
      status_.config_axis = static_cast<std::uint8_t>(a);
      return refuse_config(de);
    }
    scratch.type[a] = c.axis[a].type;
    scratch.filtered[a] = biquad_chain_enabled(scratch.filter[a]);
  }
  scratch.all_pid = true;
  for (const LoopType type : scratch.type) scratch.all_pid = scratch.all_pid && type == LoopType::kPid2Dof;
  if (!(c.payload_mass_kg >= 0.0f && c.payload_mass_kg <= kMaxPayloadSanity_kg)) return refuse_config(ConfigError::kPayload);
  ForceAllocationConfig alloc = c.allocation;
  alloc.payload_kg = static_cast<double>(c.payload_mass_kg);
  if (ApplyForceAllocationConfig<Scalar>(alloc, &scratch.allocation) != ForceAllocationError::kOk) {
    // A payload the fixed-point tables cannot hold is a payload error.
    return refuse_config(c.payload_mass_kg > 0.0f ? ConfigError::kPayload : ConfigError::kAllocation);
  }
  // The stage must hover its platen and payload with room to control: the
  // gravity feed-forward through the allocation, at the largest coil over 4 x
  // 4 places per pitch, at most kMaxHoverFraction of the peak current. The
  // fixed cap it replaces (1.5 kg; the register's 1.0 kg) let through
  // payloads the seed stage cannot lift (1.0 kg: 5.0 A per coil of its 4 A),
  // and would refuse a heavier stage's real capacity.
  if (c.payload_mass_kg > 0.0f &&
      HoverPeakCurrent_A(scratch.allocation, c.allocation.pitch_m) >
          kMaxHoverFraction * static_cast<double>(c.supervisor.peak_current_A)) {
    return refuse_config(ConfigError::kPayload);
  }
  for (float j : c.payload_inertia_kgm2) {
    if (!(j >= 0.0f && j <= 0.01f)) return refuse_config(ConfigError::kPayload);
  }
  // The platen's own inertias (a profile's [body]): positive and finite.
  for (double j : alloc.inertia_kgm2) {
    if (!(j > 0.0 && j < 1e3)) return refuse_config(ConfigError::kAllocation);
  }
  const double two_b_star = scratch.allocation.two_b_star_N_per_A;
  const double m_total = alloc.mass_kg + alloc.payload_kg;
  const double inertia[kAxisCount] = {m_total,
                                      m_total,
                                      alloc.inertia_kgm2[2] + static_cast<double>(c.payload_inertia_kgm2[0]),
                                      m_total,
                                      alloc.inertia_kgm2[0] + static_cast<double>(c.payload_inertia_kgm2[1]),
                                      alloc.inertia_kgm2[1] + static_cast<double>(c.payload_inertia_kgm2[2])};
  for (int a = 0; a < kAxisCount; ++a) {
    // Acceleration feed-forward, eq (22) inverted: U = (m or I) a / (2 b*), A per SI acceleration.
    scratch.inertia_over_two_b_star[a] = inertia[a] / two_b_star;
  }
  // Coupling correction: finite, near the identity (scaled by the radii of gyration).
  {
    float radius[kAxisCount];
    for (int a = 0; a < kAxisCount; ++a) {
      radius[a] = static_cast<float>(std::sqrt(scratch.inertia_over_two_b_star[a] / scratch.inertia_over_two_b_star[0]));
    }
    if (!correction_valid(c.coupling, radius)) return refuse_config(ConfigError::kCouplingCorrection);
  }
  // Reference limits: inside the supervisor window, positive rates.
  const ReferenceLimits& r = c.references;
  const SupervisorConfig& sv = c.supervisor;
  for (int a = 0; a < kAxisCount; ++a) {
    if (!(r.position_min[a] < r.position_max[a]) || !finite_positive(r.max_velocity[a]) ||
        !finite_positive(r.max_acceleration[a]) || !finite_positive(r.max_step[a]) || r.max_step[a] > 100e-6f ||
        !finite_positive(r.max_jerk[a])) {
      return refuse_config(ConfigError::kReferenceLimits);
    }
  }
  if (r.position_min[0] < sv.x_min_m || r.position_max[0] > sv.x_max_m || r.position_min[1] < sv.y_min_m ||
      r.position_max[1] > sv.y_max_m || r.position_min[2] < -sv.theta_z_limit_rad ||
      r.position_max[2] > sv.theta_z_limit_rad || r.position_min[3] < sv.z_min_m ||
      r.position_max[3] > sv.z_max_m || r.position_min[4] < -sv.tilt_limit_rad ||
      r.position_max[4] > sv.tilt_limit_rad || r.position_min[5] < -sv.tilt_limit_rad ||
      r.position_max[5] > sv.tilt_limit_rad) {
    return refuse_config(ConfigError::kReferenceLimits);
  }
  // Excitation: bounded amplitude (never more than the coil peak), lines below Nyquist.
  const ExcitationLimits& ex = c.excitation;
  if (!finite_positive(ex.max_amplitude_A) || ex.max_amplitude_A > c.supervisor.peak_current_A ||
      !finite_positive(ex.max_frequency_Hz) || ex.max_frequency_Hz >= 0.5f * c.servo_rate_Hz ||
      !finite_positive(ex.max_duration_s) ||
      static_cast<double>(ex.max_duration_s) * rate > 4.0e9) {
    return refuse_config(ConfigError::kReferenceLimits);
  }
  if (validate(c.sequencer, c.servo_rate_Hz) != SequencerConfigError::kOk) return refuse_config(ConfigError::kSequencer);
  if (validate(c.supervisor, c.servo_rate_Hz) != SupervisorConfigError::kOk) return refuse_config(ConfigError::kSupervisor);
  // The stage's own limits (StageEnvelope): the register ranges are the
  // board's envelope, these are the selected stage's coils and travel.
  {
    const StageEnvelope& st = c.stage;
    const bool envelope_ok = finite_positive(st.peak_current_A) && finite_positive(st.rms_current_A) &&
                             st.x_min_m < 0.0f && st.x_max_m > 0.0f && st.y_min_m < 0.0f && st.y_max_m > 0.0f &&
                             std::isfinite(st.x_min_m) && std::isfinite(st.x_max_m) && std::isfinite(st.y_min_m) &&
                             std::isfinite(st.y_max_m);
    if (!envelope_ok || !(sv.peak_current_A <= st.peak_current_A) || !(sv.rms_current_A <= st.rms_current_A) ||
        !(sv.x_min_m >= st.x_min_m) || !(sv.x_max_m <= st.x_max_m) || !(sv.y_min_m >= st.y_min_m) ||
        !(sv.y_max_m <= st.y_max_m)) {
      return refuse_config(ConfigError::kBeyondStageLimits);
    }
  }
  // The nominal height must sit inside the reference and supervisor z range.
  if (c.sequencer.nominal_height_m > sv.z_max_m) return refuse_config(ConfigError::kSequencer);
  // The z window's top inside what the laser displacement sensors measure.
  if (!(static_cast<double>(sv.z_max_m) < HeightSensorsTop_m(c.measurement))) return refuse_config(ConfigError::kSupervisor);
  // Its integer limits here, with interrupts enabled: commit_config copies them.
  supervisor_next_ = PrepareSupervisorSettings(c.supervisor, c.servo_rate_Hz);
  prepared_ = true;
  return ConfigError::kOk;
}

template <typename Scalar>
ConfigError Controller<Scalar>::commit_config(const KernelConfig& c) {
  if (!prepared_) {
    const ConfigError e = prepare_config(c);
    if (e != ConfigError::kOk) return e;
  }
  prepared_ = false;

  // --- 2. while not on rest only gains may change, and only with live_tuning.
  const bool levitated = levitated_or_busy();
  if (levitated) {
    const bool locked_same = c.servo_rate_Hz == config_.servo_rate_Hz &&
                             same_bytes(c.measurement, config_.measurement) &&
                             same_bytes(c.allocation, config_.allocation) &&
                             same_bytes(c.references, config_.references) &&
                             same_bytes(c.sequencer, config_.sequencer) &&
                             same_bytes(c.supervisor, config_.supervisor) &&
                             c.payload_mass_kg == config_.payload_mass_kg &&
                             same_bytes(c.payload_inertia_kgm2, config_.payload_inertia_kgm2) &&
                             same_bytes(c.coupling, config_.coupling) && same_bytes(c.stage, config_.stage);
    if (!locked_same) return refuse_config(ConfigError::kLockedWhileLevitated);
    bool gains_same = true;
    for (int a = 0; a < kAxisCount; ++a) gains_same = gains_same && same_bytes(c.axis[a], config_.axis[a]);
    gains_same = gains_same && c.acceleration_feedforward == config_.acceleration_feedforward &&
                 c.antiwindup == config_.antiwindup;
    if (!gains_same && !c.live_tuning) return refuse_config(ConfigError::kGainsLockedWhileLevitated);
    // Live tuning: a bounded step per write (kMaxLiveGainStep).
    auto step_ok = [](float now, float next) {
      if (now == 0.0f) return next == 0.0f;
      const float ratio = next / now;  // NaN (refused) if next is NaN
      return ratio >= 1.0f / kMaxLiveGainStep && ratio <= kMaxLiveGainStep;
    };
    for (int a = 0; a < kAxisCount; ++a) {
      const Pid2DofConfig& now = config_.axis[a].pid;
      const Pid2DofConfig& next = c.axis[a].pid;
      if (!step_ok(now.kp, next.kp) || !step_ok(now.ki, next.ki) || !step_ok(now.kd, next.kd)) {
        status_.config_axis = static_cast<std::uint8_t>(a);
        return refuse_config(ConfigError::kGainStepTooLarge);
      }
    }
  }

  // --- 3. swap. Measurement state is only replaced when its config changed
  // (re-seeding the counters would lose the interferometer zero).
  // A new measurement state has no homing offsets: the sequencer forgets
  // that it homed, so the next levitate homes again (it went straight to
  // InPlaneLock, commutating from wherever the counters re-seeded).
  if (!same_bytes(c.measurement, config_.measurement) || !s2p_.lsb_den) {
    s2p_ = s2p_next_;
    sequencer_.invalidate_homing();
  }
  active_ = 1 - active_;
  config_ = c;
  // On rest a running coupling ramp ends (the correction cannot change while
  // levitated, see above). A live gain write used to cut it too: the
  // correction jumped to its target instead of blending over 0.5 s.
  if (!levitated) ramp_.left = 0;
  // A live loop-type switch hands the effort over (approximately bumpless):
  // the new loop's integral state starts at the old loop's last output.
  for (int a = 0; a < kAxisCount; ++a) {
    const LoopType t = applied_[active_].type[a];
    if (t == running_type_[a]) continue;
    const Scalar e = running_type_[a] == LoopType::kPid2Dof ? pid_state_[a].prev_error : imr_state_[a].prev_d_input;
    if (t == LoopType::kInternalModel) {
      const Scalar u = pid_state_[a].last_output;
      InternalModelRegulator<Scalar>(&applied_[active_].imr[a], &imr_state_[a]).reset(e);
      imr_state_[a].xi[0] = Traits::acc_from_scalar(u);
      imr_state_[a].last_output = u;
    } else {
      Pid2Dof<Scalar>(&applied_[active_].pid[a], &pid_state_[a]).reset(imr_state_[a].last_output, e);
    }
    running_type_[a] = t;
  }
  // The filter chains skip their stages while none is enabled (BiquadBank):
  // a newly enabled chain gets the state tracking every stage would have left.
  filters_.reconfigure(applied_[1 - active_].filtered, applied_[active_].filtered);
  sequencer_.configure(c.sequencer, c.servo_rate_Hz);
  supervisor_.configure(supervisor_next_);
  homing_needed_ticks_ = static_cast<std::uint32_t>(c.sequencer.homing_time_s * c.servo_rate_Hz) + 1u;
  coupling_ramp_ticks_ = static_cast<std::uint32_t>(std::lround(kCouplingRamp_s * c.servo_rate_Hz));
  for (int k = 0; k < 2; ++k) {
    tilt_min_pico_[k] = numeric::si_to_pico(static_cast<double>(c.references.position_min[4 + k]));
    tilt_max_pico_[k] = numeric::si_to_pico(static_cast<double>(c.references.position_max[4 + k]));
  }
  const std::int64_t level_step = numeric::si_to_pico(static_cast<double>(c.sequencer.tilt_reference_rate_rad_per_s) /
                                                      static_cast<double>(c.servo_rate_Hz));
  tilt_level_step_pico_ = level_step > 0 ? level_step : 1;
  status_.last_config_error = ConfigError::kOk;
  return ConfigError::kOk;
}

template <typename Scalar>
CommandResult Controller<Scalar>::command(const MotionCommand& cmd) {
  auto seq = [this](SequencerCommand sc) {
    const SequencerCommandResult r = sequencer_.command(sc, supervisor_.cause_present());
    if (sc == SequencerCommand::kClearFault && r == SequencerCommandResult::kAccepted) supervisor_.clear_fault();
    switch (r) {
      case SequencerCommandResult::kAccepted: return CommandResult::kAccepted;
      case SequencerCommandResult::kAlreadyThere: return CommandResult::kAlreadyThere;
      case SequencerCommandResult::kRefusedBusy: return CommandResult::kRefusedBusy;
      case SequencerCommandResult::kRefusedNotLevitated: return CommandResult::kRefusedNotLevitated;
      case SequencerCommandResult::kRefusedFaultLatched: return CommandResult::kRefusedFaultLatched;
      case SequencerCommandResult::kRefusedNotFaulted: return CommandResult::kRefusedNotFaulted;
      case SequencerCommandResult::kRefusedFaultActive: return CommandResult::kRefusedFaultActive;
    }
    return CommandResult::kRefusedBusy;
  };
  // Any other command interrupts a running calibration (nothing is kept).
  if (cal_.running && cmd.type != MotionType::kCalibrateCoupling) {
    finish_calibration(CouplingCalibrationResult::kAbandonedInterrupted, true);
  }
  if (cmd.type == MotionType::kCalibrateCoupling) return start_calibration();
  switch (cmd.type) {
    case MotionType::kHome: return seq(SequencerCommand::kHome);
    case MotionType::kLevitate: return seq(SequencerCommand::kLevitate);
    case MotionType::kLand: return seq(SequencerCommand::kLand);
    case MotionType::kStop: return seq(SequencerCommand::kStop);
    case MotionType::kClearFault: return seq(SequencerCommand::kClearFault);
    default: break;
  }
  if (cmd.type == MotionType::kHold) {
    hold();
    return CommandResult::kAccepted;
  }
  if (cmd.type == MotionType::kStopExcitation) {
    excitation_.active = false;
    return CommandResult::kAccepted;
  }
  if (cmd.type == MotionType::kExcite) return start_excitation(cmd);
  if (!sequencer_.output().motion_allowed) return CommandResult::kRefusedNotReady;
  const int a = axis_index(cmd.axis);
  if (a < 0 || a >= kAxisCount) return CommandResult::kRefusedOutOfRange;
  // Every request is planned by firmware/kernel/references against this
  // axis' ReferenceLimits; a refused plan leaves the axis as it was.
  auto result = [](ReferenceError e) {
    switch (e) {
      case ReferenceError::kOk: return CommandResult::kAccepted;
      case ReferenceError::kOutsideTravel:
      case ReferenceError::kStepTooLarge: return CommandResult::kRefusedOutOfRange;
      default: return CommandResult::kRefusedBadProfile;
    }
  };
  const double fs = static_cast<double>(config_.servo_rate_Hz);
  const AxisReferenceLimits lim = axis_limits(a);
  // A running profile owns its axis (a circle both x and y) until it ends or
  // kHold stops it: a new profile would start from the running one's
  // position at zero velocity, a step would jump a moving reference -- a
  // reference deceleration of ~370 m/s^2 from 0.15 m/s, against limits of a
  // few m/s^2, and the stage faults on its following error.
  if (profile_[a].kind != ProfileKind::kNone ||
      (cmd.type == MotionType::kCircle && (profile_[axis_index(Axis::kX)].kind != ProfileKind::kNone ||
                                           profile_[axis_index(Axis::kY)].kind != ProfileKind::kNone))) {
    return CommandResult::kRefusedBusy;
  }
  const std::int64_t start = status_.reference.pico[a] + pending_step_pm_[a];
  switch (cmd.type) {
    case MotionType::kStep: {
      // A NaN step would become 0 pm (si_to_pico) and be accepted.
      if (!std::isfinite(cmd.target)) return CommandResult::kRefusedOutOfRange;
      // Steps given before the next tick add up into one step of the
      // reference: the sum is what max_step and the travel bound, so it is
      // planned from the reference as it stands.
      StepReference step;
      const ReferenceError e =
          step.plan(status_.reference.pico[a], pending_step_pm_[a] + numeric::si_to_pico(cmd.target), lim);
      if (e != ReferenceError::kOk) return result(e);
      // Applied on the next tick and handed to the loop as an explicit step, so
      // its setpoint weighting b acts on it (pid2dof.hpp).
      pending_step_pm_[a] = step.sample(0).step_pico;
      maybe_busy_axes_ |= 1u << a;
      return CommandResult::kAccepted;
    }
    case MotionType::kMoveTo:
    case MotionType::kMoveJerkLimited: {
      if (!std::isfinite(cmd.target)) return CommandResult::kRefusedOutOfRange;
      const std::int64_t target = numeric::si_to_pico(cmd.target);
      MoveReference m;
      const ReferenceError e =
          cmd.type == MotionType::kMoveTo
              ? m.plan_trapezoid(start, target, cmd.velocity, cmd.acceleration, fs, lim)  // paper 000 Fig. 10
              : m.plan_scurve(start, target, cmd.velocity, cmd.acceleration, cmd.jerk, fs, lim);
      if (e != ReferenceError::kOk) return result(e);
      move_[a] = m;
      profile_[a] = Profile{ProfileKind::kMove, 0};
      maybe_busy_axes_ |= 1u << a;
      return CommandResult::kAccepted;
    }
    case MotionType::kSinusoid: {  // paper 002: p0 + A (1 - cos w t), w0 = 1.5 pi
      SinusoidReference sref;
      const ReferenceError e = sref.plan(start, cmd.amplitude, cmd.frequency_Hz, cmd.turns, fs, lim);
      if (e != ReferenceError::kOk) return result(e);
      sinusoid_[a] = sref;
      profile_[a] = Profile{ProfileKind::kSinusoid, 0};
      maybe_busy_axes_ |= 1u << a;
      return CommandResult::kAccepted;
    }
    case MotionType::kCircle: {  // paper 000 Fig. 8: x, y; starts on the circle, centre at -r in x
      const int ix = axis_index(Axis::kX), iy = axis_index(Axis::kY);
      const AxisReferenceLimits lx = axis_limits(ix), ly = axis_limits(iy);
      if (!(cmd.diameter_m > 0.0) || !(cmd.period_s > 0.0)) return CommandResult::kRefusedBadProfile;
      const double r = 0.5 * cmd.diameter_m;
      const double speed = 3.14159265358979323846 * cmd.diameter_m / cmd.period_s;
      const double alim = std::fmin(lx.max_acceleration, ly.max_acceleration);
      const double jlim = std::fmin(lx.max_jerk, ly.max_jerk);
      const double centripetal = speed * speed / r;
      // Unless given, the arc-length S-curve uses half of what the limits leave
      // after the centripetal part (references.cpp checks the worst case).
      const double at = cmd.acceleration > 0.0
                            ? cmd.acceleration
                            : 0.5 * std::sqrt(std::fmax(alim * alim - centripetal * centripetal, 0.0));
      const double jerk = cmd.jerk > 0.0 ? cmd.jerk
                                         : 0.5 * (jlim - 3.0 * speed * at / r - speed * centripetal / r);
      CircleReference c;
      const ReferenceError e = c.plan(status_.reference.pico[ix] + pending_step_pm_[ix], status_.reference.pico[iy] + pending_step_pm_[iy],
                                      cmd.diameter_m, speed, cmd.turns, at, jerk, fs, lx, ly);
      if (e != ReferenceError::kOk) return result(e);
      circle_ = c;
      profile_[ix] = Profile{ProfileKind::kCircle, 0};
      profile_[iy] = Profile{ProfileKind::kCircle, 0};
      maybe_busy_axes_ |= (1u << ix) | (1u << iy);
      return CommandResult::kAccepted;
    }
    default: break;
  }
  return CommandResult::kUnsupported;
}

template <typename Scalar>
AxisReferenceLimits Controller<Scalar>::axis_limits(int a) const {
  const ReferenceLimits& r = config_.references;
  AxisReferenceLimits l;
  l.max_velocity = static_cast<double>(r.max_velocity[a]);
  l.max_acceleration = static_cast<double>(r.max_acceleration[a]);
  l.max_jerk = static_cast<double>(r.max_jerk[a]);
  l.max_step_pico = numeric::si_to_pico(static_cast<double>(r.max_step[a]));
  l.travel_min_pico = numeric::si_to_pico(static_cast<double>(r.position_min[a]));
  l.travel_max_pico = numeric::si_to_pico(static_cast<double>(r.position_max[a]));
  return l;
}

// kHold: every moving reference comes to rest at its axis' max
// acceleration, from where it is and as fast as it goes (it used to stop
// dead: from 0.15 m/s that is ~370 m/s^2 of reference deceleration, and the
// stage faulted on its following error); the excitation stops at once.
template <typename Scalar>
void Controller<Scalar>::hold() {
  excitation_.active = false;
  const double fs = static_cast<double>(config_.servo_rate_Hz);
  float velocity[kAxisCount] = {};
  const int ix = axis_index(Axis::kX), iy = axis_index(Axis::kY);
  for (int a = 0; a < kAxisCount; ++a) {
    const Profile& p = profile_[a];
    switch (p.kind) {
      case ProfileKind::kMove: velocity[a] = move_[a].sample(p.tick).velocity; break;
      case ProfileKind::kSinusoid: velocity[a] = sinusoid_[a].sample(p.tick).velocity; break;
      case ProfileKind::kStop: velocity[a] = stop_[a].sample(p.tick).velocity; break;
      case ProfileKind::kCircle:
        if (a == ix) {  // x's tick counts the circle; y's sample is made with it
          AxisReference rx, ry;
          circle_.sample(profile_[ix].tick, &rx, &ry);
          velocity[ix] = rx.velocity;
          velocity[iy] = ry.velocity;
        }
        break;
      case ProfileKind::kNone: break;
    }
  }
  circle_y_valid_ = false;
  circle_y_last_ = false;
  for (int a = 0; a < kAxisCount; ++a) {
    Profile& p = profile_[a];
    if (p.kind == ProfileKind::kNone) continue;
    // From where the reference is about to be: a step given in the tick its
    // profile was commanded is pending, and the profile (like the stop) holds it.
    StopReference stop;
    if (stop.plan(status_.reference.pico[a] + pending_step_pm_[a], static_cast<double>(velocity[a]), fs,
                  axis_limits(a)) == ReferenceError::kOk) {
      stop_[a] = stop;
      p = Profile{ProfileKind::kStop, 0};
    } else {
      p.kind = ProfileKind::kNone;  // (limits validated at configuration: not reached)
    }
  }
}

template <typename Scalar>
CommandResult Controller<Scalar>::start_excitation(const MotionCommand& cmd) {
  if (!sequencer_.output().motion_allowed) return CommandResult::kRefusedNotReady;
  const int a = axis_index(cmd.axis);
  if (a < 0 || a >= kAxisCount) return CommandResult::kRefusedOutOfRange;
  const ExcitationLimits& lim = config_.excitation;
  const int n = cmd.harmonics;
  const double fs = static_cast<double>(config_.servo_rate_Hz);
  if (n < 1 || n > kMaxExcitationHarmonics || !(cmd.amplitude > 0.0) ||
      !(cmd.amplitude <= static_cast<double>(lim.max_amplitude_A)) || !(cmd.frequency_Hz > 0.0) ||
      !(cmd.frequency_Hz * n <= static_cast<double>(lim.max_frequency_Hz)) || !(cmd.duration_s >= 0.0) ||
      !(cmd.duration_s <= static_cast<double>(lim.max_duration_s))) {
    return CommandResult::kRefusedExcitation;
  }
  // Line k at k f (quantised to the phase-increment grid fs / 2^32 = 0.6 uHz),
  // Schroeder phase -pi k (k-1) / N (low crest factor), amplitude A / N each:
  // |d| <= A holds for every tick whatever the phases.
  constexpr double kTurn = 4294967296.0;
  const double inc1 = std::round(cmd.frequency_Hz / fs * kTurn);
  if (!(inc1 >= 1.0)) return CommandResult::kRefusedExcitation;
  Excitation ex;
  ex.axis = a;
  for (int k = 0; k < kMaxExcitationHarmonics; ++k) {
    const int h = k + 1;
    const bool used = h <= n;
    ex.increment[k] = used ? static_cast<std::uint32_t>(static_cast<double>(h) * inc1) : 0u;
    const double frac = -static_cast<double>(h * (h - 1)) / (2.0 * n);
    const double wrapped = frac - std::floor(frac);
    ex.phase[k] = static_cast<std::uint32_t>(static_cast<std::uint64_t>(std::llround(wrapped * kTurn)) & 0xFFFFFFFFu);
    ex.amplitude[k] = used ? Traits::from_double(cmd.amplitude / n) : Traits::zero();
  }
  ex.tick = 0;
  // 0 runs until stopped; any positive duration lasts at least one tick (a
  // 0.1 ms one rounded to 0 and ran until stopped).
  const long long ticks = std::llround(cmd.duration_s * fs);
  ex.duration_ticks = static_cast<std::uint32_t>(cmd.duration_s > 0.0 && ticks < 1 ? 1 : ticks);
  ex.active = true;
  excitation_ = ex;
  status_.excitation_frequency_Hz = static_cast<float>(inc1 * fs / kTurn);
  status_.excitation_axis = static_cast<std::uint8_t>(a);
  return CommandResult::kAccepted;
}

// ---- cross-coupling calibration (issue 15; coupling_calibration.hpp) ------

template <typename Scalar>
void Controller<Scalar>::radii(float r[kAxisCount]) const {
  const Applied& ap = applied();
  for (int a = 0; a < kAxisCount; ++a) {
    r[a] = static_cast<float>(std::sqrt(ap.inertia_over_two_b_star[a] / ap.inertia_over_two_b_star[0]));
  }
}

template <typename Scalar>
CommandResult Controller<Scalar>::start_calibration() {
  if (cal_.running) return CommandResult::kRefusedBusy;
  const SequencerOutput& so = sequencer_.output();
  if (so.state != SequencerState::kReady || !so.motion_allowed) {
    status_.calibration_result = CouplingCalibrationResult::kRefusedNotReady;
    return CommandResult::kRefusedNotReady;
  }
  if (motion_active()) {
    status_.calibration_result = CouplingCalibrationResult::kRefusedBusy;
    return CommandResult::kRefusedBusy;
  }
  const CouplingCalibrationConfig& k = calibration_config_;
  const double fs = static_cast<double>(config_.servo_rate_Hz);
  const double f0 = static_cast<double>(k.fundamental_Hz);
  bool ok = f0 > 0.0 && f0 * kCouplingLines <= static_cast<double>(config_.excitation.max_frequency_Hz) &&
            k.periods >= 1 && k.settle_s >= 0.0f;
  for (float a : k.amplitude_A) ok = ok && a > 0.0f && a <= config_.excitation.max_amplitude_A;
  if (!ok) return CommandResult::kRefusedExcitation;
  Calibration c;
  c.running = true;
  c.increment = static_cast<std::uint32_t>(std::llround(f0 / fs * 4294967296.0));
  const double f0_q = static_cast<double>(c.increment) * fs / 4294967296.0;  // as generated
  c.settle_ticks = static_cast<std::uint32_t>(std::llround(static_cast<double>(k.settle_s) * fs));
  c.window_ticks = static_cast<std::uint32_t>(std::llround(static_cast<double>(k.periods) * fs / f0_q));
  c.previous = config_.coupling;
  cal_ = c;
  identifier_.reset();
  status_.calibration_result = CouplingCalibrationResult::kRunning;
  status_.calibration_experiment = 0;
  return CommandResult::kAccepted;
}

template <typename Scalar>
void Controller<Scalar>::set_coupling(const CouplingCorrection& next) {
  // Ramp from what acts now (identity when off) to next.
  for (int e = 0; e < kCouplingMatrixSize; ++e) {
    ramp_.from[e] = config_.coupling.enabled ? config_.coupling.matrix[e] : identity_entry(e);
  }
  ramp_.left = coupling_ramp_ticks_;
  config_.coupling = next;
}

template <typename Scalar>
void Controller<Scalar>::finish_calibration(CouplingCalibrationResult r, bool restore) {
  if (restore && !same_value_bytes(config_.coupling, cal_.previous)) {
    // The old correction comes back; ramped unless the stage is going down anyway.
    set_coupling(cal_.previous);
    if (!sequencer_.output().motion_allowed) ramp_.left = 0;
  }
  cal_.running = false;
  excitation_.active = false;
  status_.calibration_result = r;
}

// Before excite(): abandon on a fault / state change, else start experiment
// j's excitation (the kernel's multisine, f0..4 f0, axis j's amplitude).
template <typename Scalar>
void Controller<Scalar>::calibrate(Tick& t) {
  if (!cal_.running) return;
  if (!t.so->motion_allowed || t.so->state != SequencerState::kReady) {
    finish_calibration(CouplingCalibrationResult::kAbandonedFault, true);
    return;
  }
  const int j = cal_.experiment % kAxisCount;
  if (cal_.tick == 0) {
    MotionCommand ex;
    ex.type = MotionType::kExcite;
    ex.axis = static_cast<Axis>(j);
    ex.amplitude = static_cast<double>(calibration_config_.amplitude_A[j]);
    ex.frequency_Hz = static_cast<double>(calibration_config_.fundamental_Hz);
    ex.harmonics = static_cast<std::uint8_t>(kCouplingLines);
    ex.duration_s = 0.0;
    if (start_excitation(ex) != CommandResult::kAccepted) {
      finish_calibration(CouplingCalibrationResult::kAbandonedInterrupted, true);
      return;
    }
  } else if (!excitation_.active) {
    finish_calibration(CouplingCalibrationResult::kAbandonedInterrupted, true);
  }
}

// After the axis loops: DFT of U (what goes into the allocation, d included)
// and of Y (pose since the window's start) at the lines; closes experiments.
template <typename Scalar>
void Controller<Scalar>::calibration_accumulate() {
  if (!cal_.running) return;
  const int j = cal_.experiment % kAxisCount;
  if (cal_.tick == cal_.settle_ticks) {
    cal_.start = status_.pose;
    cal_.phase = 0;
  }
  if (cal_.tick >= cal_.settle_ticks) {
    float y[kAxisCount];
    for (int a = 0; a < kAxisCount; ++a) y[a] = PicoToSi(status_.pose.pico[a] - cal_.start.pico[a]);
    identifier_.accumulate(cal_.phase, calib_effort_, y);
    cal_.phase += cal_.increment;
  }
  ++cal_.tick;
  if (cal_.tick < cal_.settle_ticks + cal_.window_ticks) return;
  identifier_.finish_experiment(j);
  cal_.tick = 0;
  ++cal_.experiment;
  status_.calibration_experiment = static_cast<std::uint8_t>(cal_.experiment);
  if (cal_.experiment != kAxisCount && cal_.experiment != 2 * kAxisCount) return;
  float radius[kAxisCount];
  radii(radius);
  float r[kCouplingMatrixSize];
  float coupling = 0.0f, spread = 0.0f;
  CouplingCalibrationResult res = identifier_.solve(radius, r, &coupling, &spread);
  identifier_.reset();
  if (cal_.experiment == kAxisCount) {
    // Identification done: check, then verify with the candidate applied.
    status_.calibration_coupling_before = coupling;
    status_.calibration_inconsistency = spread;
    if (res == CouplingCalibrationResult::kPassed && spread > calibration_config_.max_inconsistency) {
      res = CouplingCalibrationResult::kFailedInconsistent;
    }
    CouplingCorrection next;
    next.enabled = 1;
    if (res == CouplingCalibrationResult::kPassed) {
      CouplingCorrection old = config_.coupling;
      if (!old.enabled) old = CouplingCorrection{};
      res = correction_from(r, old.matrix, radius, calibration_config_, next.matrix);
    }
    if (res != CouplingCalibrationResult::kPassed) {
      finish_calibration(res, false);
      return;
    }
    set_coupling(next);
    // The verification's first settle also covers the ramp.
    cal_.tick = 0;
    if (cal_.settle_ticks < coupling_ramp_ticks_) {
      cal_.settle_ticks = coupling_ramp_ticks_ + cal_.settle_ticks;
    }
    return;
  }
  // Verification done: the coupling with C applied must have dropped.
  status_.calibration_coupling_after = coupling;
  if (res == CouplingCalibrationResult::kPassed &&
      !(coupling * calibration_config_.min_improvement <= status_.calibration_coupling_before)) {
    res = CouplingCalibrationResult::kFailedVerification;
  }
  finish_calibration(res, res != CouplingCalibrationResult::kPassed);
}

template <typename Scalar>
io::ActuatorCommand Controller<Scalar>::step(const io::SensorSample& sample, bool tick_overrun) {
  ++status_.tick;
  // 1. sensors -> pose (integer, constant work).
  PoseMeasurement pose = SensorsToPoseStep(sample, &s2p_);
  status_.pose = pose.pose;
  sequencer_inputs_.homing_done = false;
  sequencer_inputs_.homing_failed = false;
  Tick t(pose, sequencer_inputs_, allocation_out_);
  supervise(sample, tick_overrun, t);
  home(sample, t);
  sequence(t);
  advance_references(t);
  calibrate(t);
  excite(t);
  run_axis_loops(t);
  allocate_forces(t);
  calibration_accumulate();
  const io::ActuatorCommand cmd = coil_currents_to_dac(t);
  publish_status(t, cmd.amplifier_enable);
  return cmd;
}

// 2. supervisor: checks on this sample and last tick's commands.
template <typename Scalar>
void Controller<Scalar>::supervise(const io::SensorSample& sample, bool tick_overrun, Tick& t) {
  const Applied& ap = applied();
  SupervisorInputs& si = t.si;
  si.sample = &sample;
  si.tick_overrun = tick_overrun;
  si.tick = status_.tick;
  const SequencerOutput& prev = sequencer_.output();
  si.positions_valid = prev.homed;
  si.envelope_active = (prev.closed_axes & kAxisBitZ) != 0;
  si.closed_axes = prev.closed_axes;
  // The supervisor compares the pose and the following errors in pm / prad
  // (integer thresholds with the outcome of the float limits): read in place.
  si.pose_pico = status_.pose.pico;
  si.reference_pico = status_.reference.pico;
  // The sequencer reads |e| in SI only in its settle checks: formed then
  // (Sequencer::ReadsFollowingErrors; 6 conversions a tick otherwise).
  if (Sequencer::ReadsFollowingErrors(prev.state)) {
    for (int a = 0; a < kAxisCount; ++a) {
      t.qi.abs_error[a] = std::fabs(PicoToSi(status_.reference.pico[a] - status_.pose.pico[a]));
    }
  }
  si.current_limited = last_current_limited_;
  si.beam_glitch = t.m.beam_glitch;
  si.displacement_bad = t.m.displacement_bad;
  // Only a glitching beam's refused step needs converting (two int64
  // divisions each): the fault record's value, almost never.
  if (t.m.beam_glitch == 0) {
    for (float& v : si.beam_glitch_m) v = 0.0f;
  } else {
    for (int b = 0; b < io::kInterferometerAxes; ++b) {
      si.beam_glitch_m[b] =
          (t.m.beam_glitch & (1u << b)) != 0 ? PicoToSi(CountsToPicometres(t.m.glitch_counts[b], s2p_)) : 0.0f;
    }
  }
  si.stage_profile_error = stage_profile_error_;
  si.coil_current_cmd_A = status_.coil_current_A;  // last tick's, as commanded
  // The supervisor works in float: the measured current is converted to
  // float directly for either kernel. Fixed point used to round it to Q7.24
  // first and convert that (~14 M7 instructions a coil more, 3e-8 A less exact).
  for (int j = 0; j < io::kCoils; ++j) {
    si.coil_current_measured_A[j] =
        MonitorCodeToCurrentFloat_A(sample.coil_current_adc[j], ap.allocation.monitor_A_per_code);
  }
  t.sup = &supervisor_.step(si);
}

// 3. homing (Hall phase + interferometer zero).
template <typename Scalar>
void Controller<Scalar>::home(const io::SensorSample& sample, Tick& t) {
  if (!sequencer_.output().homing_active) {
    homing_ticks_ = 0;
    return;
  }
  if (homing_ticks_ == 0) ReseedInterferometers(&s2p_);
  ++homing_ticks_;
  // The Hall solve's sample is the one kHallSolveSteps ticks before the end
  // of the window, with its unhomed pose: offset = Hall - interferometer of
  // the SAME sample, so motion in between cannot bias it. The solve itself
  // runs in background() meanwhile (it used to take one step per tick here,
  // ~1 300 instructions each; before that, 25 000 on the last tick); if
  // background() has not delivered it by the last tick, it runs here. The
  // same inputs and functions either way: the same bits.
  const std::uint32_t first = homing_needed_ticks_ > static_cast<std::uint32_t>(kHallSolveSteps) + 1u
                                  ? homing_needed_ticks_ - static_cast<std::uint32_t>(kHallSolveSteps)
                                  : homing_needed_ticks_;
  if (homing_ticks_ < first) return;
  if (homing_ticks_ == first) {
    hall_request_ = HallRequest{HallSolveInputsOf(sample, s2p_), t.m.pose_unhomed, hall_request_.generation + 1u};
    if (hall_job_ != HallJob::kRunning) {  // (a job still running is an old one: it keeps its request)
      hall_job_request_ = hall_request_;
      std::atomic_signal_fence(std::memory_order_seq_cst);
      hall_job_ = HallJob::kRequested;
    }
  }
  if (homing_ticks_ < homing_needed_ticks_) return;
  std::atomic_signal_fence(std::memory_order_seq_cst);
  HallResult result;
  if (hall_job_ == HallJob::kDone && hall_job_result_.generation == hall_request_.generation) {
    result = hall_job_result_;
    hall_job_ = HallJob::kIdle;
  } else {
    if (hall_job_ == HallJob::kRequested) hall_job_ = HallJob::kIdle;  // not taken: withdrawn
    result = SolveHoming(hall_request_);
    ++hall_solves_in_tick_;
  }
  const HallPhase& h = result.phase;
  if (h.plausible) {
    SetHomingOffsets(result.offsets, &s2p_);
    // This tick's pose with the new zero, so that references start from the
    // homed pose. (It used to run the whole sensors_to_pose step again on the
    // same sample, which also fed the glitch check a zero step.)
    ApplyHomingOffsets(s2p_, &t.m);
    status_.pose = t.m.pose;
    t.qi.homing_done = true;
  } else {
    t.qi.homing_failed = true;
  }
}

template <typename Scalar>
typename Controller<Scalar>::HallResult Controller<Scalar>::SolveHoming(const HallRequest& request) {
  const HallPhase phase = HallSolveRun(request.inputs);
  const HomingOffsets offsets =
      phase.plausible ? ComputeHomingOffsets(phase, request.pose_unhomed, request.inputs) : HomingOffsets{};
  return HallResult{phase, offsets, request.generation};
}

template <typename Scalar>
MAGLEV_CONFIG_CODE bool Controller<Scalar>::background() {
  if (hall_job_ != HallJob::kRequested) return false;
  hall_job_ = HallJob::kRunning;  // from here on step() leaves the request alone
  std::atomic_signal_fence(std::memory_order_seq_cst);
  const HallRequest request = hall_job_request_;
  hall_job_result_ = SolveHoming(request);
  std::atomic_signal_fence(std::memory_order_seq_cst);
  hall_job_ = HallJob::kDone;
  return true;
}

// 4. sequencer.
template <typename Scalar>
void Controller<Scalar>::sequence(Tick& t) {
  SequencerInputs& qi = t.qi;
  qi.z_valid = t.sup->z_sensors_valid && (t.m.valid_axes & kPoseValidZ) != 0;
  // The measured height as supervise() saw it: homing between them moves x
  // and y only (ApplyHomingOffsets), never z.
  qi.z_m = PicoToSi(status_.pose.pico[axis_index(Axis::kZ)]);
  qi.tilt_references_in_range = tilt_references_in_range_;
  qi.fault_reaction = t.sup->reaction;
  t.so = &sequencer_.step(qi);
}

// 5. references (int64). Open axes: reference = measurement (bumpless
// closing). Profiles advance only while motion is allowed; z follows the
// sequencer until Ready.
template <typename Scalar>
void Controller<Scalar>::advance_references(Tick& t) {
  const Applied& ap = applied();
  const SequencerOutput& so = *t.so;
  // A quiet axis -- closed this tick and the last, no profile, no pending
  // step, and neither the landed-z nor the TiltLock rule applies -- keeps
  // its reference: the general path below would add a zero step and leave
  // it as it is. Most axes on most Ready ticks are quiet; the general path
  // cost ~55 M7 instructions per axis for that.
  const unsigned special = (!so.motion_allowed ? (1u << axis_index(Axis::kZ)) : 0u) |
                           (so.state == SequencerState::kTiltLock
                                ? ((1u << axis_index(Axis::kThetaX)) | (1u << axis_index(Axis::kThetaY)))
                                : 0u);
  const unsigned stays_closed = static_cast<unsigned>(so.closed_axes & t.si.closed_axes) & ~special;
  const unsigned closed_axes = so.closed_axes;
  // What a quiet axis gets (the general path below writes all three too),
  // and which axes are quiet: the general path then visits only the others,
  // in axis order (the circle's x before its y). A per-axis loop with a
  // quiet branch cost ~39 M7 instructions per quiet axis, mostly its own
  // loop bookkeeping; finding the quiet axes from their profiles and int64
  // pending steps each tick cost ~80 more than maybe_busy_axes_ (a superset
  // of the busy axes is enough: the general path leaves a quiet axis as the
  // quiet path does).
  if (!so.motion_allowed) {
    for (Profile& p : profile_) p.kind = ProfileKind::kNone;
  }
#pragma GCC unroll 6
  for (int a = 0; a < kAxisCount; ++a) {
    t.step_pm[a] = 0;
    t.accel_ff[a] = Traits::zero();
  }
  const unsigned quiet = ~maybe_busy_axes_ & ((1u << kAxisCount) - 1u);
  const unsigned busy_axes = ~(quiet & stays_closed) & ((1u << kAxisCount) - 1u);
  // The general path writes the visited axes' accelerations; the others'
  // are zero, and only those written nonzero before need it again.
  for (unsigned m = reference_acceleration_set_ & ~busy_axes; m != 0; m &= m - 1u) {
    status_.reference_acceleration[__builtin_ctz(m)] = 0.0;
  }
  reference_acceleration_set_ = busy_axes;
  for (unsigned busy = busy_axes; busy != 0; busy &= busy - 1u) {
    const int a = __builtin_ctz(busy);
    const bool closed = (closed_axes & (1u << a)) != 0;
    Profile& p = profile_[a];
    double acc_now = 0.0;
    AxisReference r{};
    bool sampled = false;
    switch (p.kind) {
      case ProfileKind::kMove:
        r = move_[a].sample(++p.tick);
        sampled = true;
        if (move_[a].done(p.tick)) p.kind = ProfileKind::kNone;  // this sample is the target
        break;
      case ProfileKind::kSinusoid:
        r = sinusoid_[a].sample(++p.tick);
        sampled = true;
        if (sinusoid_[a].done(p.tick)) p.kind = ProfileKind::kNone;
        break;
      case ProfileKind::kCircle:
        if (a == axis_index(Axis::kX)) {
          ++p.tick;
          circle_.sample(p.tick, &r, &circle_y_);
          sampled = true;
          circle_y_valid_ = true;
          if (circle_.done(p.tick)) {
            p.kind = ProfileKind::kNone;
            circle_y_last_ = true;
          }
        } else if (circle_y_valid_) {
          r = circle_y_;
          sampled = true;
          circle_y_valid_ = false;
          if (circle_y_last_) {
            p.kind = ProfileKind::kNone;
            circle_y_last_ = false;
          }
        }
        break;
      case ProfileKind::kStop:
        r = stop_[a].sample(++p.tick);
        sampled = true;
        if (stop_[a].done(p.tick)) p.kind = ProfileKind::kNone;
        break;
      case ProfileKind::kNone:
        break;
    }
    if (sampled) {
      status_.reference.pico[a] = r.position_pico;
      acc_now = static_cast<double>(r.acceleration);
    }
    t.step_pm[a] = closed ? pending_step_pm_[a] : 0;
    // A profile planned in the tick its axis' step was given starts from the
    // stepped reference (command()): its sample holds the step already.
    if (!sampled) status_.reference.pico[a] += t.step_pm[a];
    pending_step_pm_[a] = 0;
    const bool newly_closed = closed && (t.si.closed_axes & (1u << a)) == 0;
    if (!closed || newly_closed) {
      status_.reference.pico[a] = status_.pose.pico[a];  // bumpless: close on the present position
    } else if (a == axis_index(Axis::kZ) && !so.motion_allowed) {
      status_.reference.pico[a] = numeric::si_to_pico(static_cast<double>(so.z_reference_m));
    } else if (a >= axis_index(Axis::kThetaX) && so.state == SequencerState::kTiltLock) {
      // The tilt loops closed on the tilt they found. A CoM offset c tilts
      // the lifting platen by m g c / k_t (57.5 urad/mm on the seed stage), so
      // a few mm put it beyond the reference range, where every tilt command
      // would be refused: ramp such a reference to the range's nearest end.
      const int k = a - axis_index(Axis::kThetaX);
      std::int64_t& ref = status_.reference.pico[a];
      if (ref > tilt_max_pico_[k]) ref = (ref - tilt_max_pico_[k] > tilt_level_step_pico_) ? ref - tilt_level_step_pico_ : tilt_max_pico_[k];
      if (ref < tilt_min_pico_[k]) ref = (tilt_min_pico_[k] - ref > tilt_level_step_pico_) ? ref + tilt_level_step_pico_ : tilt_min_pico_[k];
    }
    status_.reference_acceleration[a] = acc_now;
    if (p.kind == ProfileKind::kNone) maybe_busy_axes_ &= ~(1u << a);  // its pending step is applied
    // u_ff = (m or I) a / (2 b*) in double (a in SI, up to 1.5e6 um/s^2 would
    // not fit a Scalar), one rounding to A.
    // No profile sample: acc_now is 0 and (m or I) / (2 b*) > 0 (b* > 0 and
    // masses >= 0 are checked at configuration), so the product is +0.
    t.accel_ff[a] = (config_.acceleration_feedforward && sampled)
                        ? Traits::from_double(acc_now * ap.inertia_over_two_b_star[a])
                        : Traits::zero();
  }
  // Only TiltLock reads it (next tick); false elsewhere, so the first TiltLock
  // tick does not count as in range before it was checked.
  const std::int64_t tx = status_.reference.pico[axis_index(Axis::kThetaX)], ty = status_.reference.pico[axis_index(Axis::kThetaY)];
  tilt_references_in_range_ = so.state == SequencerState::kTiltLock && tx >= tilt_min_pico_[0] &&
                              tx <= tilt_max_pico_[0] && ty >= tilt_min_pico_[1] && ty <= tilt_max_pico_[1];
}

// 5b. excitation d (while one runs, every harmonic slot runs).
template <typename Scalar>
void Controller<Scalar>::excite(Tick& t) {
  Excitation& ex = excitation_;
  if (ex.active && (!t.so->motion_allowed || (ex.duration_ticks != 0 && ex.tick >= ex.duration_ticks))) {
    ex.active = false;
  }
  // The harmonic sum and the phase advance only while an excitation runs:
  // its output is zero otherwise, and start_excitation() sets every phase
  // afresh, so phases advanced while idle were never read.
  Scalar d_sum = Traits::zero();
  if (ex.active) {
    for (int k = 0; k < kMaxExcitationHarmonics; ++k) {
      d_sum += ex.amplitude[k] * Traits::sin(ex.phase[k]);  // the kernel's table
    }
    for (int k = 0; k < kMaxExcitationHarmonics; ++k) ex.phase[k] += ex.increment[k];  // uint32 wrap = one turn
  }
  for (int a = 0; a < kAxisCount; ++a) t.excitation[a] = (ex.active && a == ex.axis) ? d_sum : Traits::zero();
  ex.tick += ex.active ? 1u : 0u;
  // External injection (lab wave generator): same rule as kExcite (motion
  // allowed), clamped here whatever the generator checked.
  // A NaN value injects nothing (it would reach the loops, and the int64
  // reference below, as no number).
  const Injection& in = injection_;
  if (in.active && t.so->motion_allowed && in.axis < kAxisCount) {
    t.injecting = true;
    const float value = in.value == in.value ? in.value : 0.0f;
    if (in.at_reference) {
      const float lim = config_.references.max_step[in.axis];
      const float v = value > lim ? lim : (value < -lim ? -lim : value);
      // Truncated toward zero as static_cast<int64_t> would, without its libgcc
      // call (__aeabi_d2lz on the M7): |v| <= max_step * 1e12, far below 2^51.
      const std::int64_t asked_pm = numeric::TruncToInt64(static_cast<double>(v) * 1e12);
      std::int64_t pm = asked_pm;
      // The injected reference stays inside the axis' travel, as every
      // planned reference does (a +9.9 um injection on a z reference of
      // 37.9 um took the stage to 40.2 um, out of its envelope).
      const std::int64_t ref = status_.reference.pico[in.axis];
      const std::int64_t up = numeric::si_to_pico(static_cast<double>(config_.references.position_max[in.axis])) - ref;
      const std::int64_t down = numeric::si_to_pico(static_cast<double>(config_.references.position_min[in.axis])) - ref;
      if (pm > up) pm = up > 0 ? up : 0;
      if (pm < down) pm = down < 0 ? down : 0;
      t.reference_injection_pm = pm;
      t.reference_injection = pm == asked_pm ? v : PicoToSi(pm);
    } else {
      // The sum with a running kExcite (or a calibration's excitation) on the
      // same axis is held to the same bound as each: alone, each was within
      // it and the sum reached twice it.
      const float lim = config_.excitation.max_amplitude_A;
      const float d = value > lim ? lim : (value < -lim ? -lim : value);
      if (t.excitation[in.axis] == Traits::zero()) {
        t.excitation[in.axis] += Traits::from_float(d);  // (+= keeps the sign of a zero as before)
      } else {
        const float sum = Traits::to_float(t.excitation[in.axis]) + d;
        t.excitation[in.axis] = Traits::from_float(sum > lim ? lim : (sum < -lim ? -lim : sum));
      }
    }
  }
}

// 6. axis loops (all run; outputs selected by the closed mask). Every axis a
// PID (the usual configuration): the loops without their type tests.
template <typename Scalar>
void Controller<Scalar>::run_axis_loops(Tick& t) {
  in_loop_form([&](auto pid_only) { run_axis_loops_as<decltype(pid_only)::value>(t); });
}

template <typename Scalar>
template <bool kPidOnly>
void Controller<Scalar>::run_axis_loops_as(Tick& t) {
  const Applied& ap = applied();
  const SequencerOutput& so = *t.so;
  const Scalar ff_fraction = Traits::from_float(so.feedforward_fraction);
  // The sequencer's fraction may exceed 1 (cable stiffness, payload margin),
  // so it scales the full lift effort precomputed at apply time
  // (GravityFeedForward_A would clamp the ramp to [0, 1]).
  const Scalar gravity_A = ff_fraction * ap.allocation.gravity_effort_A;
  // The external reference injection enters the loop's error in pico (before
  // the Scalar conversion and its +-128 um saturation): added to the stored
  // reference for the loops only, taken off again below (exact integers).
  const int inj_axis = injection_.axis;
  if (t.reference_injection_pm != 0) status_.reference.pico[inj_axis] += t.reference_injection_pm;
  const auto axis = [&](int a) __attribute__((always_inline)) {
    AxisLoop<Scalar, kPidOnly> l = loop<kPidOnly>(ap, a);
    // Only the error (and this tick's explicit step) become Scalar: +-128 um.
    const Scalar e_um = numeric::pico_to_micro<Scalar>(status_.reference.pico[a] - status_.pose.pico[a]);
    // The explicit step is zero on almost every tick (0 pm is exactly 0).
    const Scalar dr_um = t.step_pm[a] == 0 ? Traits::zero() : numeric::pico_to_micro<Scalar>(t.step_pm[a]);
    const Scalar ff = a == axis_index(Axis::kZ) ? gravity_A + t.accel_ff[a] : t.accel_ff[a];
    const Scalar v_loop = l.update(e_um, dr_um, ff);
    const Scalar v = filters_.update(a, ap.filter[a], ap.filtered[a], v_loop);
    t.aw_offset[a] = v_loop - v;
    const Scalar loop_out = l.saturate(v);
    // Published as it is made (publish_status() zeroes it with the amplifiers off).
    status_.loop_effort_A[a] = Traits::to_float(loop_out);
    const bool closed = (so.closed_axes & (1u << a)) != 0;
    // Open axis: no feedback, only the feed-forward (the gravity lift of z).
    // Closed axis: the loop plus the excitation d (zero unless kExcite runs).
    t.effort[a] = closed ? loop_out + t.excitation[a] : (a == axis_index(Axis::kZ) ? gravity_A : Traits::zero());
    if (!closed) l.reset(e_um);
  };
  // The PID-only form unrolled (the usual configuration's tick); the form
  // with internal-model axes rolled: unrolled it took 9 992 B of the board's
  // ITCM, rolled ~1.7 KB, for +3.6 % of such a configuration's tick (the
  // cross stage with internal-model x and y: Ready max 3 625 -> 3 755, test
  // kernel-bitexact-qemu-m7-nk2017-cross-internal-model; docs/PERFORMANCE.md).
  if constexpr (kPidOnly) {
#pragma GCC unroll 6
    for (int a = 0; a < kAxisCount; ++a) axis(a);
  } else {
#pragma GCC unroll 1
    for (int a = 0; a < kAxisCount; ++a) axis(a);
  }
  filters_.end_tick();
  if (t.reference_injection_pm != 0) status_.reference.pico[inj_axis] -= t.reference_injection_pm;
}

// 7. force allocation with the whole-vector current limit, then 8. the
// anti-windup: the loops learn what was really applied (k U). The loop's
// share of k U is k U - d; the comparison is against the signal that entered
// the clamp (after the biquads), so the back-calculation sees exactly the
// clamp + current-limit loss: pass (k U - d) + (v_loop - v_filtered).
template <typename Scalar>
void Controller<Scalar>::allocate_forces(Tick& t) {
  const Applied& ap = applied();
  // Cross-coupling correction U' = C U (issue 15): only when one is set or
  // ramping, so the default kernel's arithmetic is untouched.
  const bool coupled = config_.coupling.enabled != 0 || ramp_.left != 0;
  status_.coupling_correction_active = coupled;
  if (cal_.running) {
    for (int a = 0; a < kAxisCount; ++a) calib_effort_[a] = Traits::to_float(t.effort[a]);
  }
  if (!coupled) {
    AllocateCurrents<Scalar>(t.effort, status_.pose.pico[0], status_.pose.pico[1], ap.allocation, &t.out);
  } else {
    float c[kCouplingMatrixSize];
    const float w = static_cast<float>(ramp_.left) / static_cast<float>(coupling_ramp_ticks_);  // weight of `from`
    for (int e = 0; e < kCouplingMatrixSize; ++e) {
      const float to = config_.coupling.enabled ? config_.coupling.matrix[e] : identity_entry(e);
      c[e] = to + w * (ramp_.from[e] - to);
    }
    if (ramp_.left != 0) --ramp_.left;
    float u[kAxisCount];
    for (int a = 0; a < kAxisCount; ++a) u[a] = Traits::to_float(t.effort[a]);
    Scalar corrected[kAxisCount];
    for (int i = 0; i < kAxisCount; ++i) {
      float s = 0.0f;
      for (int j = 0; j < kAxisCount; ++j) s += c[i * kAxisCount + j] * u[j];
      corrected[i] = Traits::from_float(s);
    }
    AllocateCurrents<Scalar>(corrected, status_.pose.pico[0], status_.pose.pico[1], ap.allocation, &t.out);
    // The loops' anti-windup works in uncorrected efforts: what they got is k U.
    for (int a = 0; a < kAxisCount; ++a) t.out.applied_effort_A[a] = t.out.scale_k * t.effort[a];
  }
  in_loop_form([&](auto pid_only) { apply_loop_limits_as<decltype(pid_only)::value>(t); });
}

// 8. the anti-windup, axis by axis (allocate_forces()).
template <typename Scalar>
template <bool kPidOnly>
void Controller<Scalar>::apply_loop_limits_as(Tick& t) {
  const Applied& ap = applied();
  const bool antiwindup = config_.antiwindup;
#pragma GCC unroll 6
  for (int a = 0; a < kAxisCount; ++a) {
    AxisLoop<Scalar, kPidOnly> l = loop<kPidOnly>(ap, a);
    const bool closed = (t.so->closed_axes & (1u << a)) != 0;
    const Scalar applied_loop = t.out.applied_effort_A[a] - t.excitation[a] + t.aw_offset[a];
    // Open axes (state reset) and anti-windup off: no correction.
    l.apply_limit((closed && antiwindup) ? applied_loop : l.last_output());
  }
}

// 9. coil currents -> DAC codes; amplifiers only when the sequencer says so.
template <typename Scalar>
io::ActuatorCommand Controller<Scalar>::coil_currents_to_dac(const Tick& t) {
  const Applied& ap = applied();
  io::ActuatorCommand cmd = io::kSafeActuatorCommand;
  const bool enable = t.so->amplifier_enable;
  if (enable) {
    for (int j = 0; j < io::kCoils; ++j) {
      cmd.dac_code[j] = CurrentToDacCode<Scalar>(t.out.current_A[j], ap.allocation);
      status_.coil_current_A[j] = Traits::to_float(t.out.current_A[j]);
    }
  } else {  // the safe command's codes are already 0
    for (float& i : status_.coil_current_A) i = 0.0f;
  }
  cmd.amplifier_enable = enable;
  last_current_limited_ = enable && t.out.saturated;
  return cmd;
}

// 10. status.
template <typename Scalar>
void Controller<Scalar>::publish_status(const Tick& t, bool enable) {
  const SequencerOutput& so = *t.so;
  const SupervisorStatus& sup = *t.sup;
  // status_.pose and status_.reference are the tick's own pose and reference
  // (written where they are made): nothing to copy.
  status_.pose_valid = t.m.valid_axes;
  status_.state = so.state;
  status_.last_reason = so.last_reason;
  status_.closed_axes = so.closed_axes;
  status_.feedforward_fraction = so.feedforward_fraction;
  status_.fault = sup.first_fault.code;
  status_.first_fault = sup.first_fault;
  status_.reaction = sup.reaction;
  status_.saturated = t.out.saturated;
  status_.scale_k = Traits::to_float(t.out.scale_k);
  if (enable) {
    for (int a = 0; a < kAxisCount; ++a) {
      status_.effort_A[a] = Traits::to_float(t.effort[a]);
      status_.applied_effort_A[a] = Traits::to_float(t.out.applied_effort_A[a]);
    }
  } else {
    for (int a = 0; a < kAxisCount; ++a) {
      status_.effort_A[a] = status_.loop_effort_A[a] = status_.applied_effort_A[a] = 0.0f;
    }
  }
  for (int a = 0; a < kAxisCount; ++a) {
    status_.excitation_A[a] = Traits::to_float(t.excitation[a]);
  }
  status_.injection_active = t.injecting;
  status_.injection_at_reference = injection_.at_reference;
  status_.injection_axis = injection_.axis;
  status_.reference_injection = t.reference_injection;
  status_.excitation_active = excitation_.active;
  status_.excitation_tick = excitation_.tick;
  status_.motion_active = motion_active();
  status_.lds_target_steps = s2p_.lds_steps_repaired;
}

template <typename Scalar>
bool Controller<Scalar>::motion_active() const {
  if (excitation_.active || injection_.active) return true;
  for (unsigned m = maybe_busy_axes_; m != 0; m &= m - 1u) {
    const int a = __builtin_ctz(m);
    if (profile_[a].kind != ProfileKind::kNone || pending_step_pm_[a] != 0) return true;
  }
  return false;
}

template class Controller<float>;
template class Controller<numeric::Q7_24>;

}  // namespace maglev::kernel
