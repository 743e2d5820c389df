#include "maglev/bench/campaign.hpp"

#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "maglev/bench/run_hooks.hpp"
#include "maglev/bench/runner.hpp"
#include "maglev/can_link/catalog.hpp"
#include "maglev/force_allocation/force_allocation.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/modbus/register_server.hpp"
#include "maglev/persistence/config_store.hpp"
#include "maglev/persistence/power_cut_flash.hpp"
#include "maglev/scenario/scenario.hpp"

namespace maglev::bench {

const char* to_string(CampaignFault f) {
  switch (f) {
#define MAGLEV_CAMPAIGN_NAME(name, text, category) \
  case CampaignFault::name:                        \
    return text;
    MAGLEV_CAMPAIGN_FAULTS(MAGLEV_CAMPAIGN_NAME)
#undef MAGLEV_CAMPAIGN_NAME
    case CampaignFault::kCount:
      break;
  }
  return "?";
}

const char* category_of(CampaignFault f) {
  switch (f) {
#define MAGLEV_CAMPAIGN_CATEGORY(name, text, category) \
  case CampaignFault::name:                            \
    return category;
    MAGLEV_CAMPAIGN_FAULTS(MAGLEV_CAMPAIGN_CATEGORY)
#undef MAGLEV_CAMPAIGN_CATEGORY
    case CampaignFault::kCount:
      break;
  }
  return "?";
}

namespace {

namespace st = io::stage;

constexpr double kDuration_s = 7.0;       // levitation ~3.4 s, motions and faults, 2 s to land
constexpr double kFaultWindow0_s = 3.8;   // the stage is Ready by then (checked)
constexpr double kFaultWindow1_s = 4.8;
// A contact while an actuator or plant fault acts, or within this long after
// it, is forced by the fault: judged against the drop bound, not the landing's.
constexpr double kForcedContactWindow_s = 0.5;
constexpr double kJudgeAfterFault_s = 2.0;  // a latched fault must have landed the stage by then

// The frame kinds a CAN fault strikes.
constexpr can::MessageKind kTargetFrames[] = {can::MessageKind::kSensor, can::MessageKind::kActuator,
                                              can::MessageKind::kCurrentMonitor,
                                              can::MessageKind::kControllerStatus,
                                              can::MessageKind::kHeartbeatController};

std::uint64_t mix(std::uint64_t x) {  // splitmix64
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// v with `decimals` digits after the point.
std::string fixed(double v, int decimals) {
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

}  // namespace

CampaignPlan MakePlan(std::uint64_t seed, int index) {
  CampaignPlan p;
  p.run_seed = mix(mix(seed) ^ static_cast<std::uint64_t>(index));
  std::mt19937_64 rng(p.run_seed);
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto pick = [&](int n) { return static_cast<int>(std::uniform_int_distribution<int>(0, n - 1)(rng)); };
  auto sign = [&]() { return pick(2) == 0 ? -1.0 : 1.0; };

  // A random mix of the suite's motions while the faults strike.
  const int motions = 1 + pick(3);
  for (int m = 0; m < motions; ++m) {
    const double t = uni(kFaultWindow0_s - 0.1, kFaultWindow1_s);
    switch (pick(5)) {
      case 0: p.motions.push_back((fixed(t, 4)) + " step x " + (fixed(sign() * uni(1, 8), 2) + "um")); break;
      case 1: p.motions.push_back((fixed(t, 4)) + " step y " + (fixed(sign() * uni(1, 8), 2) + "um")); break;
      case 2: p.motions.push_back((fixed(t, 4)) + " step z " + (fixed(sign() * uni(0.5, 2), 2) + "um")); break;
      case 3: p.motions.push_back((fixed(t, 4)) + " step theta_z " + (fixed(sign() * uni(1, 20), 2) + "urad")); break;
      default:
        p.motions.push_back((fixed(t, 4)) + " move x " + (fixed(sign() * uni(0.5, 3), 3) + "mm") + " 60mm/s 0.6m/s^2");
        break;
    }
  }
  const int n_faults = 1 + pick(2);
  for (int f = 0; f < n_faults; ++f) {
    FaultEvent e;
    // Kinds added after the first campaign (from kConfigWrite on) come from
    // their own stream below, so that every run index keeps the plan it had:
    // a replay command in a report or a test stays the same run.
    e.kind = static_cast<CampaignFault>(pick(static_cast<int>(CampaignFault::kConfigWrite)));
    e.t_s = uni(kFaultWindow0_s, kFaultWindow1_s);
    // The campaign's runs are at the default servo rate (their plans are
    // replayable by run index; no --servo-rate), so its tick is that one's.
    const double tick = 1.0 / st::kServoRate_Hz;
    const double ticks_1_150 = tick * (1 + pick(150));  // the 1-150 ticks
    e.duration_s = ticks_1_150;
    switch (e.kind) {
      case CampaignFault::kCanLoss:
      case CampaignFault::kCanCorrupt:
      case CampaignFault::kCanDuplicate:
      case CampaignFault::kCanReorder:
        e.target = pick(static_cast<int>(std::size(kTargetFrames)));
        break;
      case CampaignFault::kCanBurstLoss:
        // One in four is a link that dies for up to a second.
        if (pick(4) == 0) e.duration_s = uni(0.1, 1.0);
        break;
      case CampaignFault::kCanDelay:
        e.target = pick(static_cast<int>(std::size(kTargetFrames)));
        e.magnitude = 1 + pick(6);  // frames held back
        break;
      case CampaignFault::kBabblingNode:
        e.magnitude = 1 + pick(20);  // frames per tick
        break;
      case CampaignFault::kBeamLoss:
      case CampaignFault::kLaserOutOfRange:
      case CampaignFault::kAdcRailed:
      case CampaignFault::kAdcStuck:
        e.target = pick(3);
        break;
      case CampaignFault::kCountJump:
        e.target = pick(3);
        e.magnitude = sign() * std::pow(10.0, uni(1.0, 6.0));  // counts, kept from then on
        e.duration_s = kDuration_s;
        break;
      case CampaignFault::kHallStuck:
      case CampaignFault::kStaleSample:
        break;
      case CampaignFault::kAmplifierSaturation:
        e.magnitude = uni(0.5, 3.5);  // A: the amplifier's output clips there
        break;
      case CampaignFault::kAmplifierOpen:
      case CampaignFault::kAmplifierShorted:
      case CampaignFault::kDacStuck:
        e.target = pick(io::kCoils);
        if (pick(3) == 0) e.duration_s = uni(0.1, 1.0);  // a failure that stays
        break;
      case CampaignFault::kGainDrop:
        e.target = pick(io::kCoils + 1);  // kCoils: every coil
        e.magnitude = uni(0.3, 0.95);
        if (pick(3) == 0) e.duration_s = uni(0.1, 1.0);
        break;
      case CampaignFault::kPush:
        e.target = pick(3);                   // x, y, z
        e.magnitude = sign() * uni(0.2, 3.0);  // N
        e.duration_s = uni(0.005, 0.05);
        break;
      case CampaignFault::kPayloadAdded:
        e.magnitude = uni(0.02, 0.6);  // kg, unknown to the controller, stays on
        e.duration_s = kDuration_s;
        break;
      case CampaignFault::kBrownoutDuringSave:
        e.magnitude = uni(0.0, 1.0);  // where in the save the power goes
        break;
      case CampaignFault::kCommandStorm:
        e.magnitude = 20 + pick(200);  // commands
        e.duration_s = uni(0.01, 0.2);
        break;
      case CampaignFault::kCommandOutOfRange:
        e.target = pick(4);
        break;
      case CampaignFault::kConfigWrite:  // drawn below
      case CampaignFault::kCount:
        break;
    }
    p.faults.push_back(e);
  }
  // A host configuration write mid-motion in one run of 16, from its own
  // stream (see above). Variants, on a random axis:
  //   0: gains x1.5, live tuning off (must be refused while levitated);
  //   1: live tuning on, kp and kd x0.7-1.4 (applied if the loop check passes);
  //   2: live tuning on, kp and kd x20 (the loop check should refuse them);
  //   3: the supervisor's z envelope halved (must be refused while levitated).
  // target = variant * 10 + axis; magnitude = the gain factor.
  std::mt19937_64 host_rng(mix(p.run_seed ^ 0xC0F16u));
  auto host_pick = [&](int n) { return static_cast<int>(std::uniform_int_distribution<int>(0, n - 1)(host_rng)); };
  if (host_pick(16) == 0) {
    FaultEvent e;
    e.kind = CampaignFault::kConfigWrite;
    e.t_s = std::uniform_real_distribution<double>(kFaultWindow0_s, kFaultWindow1_s)(host_rng);
    e.duration_s = 1.0 / st::kServoRate_Hz;
    e.target = host_pick(4) * 10 + host_pick(kernel::kAxisCount);
    e.magnitude = e.target / 10 == 1   ? std::uniform_real_distribution<double>(0.7, 1.4)(host_rng)
                  : e.target / 10 == 2 ? 20.0
                                       : 1.5;
    p.faults.push_back(e);
  }
  std::sort(p.faults.begin(), p.faults.end(), [](const FaultEvent& a, const FaultEvent& b) { return a.t_s < b.t_s; });
  return p;
}

namespace {

bool must_land(CampaignFault k) {
  // Faults that remove a sensor the levitated stage needs: the controller must
  // detect them and land (the supervisor's sensor plausibility checks).
  return k == CampaignFault::kBeamLoss || k == CampaignFault::kLaserOutOfRange || k == CampaignFault::kAdcRailed;
}

struct RunVerdict {
  int index = 0;
  std::uint64_t run_seed = 0;
  std::vector<std::string> unsafe;  // empty: safe
  std::string invalid;              // the run could not judge (no levitation before the faults)
  std::string fault_code = "None";
  double detect_s = -1.0;           // first fault latched - first fault start
  std::string path;                 // sequencer states after the first fault
  double max_current_A = 0.0;
  double touchdown_speed_m_per_s = 0.0;
  bool touchdown_amplifiers_on = false;
  double max_controlled_touchdown_m_per_s = 0.0;  // contacts judged as controlled landings
  bool landed_at_end = false;
  std::uint64_t missed_actuator_frames = 0;
  std::string config_write;  // the kernel's answer to a host configuration write
};

class CampaignHooks final : public RunHooks {
 public:
  CampaignHooks(const CampaignPlan& plan, double rated_current_A, double landing_speed_m_per_s)
      : plan_(plan), rng_(plan.run_seed ^ 0xC0FFEEull), rated_A_(rated_current_A), landing_speed_(landing_speed_m_per_s) {
    kernel::ForceAllocationConfig ac = kernel::default_kernel_config().allocation;
    kernel::ForceAllocationState<float> alloc{};
    kernel::ApplyForceAllocationConfig<float>(ac, &alloc);
    codes_per_A_ = alloc.dac_codes_per_A;
    first_fault_s_ = plan.faults.empty() ? kDuration_s : plan.faults.front().t_s;
  }

  void attach(can::VirtualBus& bus) override { babbler_ = bus.open_endpoint(64); }

  // --- a host configuration write mid-motion -----------------------------------
  bool config_write_due(std::uint64_t, double t_s) override {
    // The plan's faults are in time order: the next write not yet made.
    std::size_t k = 0;
    for (const FaultEvent& e : plan_.faults) {
      if (e.kind != CampaignFault::kConfigWrite) continue;
      if (k++ < config_writes_done_) continue;
      if (t_s < e.t_s) return false;
      config_event_ = &e;
      ++config_writes_done_;
      return true;
    }
    return false;
  }

  void make_config_write(kernel::KernelConfig* c) override {
    const FaultEvent& e = *config_event_;
    const int axis = e.target % 10;
    const auto factor = static_cast<float>(e.magnitude);
    before_ = *c;
    kernel::Pid2DofConfig& pid = c->axis[axis].pid;
    switch (e.target / 10) {
      case 0:
        pid.kp *= factor;
        break;
      case 1:
      case 2:
        c->live_tuning = true;
        pid.kp *= factor;
        pid.kd *= factor;
        break;
      default:
        c->supervisor.z_max_m *= 0.5f;
        break;
    }
    written_ = *c;
    config_axis_ = axis;
  }

  void config_result(kernel::ConfigError r, const kernel::KernelConfig& in_force) override {
    v_.config_write += (v_.config_write.empty() ? "" : ",") + std::string(hil::to_string(r));
    const kernel::Pid2DofConfig& now = in_force.axis[config_axis_].pid;
    const kernel::KernelConfig& expect = r == kernel::ConfigError::kOk ? written_ : before_;
    const kernel::Pid2DofConfig& want = expect.axis[config_axis_].pid;
    // A refused write changes nothing; an accepted one is what was written.
    if (now.kp != want.kp || now.kd != want.kd || in_force.live_tuning != expect.live_tuning ||
        in_force.supervisor.z_max_m != expect.supervisor.z_max_m) {
      unsafe(std::string("configuration write ") + v_.config_write + " left a different configuration in force");
    }
    // Gains without live tuning, and a supervisor limit, are locked while
    // the stage is off its rest. Gains x20 with live tuning are judged by
    // what they do to the plant (the loop check should refuse them).
    const FaultEvent& e = *config_event_;
    const bool off_rest = last_state_ != kernel::SequencerState::kIdle && last_state_ != kernel::SequencerState::kFault;
    if (off_rest && (e.target / 10 == 0 || e.target / 10 == 3) && r == kernel::ConfigError::kOk) {
      unsafe("a configuration write that must be refused while levitated was applied");
    }
  }

  void before_tick(std::uint64_t n, double t_s, hil::Plant& plant) override {
    n_ = n;
    t_ = t_s;
    Eigen::Vector3d force = Eigen::Vector3d::Zero();
    for (const FaultEvent& e : plan_.faults) {
      const bool on = active(e);
      switch (e.kind) {
        case CampaignFault::kBeamLoss:
          plant.set_beam_loss(e.target, on);
          break;
        case CampaignFault::kPush:
          if (on) force[e.target] += e.magnitude;
          break;
        case CampaignFault::kPayloadAdded:
          if (on) force[2] -= e.magnitude * st::kGravity_m_per_s2;
          break;
        case CampaignFault::kBabblingNode:
          if (on && babbler_) babble(static_cast<int>(e.magnitude));
          break;
        default:
          break;
      }
    }
    plant.set_external_force(force);
    if (babbler_) {  // the babbler's own receive queue: drained, unread
      can::CanFrame f{};
      while (babbler_->pending() > 0 && babbler_->receive(f, 0u) == can::PortStatus::kOk) {
      }
    }
  }

  void on_sensor_sample(std::uint64_t, double, io::SensorSample* s) override {
    for (std::size_t i = 0; i < plan_.faults.size(); ++i) {
      const FaultEvent& e = plan_.faults[i];
      if (!active(e)) {
        frozen_[i] = false;
        continue;
      }
      switch (e.kind) {
        case CampaignFault::kCountJump:
          s->interferometer_counts[e.target] += static_cast<std::uint32_t>(static_cast<std::int32_t>(e.magnitude));
          break;
        case CampaignFault::kLaserOutOfRange:
          s->status_flags = static_cast<std::uint16_t>(s->status_flags | (io::kDisplacementOutOfRange0 << e.target));
          break;
        case CampaignFault::kAdcRailed:
          s->displacement_adc[e.target] = 32767;
          break;
        case CampaignFault::kHallStuck:
        case CampaignFault::kAdcStuck:
        case CampaignFault::kStaleSample:
          if (!frozen_[i]) {
            frozen_sample_[i] = *s;
            frozen_[i] = true;
          }
          if (e.kind == CampaignFault::kHallStuck) {
            std::memcpy(s->hall_adc, frozen_sample_[i].hall_adc, sizeof s->hall_adc);
          } else if (e.kind == CampaignFault::kAdcStuck) {
            s->displacement_adc[e.target] = frozen_sample_[i].displacement_adc[e.target];
          } else {
            *s = frozen_sample_[i];  // a stale value, unflagged
          }
          break;
        default:
          break;
      }
    }
  }

  can::FaultAction on_frame(const can::CanFrame& frame, std::uint64_t) override {
    can::FaultAction a{};
    for (const FaultEvent& e : plan_.faults) {
      if (!active(e) || std::strcmp(category_of(e.kind), "can") != 0) continue;
      // Only the CAN kinds carry a frame-kind index in `target`.
      const bool target = e.target >= 0 && e.target < static_cast<int>(std::size(kTargetFrames)) &&
                          frame.id == can::message(kTargetFrames[e.target]).can_id;
      switch (e.kind) {
        case CampaignFault::kCanBurstLoss:
          a.kind = can::FaultAction::kDrop;
          return a;
        case CampaignFault::kCanLoss:
          if (target) a.kind = can::FaultAction::kDrop;
          break;
        case CampaignFault::kCanCorrupt:
          if (target) {
            a.kind = can::FaultAction::kCorrupt;
            a.corrupt_bit = static_cast<std::uint16_t>(rng_() % 512);
          }
          break;
        case CampaignFault::kCanDuplicate:
          if (target) a.kind = can::FaultAction::kDuplicate;
          break;
        case CampaignFault::kCanReorder:
        case CampaignFault::kCanDelay:
          if (target) {
            a.kind = can::FaultAction::kDelay;
            a.delay_frames = e.kind == CampaignFault::kCanReorder ? 1u : static_cast<std::uint32_t>(e.magnitude);
          }
          break;
        default:
          break;
      }
    }
    return a;
  }

  void on_actuator(std::uint64_t, double, io::ActuatorCommand* a) override {
    for (std::size_t i = 0; i < plan_.faults.size(); ++i) {
      const FaultEvent& e = plan_.faults[i];
      if (!active(e)) {
        frozen_[i] = false;
        continue;
      }
      auto code_of = [&](double amps) { return static_cast<std::int16_t>(std::lround(amps * codes_per_A_)); };
      switch (e.kind) {
        case CampaignFault::kAmplifierSaturation: {
          const std::int16_t lim = code_of(e.magnitude);
          for (auto& c : a->dac_code) c = std::clamp<std::int16_t>(c, static_cast<std::int16_t>(-lim), lim);
          break;
        }
        case CampaignFault::kAmplifierOpen:
          a->dac_code[e.target] = 0;
          break;
        case CampaignFault::kAmplifierShorted:
          // The output stage fails to its rail: the amplifier's own limit (the rating).
          if (a->amplifier_enable) a->dac_code[e.target] = code_of(rated_A_);
          break;
        case CampaignFault::kGainDrop:
          for (int j = 0; j < io::kCoils; ++j) {
            if (e.target == io::kCoils || e.target == j) {
              a->dac_code[j] = static_cast<std::int16_t>(std::lround(a->dac_code[j] * e.magnitude));
            }
          }
          break;
        case CampaignFault::kDacStuck:
          if (!frozen_[i]) {
            frozen_code_[i] = a->dac_code[e.target];
            frozen_[i] = true;
          }
          a->dac_code[e.target] = frozen_code_[i];
          break;
        default:
          break;
      }
    }
  }

  void after_tick(std::uint64_t, double t_s, const hil::Plant& plant, const kernel::ControllerStatus& status) override {
    const hil::PlantState& truth = plant.truth();
    last_state_ = status.state;
    for (double i : truth.coil_current_A) v_.max_current_A = std::max(v_.max_current_A, std::fabs(i));
    // Touchdown: every tick of contact after flight, at the speed the platen
    // comes DOWN with. `in_contact` means one corner touches: a tilted platen
    // lands corner by corner, and the centre's descent while in contact is
    // what the other corners come down with. An upward speed is no impact:
    // counting |vz| judged a platen lifted off its pads by amplifiers coming
    // back after a link outage (+0.224 mm/s) as a landing too fast (seed 1,
    // run 2716, whose real touchdowns were 0.062 mm/s landing and 0.256 mm/s
    // amplifiers off).
    if (truth.in_contact && was_flying_) {
      const double speed = std::max(0.0, -std::min(last_vz_, truth.velocity_m_per_s[2]));
      if (speed > v_.touchdown_speed_m_per_s) {
        v_.touchdown_speed_m_per_s = speed;
        v_.touchdown_amplifiers_on = truth.amplifier_enable;
      }
      // A controlled landing must keep the profile's landing speed; a drop
      // (amplifiers off) or a contact an actuator or plant fault forces is
      // bounded by the free fall from z_max.
      // A platen that fell with its amplifiers off (the amplifier side's
      // watchdog cut them after 10 ms without actuator frames) is a drop
      // even if the frames, and the amplifiers, came back just before it
      // touched: no controller can brake 6 mm/s in the last few um (seed 1,
      // run 5385: 36 actuator frames lost, cut at 26, back 0.6 ms before the
      // touchdown at 5.8 mm/s).
      const bool forced = forced_contact();
      const bool fell_unpowered = amplifiers_off_flying_s_ >= 0.0 && t_s - amplifiers_off_flying_s_ < kForcedContactWindow_s;
      const bool controlled = truth.amplifier_enable && !forced && !fell_unpowered;
      const double bound = controlled ? landing_speed_ : kFreeFallBound_m_per_s;
      if (speed > bound) {
        unsafe(std::string("touchdown at ") + fixed(speed * 1e3, 3) + " mm/s (" +
               (controlled ? "controlled landing" : forced ? "forced by a fault" : "amplifiers off") + ", bound " +
               fixed(bound * 1e3, 3) + " mm/s)");
      }
      if (controlled) v_.max_controlled_touchdown_m_per_s = std::max(v_.max_controlled_touchdown_m_per_s, speed);
    }
    if (!truth.in_contact) was_flying_ = true;
    if (!truth.in_contact && !truth.amplifier_enable) amplifiers_off_flying_s_ = t_s;
    last_vz_ = truth.velocity_m_per_s[2];
    if (std::fabs(truth.position_m[0]) > 0.029 || std::fabs(truth.position_m[1]) > 0.0185) {
      unsafe((std::string("platen outside its travel (x ") + fixed(truth.position_m[0], 4) + " m") + (std::string(", y ") + fixed(truth.position_m[1], 4) + " m)"));
    }
    // The state at the end of the last tick before the first fault struck
    // (this tick's status already shows the controller's reaction).
    if (t_s >= first_fault_s_ && !levitated_checked_) {
      levitated_checked_ = true;
      if (state_before_fault_ != kernel::SequencerState::kReady) {
        v_.invalid = std::string("not levitated when the first fault struck (") + kernel::to_string(state_before_fault_) + ")";
      }
    }
    if (t_s < first_fault_s_) state_before_fault_ = status.state;
    if (t_s >= first_fault_s_) {
      const std::string s = kernel::to_string(status.state);
      if (states_.empty() || states_.back() != s) states_.push_back(s);
      if (status.fault != kernel::FaultCode::kNone && latched_s_ < 0.0) {
        latched_s_ = t_s;
        v_.fault_code = kernel::to_string(status.fault);
        v_.detect_s = t_s - first_fault_s_;
      }
    }
    in_contact_ = truth.in_contact;
    amplifiers_on_ = truth.amplifier_enable;
  }

  RunVerdict finish(double end_s) {
    v_.landed_at_end = in_contact_;
    if (v_.max_current_A > rated_A_ * 1.02) unsafe((std::string("coil current ") + fixed(v_.max_current_A, 3) + " A beyond its rating"));
    if (latched_s_ >= 0.0 && end_s - latched_s_ >= kJudgeAfterFault_s && !in_contact_ && amplifiers_on_) {
      unsafe("still levitated " + (fixed(end_s - latched_s_, 2) + std::string(" s")) + " after fault " + v_.fault_code);
    }
    for (const FaultEvent& e : plan_.faults) {
      if (must_land(e.kind) && latched_s_ < 0.0 && !in_contact_) {
        unsafe(std::string(to_string(e.kind)) + " undetected: still levitated at the end");
      }
    }
    for (std::size_t i = 0; i < states_.size(); ++i) v_.path += (i ? ">" : "") + states_[i];
    return v_;
  }

  RunVerdict& verdict() { return v_; }

 private:
  // Free fall from z_max (the supervisor's 40 um envelope) onto the pads: the
  // bound when the amplifiers are off (docs/RELIABILITY.md).
  static constexpr double kFreeFallBound_m_per_s = 0.028;

  bool active(const FaultEvent& e) const { return t_ >= e.t_s && t_ < e.t_s + e.duration_s; }
  bool forced_contact() const {
    for (const FaultEvent& e : plan_.faults) {
      const char* c = category_of(e.kind);
      if ((std::strcmp(c, "actuator") == 0 || std::strcmp(c, "plant") == 0) && t_ >= e.t_s && t_ < e.t_s + e.duration_s + kForcedContactWindow_s) {
        return true;
      }
    }
    return false;
  }
  void unsafe(const std::string& why) {
    if (std::find(v_.unsafe.begin(), v_.unsafe.end(), why) == v_.unsafe.end() && v_.unsafe.size() < 8) {
      v_.unsafe.push_back(why);
    }
  }
  void babble(int frames) {
    // Frames with the catalog's own ids and random payloads: the E2E check
    // (CRC, counter) must keep every one of them out.
    for (int k = 0; k < frames; ++k) {
      can::CanFrame f{};
      const can::Message& m = can::message(kTargetFrames[rng_() % std::size(kTargetFrames)]);
      f.id = m.can_id;
      f.len = m.length;
      f.flags = 0;
      for (std::size_t b = 0; b < f.len; ++b) f.data[b] = static_cast<std::uint8_t>(rng_());
      (void)babbler_->send(f);
    }
  }

  const CampaignPlan& plan_;
  std::mt19937_64 rng_;
  double rated_A_;
  double landing_speed_;
  const FaultEvent* config_event_ = nullptr;
  std::size_t config_writes_done_ = 0;
  kernel::KernelConfig before_{};
  kernel::KernelConfig written_{};
  int config_axis_ = 0;
  kernel::SequencerState last_state_ = kernel::SequencerState::kIdle;
  double codes_per_A_ = 0.0;
  double first_fault_s_ = 0.0;
  std::uint64_t n_ = 0;
  double t_ = 0.0;
  std::unique_ptr<can::VirtualCanPort> babbler_;
  bool frozen_[4] = {};
  io::SensorSample frozen_sample_[4] = {};
  std::int16_t frozen_code_[4] = {};
  bool was_flying_ = false;
  double amplifiers_off_flying_s_ = -1.0;  // last tick the platen flew with its amplifiers off
  double last_vz_ = 0.0;
  bool levitated_checked_ = false;
  kernel::SequencerState state_before_fault_ = kernel::SequencerState::kIdle;
  double latched_s_ = -1.0;
  bool in_contact_ = true;
  bool amplifiers_on_ = false;
  std::vector<std::string> states_;
  RunVerdict v_;
};

// The brown-out: a save of a changed configuration loses power at a random
// flash operation; the next boot must load either the old or the new
// configuration, never defaults over a saved one.
std::string brownout_check(double where) {
  constexpr std::size_t kSector = 4096 * 2;
  static std::uint8_t storage[kSector * 2];
  std::memset(storage, 0xFF, sizeof storage);
  persistence::RamFlash flash(storage, kSector, 2);
  modbus::ConfigImage old_config = modbus::ConfigImage::defaults();
  old_config.set(modbus::RegId::gain_x_kp, 30000.0);
  {
    persistence::ConfigStore store(flash, 0, 1);
    store.load();
    if (!store.save(old_config)) return "the first save failed";
  }
  modbus::ConfigImage new_config = old_config;
  new_config.set(modbus::RegId::gain_x_kp, 31000.0);
  long ops = 0;
  {
    // Count the operations of a save on a copy.
    static std::uint8_t copy[sizeof storage];
    std::memcpy(copy, storage, sizeof storage);
    persistence::RamFlash f2(copy, kSector, 2);
    persistence::PowerCutFlash counter(f2, 1L << 30);
    persistence::ConfigStore s2(counter, 0, 1);
    s2.load();
    s2.save(new_config);
    ops = counter.ops;
  }
  const long budget = std::min(ops - 1, static_cast<long>(where * static_cast<double>(ops)));
  {
    persistence::PowerCutFlash cut(flash, budget);
    persistence::ConfigStore store(cut, 0, 1);
    store.load();
    (void)store.save(new_config);
  }
  persistence::ConfigStore after(flash, 0, 1);
  const persistence::LoadResult r = after.load();
  if (!(r.config == old_config) && !(r.config == new_config)) {
    return "configuration lost to a brown-out at flash operation " + std::to_string(budget) + " of " +
           std::to_string(ops);
  }
  return "";
}

std::string scenario_text(int index, const CampaignPlan& p) {
  std::ostringstream o;
  o << "[scenario]\nname = campaign_" << index << "\nduration_s = " << kDuration_s
    << "\nseed = " << (p.run_seed % 1000000000ull) << "\n[timeline]\n0.0 levitate\n";
  std::vector<std::pair<double, std::string>> lines;
  for (const std::string& m : p.motions) lines.emplace_back(std::atof(m.c_str()), m);
  for (const FaultEvent& e : p.faults) {
    if (e.kind == CampaignFault::kCommandStorm) {
      const int n = static_cast<int>(e.magnitude);
      for (int k = 0; k < n; ++k) {
        const double t = e.t_s + e.duration_s * k / n;
        lines.emplace_back(t, (fixed(t, 5)) + (k % 2 ? " step x -10nm" : " step x 10nm"));
      }
    } else if (e.kind == CampaignFault::kCommandOutOfRange) {
      static const char* kOut[] = {" step x 5mm", " move_to x 80mm 60mm/s 0.6m/s^2", " step z 500um",
                                   " move y 60mm 1m/s 10m/s^2"};
      lines.emplace_back(e.t_s, (fixed(e.t_s, 5)) + kOut[e.target]);
    }
  }
  std::stable_sort(lines.begin(), lines.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& l : lines) o << l.second << "\n";
  return o.str();
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o;
}

std::string to_json(const RunVerdict& v, const CampaignPlan& p, std::uint64_t seed) {
  std::ostringstream o;
  o << "{\"run\": " << v.index << ", \"replay\": \"maglev-hil campaign --seed " << seed << " --only " << v.index
    << "\", \"faults\": [";
  for (std::size_t i = 0; i < p.faults.size(); ++i) {
    const FaultEvent& e = p.faults[i];
    o << (i ? ", " : "") << "{\"kind\": \"" << to_string(e.kind) << "\", \"category\": \"" << category_of(e.kind)
      << "\", \"t_s\": " << e.t_s << ", \"duration_s\": " << e.duration_s << ", \"magnitude\": " << e.magnitude
      << ", \"target\": " << e.target << "}";
  }
  o << "], \"motions\": [";
  for (std::size_t i = 0; i < p.motions.size(); ++i) o << (i ? ", " : "") << "\"" << json_escape(p.motions[i]) << "\"";
  o << "], \"fault_code\": \"" << v.fault_code << "\", \"detect_s\": " << v.detect_s << ", \"sequencer_path\": \""
    << v.path << "\", \"max_coil_current_A\": " << v.max_current_A
    << ", \"touchdown_speed_m_per_s\": " << v.touchdown_speed_m_per_s
    << ", \"touchdown_amplifiers_on\": " << (v.touchdown_amplifiers_on ? "true" : "false")
    << ", \"max_controlled_touchdown_m_per_s\": " << v.max_controlled_touchdown_m_per_s
    << ", \"landed_at_end\": " << (v.landed_at_end ? "true" : "false")
    << ", \"missed_actuator_frames\": " << v.missed_actuator_frames << ", \"config_write\": \"" << v.config_write
    << "\", \"invalid\": \"" << json_escape(v.invalid)
    << "\", \"unsafe\": [";
  for (std::size_t i = 0; i < v.unsafe.size(); ++i) o << (i ? ", " : "") << "\"" << json_escape(v.unsafe[i]) << "\"";
  o << "]}";
  return o.str();
}

// One run, judged. The JSON line is what a worker hands back.
std::string run_one(std::uint64_t seed, int index, bool verbose) {
  const CampaignPlan plan = MakePlan(seed, index);
  const kernel::KernelConfig kc = kernel::default_kernel_config();
  // The rating and the controlled landing's bound: the default profile's.
  CampaignHooks hooks(plan, static_cast<double>(kc.supervisor.peak_current_A), 0.0002);
  auto parsed = scenario::parse_scenario(scenario_text(index, plan), "campaign_" + std::to_string(index));
  RunVerdict v;
  if (!parsed.ok()) {
    v.invalid = "scenario: " + parsed.errors.front().to_string();
  } else {
    RunOptions opt;
    opt.verbose = verbose;
    opt.hooks = &hooks;
    std::vector<ScenarioError> errs;
    const auto r = run(*parsed.scenario, opt, &errs);
    if (!r) {
      v.invalid = errs.empty() ? "run failed" : errs.front().message;
    } else {
      v = hooks.finish(kDuration_s);
      const auto it = r->metrics.find("missed_actuator_frames");
      if (it != r->metrics.end()) v.missed_actuator_frames = static_cast<std::uint64_t>(it->second);
      if (!r->completed && v.invalid.empty()) v.invalid = "run did not complete";
    }
  }
  for (const FaultEvent& e : plan.faults) {
    if (e.kind != CampaignFault::kBrownoutDuringSave) continue;
    const std::string lost = brownout_check(e.magnitude);
    if (!lost.empty()) v.unsafe.push_back(lost);
  }
  v.index = index;
  v.run_seed = plan.run_seed;
  return to_json(v, plan, seed);
}

bool parse_int(const char* s, long long lo, long long hi, long long* out) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s, &end, 10);
  if (errno != 0 || end == s || *end != '\0' || v < lo || v > hi) return false;
  *out = v;
  return true;
}

}  // namespace

int campaign_main(int argc, char** argv) {
  CampaignOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](long long lo, long long hi, long long* out) {
      if (i + 1 >= argc || !parse_int(argv[i + 1], lo, hi, out)) {
        std::fprintf(stderr, "maglev-hil campaign: %s needs an integer in [%lld, %lld]\n", a.c_str(), lo, hi);
        return false;
      }
      ++i;
      return true;
    };
    long long v = 0;
    if (a == "--runs") {
      if (!value(1, 1000000, &v)) return 2;
      o.runs = static_cast<int>(v);
    } else if (a == "--seed") {
      if (!value(0, 4000000000000000000LL, &v)) return 2;
      o.seed = static_cast<std::uint64_t>(v);
    } else if (a == "--jobs") {
      if (!value(0, 256, &v)) return 2;
      // 0: one worker per online CPU.
      o.jobs = v == 0 ? static_cast<int>(std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN))) : static_cast<int>(v);
    } else if (a == "--start") {
      if (!value(0, 999999, &v)) return 2;
      o.start = static_cast<int>(v);
    } else if (a == "--only") {
      if (!value(0, 999999, &v)) return 2;
      o.only = static_cast<int>(v);
    } else if (a == "--out" && i + 1 < argc) {
      o.out_dir = argv[++i];
    } else if (a == "--verbose") {
      o.verbose = true;
    } else {
      std::fprintf(stderr,
                   "maglev-hil campaign: unknown option '%s'\n"
                   "usage: maglev-hil campaign --runs N [--start I] [--seed S] [--jobs J] [--out DIR] [--only I] "
                   "[--verbose]\n",
                   a.c_str());
      return 2;
    }
  }
  std::vector<int> indices;
  if (o.only >= 0) {
    indices.push_back(o.only);
  } else {
    for (int i = 0; i < o.runs; ++i) indices.push_back(o.start + i);
  }
  const int jobs = std::max(1, std::min<int>(o.jobs, static_cast<int>(indices.size())));
  std::printf("maglev-hil campaign: %zu runs, seed %llu, %d jobs, %.1f s each\n", indices.size(),
              static_cast<unsigned long long>(o.seed), jobs, kDuration_s);
  std::fflush(stdout);

  // Workers are processes (fork): each run is a whole bench in its own
  // address space, as `maglev-hil run` is; results come back as JSON lines.
  std::map<int, std::string> lines;
  std::vector<std::pair<pid_t, int>> workers;
  for (int w = 0; w < jobs; ++w) {
    int fds[2];
    if (::pipe(fds) != 0) {
      std::perror("pipe");
      return 2;
    }
    const pid_t pid = ::fork();
    if (pid < 0) {
      std::perror("fork");
      return 2;
    }
    if (pid == 0) {
      ::close(fds[0]);
      FILE* out = ::fdopen(fds[1], "w");
      for (std::size_t k = static_cast<std::size_t>(w); k < indices.size(); k += static_cast<std::size_t>(jobs)) {
        const std::string line = run_one(o.seed, indices[k], o.verbose);
        std::fprintf(out, "%d\t%s\n", indices[k], line.c_str());
        std::fflush(out);
      }
      std::fclose(out);
      std::_Exit(0);
    }
    ::close(fds[1]);
    workers.emplace_back(pid, fds[0]);
  }
  // Read every worker's pipe as it fills (poll): a worker whose pipe is
  // full would otherwise wait for the ones read before it.
  std::size_t done = 0;
  std::vector<std::string> partial(workers.size());
  std::vector<bool> open_fd(workers.size(), true);
  for (std::size_t left = workers.size(); left > 0;) {
    std::vector<pollfd> fds;
    std::vector<std::size_t> which;
    for (std::size_t w = 0; w < workers.size(); ++w) {
      if (!open_fd[w]) continue;
      fds.push_back(pollfd{workers[w].second, POLLIN, 0});
      which.push_back(w);
    }
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      std::perror("poll");
      return 2;
    }
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if ((fds[k].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      const std::size_t w = which[k];
      char buf[65536];
      const ssize_t r = ::read(fds[k].fd, buf, sizeof buf);
      if (r <= 0) {
        ::close(fds[k].fd);
        open_fd[w] = false;
        --left;
        continue;
      }
      partial[w].append(buf, static_cast<std::size_t>(r));
      for (std::size_t nl; (nl = partial[w].find('\n')) != std::string::npos;) {
        const std::string s = partial[w].substr(0, nl);
        partial[w].erase(0, nl + 1);
        const auto tab = s.find('\t');
        if (tab == std::string::npos) continue;
        lines[std::atoi(s.c_str())] = s.substr(tab + 1);
        if (++done % 100 == 0) {
          std::printf("  %zu / %zu runs\n", done, indices.size());
          std::fflush(stdout);
        }
      }
    }
  }
  for (auto& [pid, fd] : workers) {
    int status = 0;
    ::waitpid(pid, &status, 0);
  }

  // Summary: per fault kind, runs, unsafe, invalid; the worst figures.
  int unsafe_runs = 0, invalid_runs = 0, missing = 0;
  std::map<std::string, std::array<int, 3>> by_kind;  // runs, unsafe, fault latched
  double worst_current = 0.0, worst_on = 0.0, worst_off = 0.0;
  for (int idx : indices) {
    const auto it = lines.find(idx);
    if (it == lines.end()) {
      ++missing;
      std::printf("  run %d: no result (the worker died): maglev-hil campaign --seed %llu --only %d\n", idx,
                  static_cast<unsigned long long>(o.seed), idx);
      continue;
    }
    const std::string& j = it->second;
    const bool is_unsafe = j.find("\"unsafe\": []") == std::string::npos;
    const bool is_invalid = j.find("\"invalid\": \"\"") == std::string::npos;
    unsafe_runs += is_unsafe;
    invalid_runs += is_invalid;
    const CampaignPlan p = MakePlan(o.seed, idx);
    const bool latched = j.find("\"fault_code\": \"None\"") == std::string::npos;
    for (const FaultEvent& e : p.faults) {
      auto& k = by_kind[to_string(e.kind)];
      ++k[0];
      k[1] += is_unsafe;
      k[2] += latched;
    }
    auto number = [&](const char* key) {
      const auto at = j.find(key);
      return at == std::string::npos ? 0.0 : std::atof(j.c_str() + at + std::strlen(key));
    };
    worst_current = std::max(worst_current, number("\"max_coil_current_A\": "));
    worst_on = std::max(worst_on, number("\"max_controlled_touchdown_m_per_s\": "));
    worst_off = std::max(worst_off, number("\"touchdown_speed_m_per_s\": "));
    if (is_unsafe || is_invalid) {
      std::printf("  run %d %s: %s\n    replay: maglev-hil campaign --seed %llu --only %d\n", idx,
                  is_unsafe ? "UNSAFE" : "INVALID", j.c_str(), static_cast<unsigned long long>(o.seed), idx);
    }
  }
  std::printf("\n  %-22s %6s %8s %8s\n", "fault", "runs", "latched", "unsafe");
  for (const auto& [name, k] : by_kind) std::printf("  %-22s %6d %8d %8d\n", name.c_str(), k[0], k[2], k[1]);
  std::printf("\n  worst coil current %.3f A; worst controlled landing %.3f mm/s; worst touchdown of any kind %.3f mm/s\n",
              worst_current, worst_on * 1e3, worst_off * 1e3);
  std::printf("  %zu runs: %d unsafe, %d invalid, %d without a result\n", indices.size(), unsafe_runs, invalid_runs,
              missing);
  if (!o.out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.out_dir, ec);
    const std::string path = o.out_dir + "/campaign.json";
    std::ofstream f(path);
    f << "{\"seed\": " << o.seed << ", \"runs\": " << indices.size() << ", \"unsafe_runs\": " << unsafe_runs
      << ", \"invalid_runs\": " << invalid_runs << ", \"worst_coil_current_A\": " << worst_current
      << ", \"worst_controlled_landing_m_per_s\": " << worst_on
      << ", \"worst_touchdown_any_m_per_s\": " << worst_off << ",\n \"run_results\": [\n";
    bool first = true;
    for (const auto& [idx, j] : lines) {
      f << (first ? "  " : ",\n  ") << j;
      first = false;
    }
    f << "\n]}\n";
    if (!f) {
      std::fprintf(stderr, "maglev-hil campaign: cannot write %s\n", path.c_str());
      return 2;
    }
    std::printf("  wrote %s\n", path.c_str());
  }
  return unsafe_runs == 0 && invalid_runs == 0 && missing == 0 ? 0 : 1;
}

}  // namespace maglev::bench
