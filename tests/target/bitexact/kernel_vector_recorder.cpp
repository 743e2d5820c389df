// kernel-vector-recorder: closes the loop between the HIL plant (maglev_plant,
// default PlantConfig, seed 1) and Controller<float> in lockstep -- the bench's
// per-tick order: sample(), command(s) due this tick, step(), apply(),
// advance_tick() -- through levitation start-up and then a fixed list of
// steps / moves / profiles / an excitation, and writes
//   <vectors.bin>       the kernel's inputs per tick (replay_format.hpp), and
//   <host_outputs.bin>  this host kernel's outputs per tick, encoded exactly as
//                       the M7 replay image encodes its own.
// Exit status 0 only if the stage reached Ready and every command was accepted
// (so the recorded run really exercises the levitated kernel).
//
// usage: kernel-vector-recorder <vectors.bin> <host_outputs.bin> [--profile FILE] [--near-home] [--q7.24] [--rate HZ]
// --q7.24: the kernel is Controller<Q7_24> (the fixed-point build) instead of
// Controller<float>; the replay image must then be run with --q7.24 too.
// --rate HZ: servo rate (2500, 5000, 10000 or 20000; default: the
// configuration's, 2500): the kernel is configured at HZ, the plant steps
// at HZ (hil::ApplyServoRate) and the schedule's tick offsets, the start-up
// limit and the ticks after Ready scale with it, so the session covers the
// same seconds (the whole-servo-interrupt measurement at 20 kHz:
// firmware/board/mps2_an500/servo_tick).
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "maglev/controller/controller.hpp"
#include "maglev/plant/plant.hpp"
#include "maglev/plant/plant_config.hpp"
#include "maglev/plant/plant_profile.hpp"
#include "maglev/io/stage_parameters.hpp"
#include "maglev/kernel_replay/replay_format.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/stage_profile/apply_profile.hpp"

namespace {

namespace kr = maglev::kernel_replay;
namespace kernel = maglev::kernel;
using kernel::Axis;
using kernel::MotionCommand;
using kernel::MotionType;

constexpr std::uint64_t kSeed = 1;
// Give up if start-up has not reached Ready after this many ticks (4 s).
constexpr std::uint32_t kMaxStartupTicks = 10000;
// Ticks recorded after Ready: the command schedule below ends well before.
constexpr std::uint32_t kTicksAfterReady = 5000;

// One scheduled command, `after_ready` ticks after the first Ready tick.
struct Scheduled {
  std::uint32_t after_ready;
  const char* text;
  MotionCommand command;
  bool relative_to_reference;  // kMoveTo: target is an offset from the present reference
};

MotionCommand make(MotionType type, Axis axis) {
  MotionCommand c;
  c.type = type;
  c.axis = axis;
  return c;
}

// near_home: only what stays within micrometres of home. The triangle layout
// over this magnet matrix cannot move millimetres on the bench (its oblique
// forcers' force drifts from the kernel's commutation, and it hovers tilted
// next to the tilt envelope: docs/PLANT.md 2a), so its replay leaves out the
// 0.5 mm move and the 1 mm circle; every other command stays.
std::vector<Scheduled> schedule(bool near_home) {
  std::vector<Scheduled> s;
  MotionCommand c = make(MotionType::kStep, Axis::kX);
  c.target = 8e-6;
  s.push_back({250, "step x +8 um", c, false});
  c.target = -4e-6;
  s.push_back({750, "step x -4 um", c, false});
  c = make(MotionType::kMoveTo, Axis::kY);
  c.target = 0.5e-3;
  c.velocity = 0.05;
  c.acceleration = 0.5;
  if (!near_home) s.push_back({1250, "move_to y +0.5 mm (trapezoid)", c, true});
  c = make(MotionType::kStep, Axis::kThetaZ);
  c.target = 2e-6;
  s.push_back({2000, "step theta_z +2 urad", c, false});
  c = make(MotionType::kStep, Axis::kZ);
  c.target = 2e-6;
  s.push_back({2300, "step z +2 um", c, false});
  c = make(MotionType::kSinusoid, Axis::kX);
  c.amplitude = 20e-6;
  c.frequency_Hz = 10.0;
  c.turns = 3.0;
  s.push_back({2600, "sinusoid x 20 um 10 Hz 3 cycles (libm sin)", c, false});
  c = make(MotionType::kExcite, Axis::kThetaZ);
  c.amplitude = 0.05;
  c.frequency_Hz = 20.0;
  c.harmonics = 4;
  c.duration_s = 0.3;
  s.push_back({3500, "excite theta_z 0.05 A, 20 Hz x 4 lines, 0.3 s", c, false});
  c = make(MotionType::kCircle, Axis::kX);
  c.diameter_m = 1e-3;
  c.period_s = 0.6;
  c.turns = 1.0;
  if (!near_home) s.push_back({4300, "circle 1 mm, 0.6 s, 1 turn", c, false});
  return s;
}

bool write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return static_cast<bool>(f);
}

double reference_si(const kernel::ControllerStatus& st, Axis axis) {
  return static_cast<double>(st.reference[axis]) * 1e-12;
}

}  // namespace

template <typename Scalar>
int record(int argc, char** argv, bool near_home, double rate_Hz);

int main(int argc, char** argv) {
  // --rate HZ (anywhere after the two paths): taken out before the positional parsing below.
  double rate_Hz = 0.0;
  for (int i = 3; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--rate") {
      rate_Hz = std::strtod(argv[i + 1], nullptr);
      for (int j = i; j + 2 < argc; ++j) argv[j] = argv[j + 2];
      argc -= 2;
      break;
    }
  }
  if (rate_Hz != 0.0 && !maglev::io::stage::is_supported_servo_rate(rate_Hz)) {
    std::fprintf(stderr, "recorder: --rate %g: not an offered servo rate (2500, 5000, 10000, 20000)\n", rate_Hz);
    return 2;
  }
  const bool q7_24 = argc > 3 && std::string(argv[argc - 1]) == "--q7.24";
  if (q7_24) --argc;
  const bool near_home = argc > 3 && std::string(argv[argc - 1]) == "--near-home";
  if (near_home) --argc;
  return q7_24 ? record<maglev::numeric::Q7_24>(argc, argv, near_home, rate_Hz)
               : record<float>(argc, argv, near_home, rate_Hz);
}

template <typename Scalar>
int record(int argc, char** argv, bool near_home, double rate_Hz) {
  if (argc != 3 && !(argc == 5 && std::string(argv[3]) == "--profile")) {
    std::fprintf(stderr, "usage: %s <vectors.bin> <host_outputs.bin> [--profile FILE] [--near-home] [--q7.24] [--rate HZ]\n",
                 argv[0]);
    return 2;
  }
  // With --profile: the stage's kernel configuration and plant both from the
  // profile, and the profile itself travels in the vectors file so the M7
  // image builds its configuration through the firmware's own profile code.
  kernel::KernelConfig config = kernel::default_kernel_config();
  maglev::hil::PlantConfig plant_config = maglev::hil::PlantConfig::Default();
  std::vector<std::uint8_t> profile_bytes;
  if (argc == 5) {
    const auto parsed = maglev::profile::load_profile_file(argv[4]);
    if (!parsed.ok()) {
      for (const auto& e : parsed.errors) std::fprintf(stderr, "%s\n", e.c_str());
      return 2;
    }
    const auto check = maglev::stage_profile::MakeKernelConfig(parsed.profile, &config);
    std::string why;
    if (check.error != maglev::stage_profile::ProfileError::kOk ||
        !maglev::hil::PlantConfigForProfile(parsed.profile, plant_config, &plant_config, &why)) {
      std::fprintf(stderr, "recorder: profile %s cannot run: %s%s\n", argv[4],
                   maglev::stage_profile::to_string(check.error), why.c_str());
      return 2;
    }
    profile_bytes.resize(sizeof parsed.profile);
    std::memcpy(profile_bytes.data(), &parsed.profile, sizeof parsed.profile);
    std::printf("recorder: stage profile %s\n", parsed.profile.name);
  }
  if (rate_Hz != 0.0) {
    config.servo_rate_Hz = static_cast<float>(rate_Hz);
    config.measurement.servo_rate_Hz = config.servo_rate_Hz;  // one rate, as the servo.rate register sets it
    maglev::hil::ApplyServoRate(rate_Hz, &plant_config);
  }
  const double tick_rate_Hz = static_cast<double>(config.servo_rate_Hz);
  // Tick counts below are written for 2.5 kHz; other rates cover the same seconds.
  const double tick_scale = tick_rate_Hz / 2500.0;
  const auto scaled = [tick_scale](std::uint32_t ticks) {
    return static_cast<std::uint32_t>(static_cast<double>(ticks) * tick_scale + 0.5);
  };
  const std::uint32_t max_startup_ticks = scaled(kMaxStartupTicks);
  if (rate_Hz != 0.0) std::printf("recorder: servo rate %g Hz\n", tick_rate_Hz);
  maglev::hil::Plant plant(plant_config, kSeed);
  auto controller = std::make_unique<kernel::Controller<Scalar>>();
  if (controller->apply_config(config) != kernel::ConfigError::kOk) {
    std::fprintf(stderr, "recorder: the kernel configuration was refused\n");
    return 1;
  }
  const std::vector<Scheduled> plan = schedule(near_home);
  std::size_t next = 0;

  std::vector<std::uint8_t> inputs(kr::kHeaderBytes);
  inputs.insert(inputs.end(), profile_bytes.begin(), profile_bytes.end());
  std::vector<std::uint8_t> outputs;
  kr::InputHeader header;
  header.profile_bytes = static_cast<std::uint32_t>(profile_bytes.size());
  bool ok = true;
  std::int64_t ready_tick = -1;
  std::uint32_t end_tick = max_startup_ticks;

  for (std::uint32_t tick = 0; tick < end_tick; ++tick) {
    kr::InputRecord in;
    in.sample = plant.sample();
    in.tick_overrun = false;
    const char* text = nullptr;
    if (tick == 0) {
      in.has_command = true;
      in.command = make(MotionType::kLevitate, Axis::kX);
      text = "levitate";
    } else if (ready_tick >= 0 && next < plan.size() &&
               static_cast<std::int64_t>(tick) == ready_tick + scaled(plan[next].after_ready)) {
      in.has_command = true;
      in.command = plan[next].command;
      if (plan[next].relative_to_reference) {
        in.command.target += reference_si(controller->status(), in.command.axis);
      }
      text = plan[next].text;
      ++next;
    }
    // Drive this kernel with the DECODED record, exactly what the image reads
    // (a MotionCommand field the format does not carry stays default on both).
    const std::size_t in_at = inputs.size();
    inputs.resize(in_at + kr::kInputRecordBytes);
    kr::encode_input(in, &inputs[in_at]);
    kr::decode_input(&inputs[in_at], &in);

    kr::OutputRecord out;
    out.tick = tick;
    if (in.has_command) {
      const kernel::CommandResult result = controller->command(in.command);
      out.command_result = static_cast<std::uint8_t>(result);
      std::printf("recorder: tick %6u  %-48s -> result %u%s\n", tick, text, static_cast<unsigned>(result),
                  result == kernel::CommandResult::kAccepted ? " (accepted)" : " (NOT accepted)");
      if (result != kernel::CommandResult::kAccepted) ok = false;
      ++header.command_count;
    }
    out.actuator = controller->step(in.sample, in.tick_overrun);
    out.status = &controller->status();
    plant.apply(out.actuator);
    plant.advance_tick();

    const std::size_t out_at = outputs.size();
    outputs.resize(out_at + kr::kOutputRecordBytes);
    kr::encode_output(out, &outputs[out_at]);

    if (ready_tick < 0 && out.status->state == kernel::SequencerState::kReady) {
      ready_tick = tick;
      end_tick = tick + scaled(kTicksAfterReady);
      std::printf("recorder: tick %6u  Ready (start-up took %.3f s)\n", tick, tick / tick_rate_Hz);
    }
    if (out.status->fault != kernel::FaultCode::kNone) {
      std::printf("recorder: tick %6u  FAULT %u latched\n", tick, static_cast<unsigned>(out.status->fault));
      ok = false;
      end_tick = tick + 1;
    }
  }
  header.tick_count = static_cast<std::uint32_t>(outputs.size() / kr::kOutputRecordBytes);
  header.input_record_bytes = kr::kInputRecordBytes;
  header.output_record_bytes = kr::kOutputRecordBytes;
  kr::encode_header(header, inputs.data());
  if (!write_file(argv[1], inputs) || !write_file(argv[2], outputs)) {
    std::fprintf(stderr, "recorder: cannot write %s / %s\n", argv[1], argv[2]);
    return 1;
  }
  std::printf("recorder: %u ticks, %u commands; wrote %zu input bytes to %s, %zu output bytes to %s\n",
              header.tick_count, header.command_count, inputs.size(), argv[1], outputs.size(), argv[2]);
  if (ready_tick < 0) {
    std::fprintf(stderr, "recorder: FAIL: the stage never reached Ready within %u ticks\n", max_startup_ticks);
    return 1;
  }
  if (next != plan.size()) ok = false;
  if (!ok) {
    std::fprintf(stderr, "recorder: FAIL: a command was refused or a fault latched (see above)\n");
    return 1;
  }
  return 0;
}
