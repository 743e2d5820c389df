// selfstab-vector-recorder: the paper-001 bench (selfstab plant + selfstab
// kernel in lockstep) through a session -- lift-off, z and x steps, refused
// commands (a passive axis, a z outside the schedule), the 10 Hz filter out
// and in, hold, landing -- recording every tick's PSD codes and command
// (vectors.bin, with the stage profile) and the host kernel's outputs
// (host_outputs.bin). The M7 image (maglev-qemu-selfstab-replay.elf) replays
// the vectors; the outputs must match bit for bit.
//
//   selfstab-vector-recorder <vectors.bin> <host_outputs.bin> --profile <file.profile>
//   selfstab-vector-recorder --compare <host_outputs.bin> <target_outputs.bin>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "maglev/bench/selfstab_suite.hpp"
#include "maglev/profile/profile_text.hpp"
#include "maglev/selfstab_replay/selfstab_replay_format.hpp"
#include "maglev/stage_profile/selfstab_config.hpp"

namespace {
namespace sr = maglev::selfstab_replay;
namespace ss = maglev::selfstab;
namespace sp = maglev::stage_profile;
namespace pl = maglev::selfstab_plant;

std::vector<char> slurp(const char* path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

int compare(const char* a, const char* b) {
  const auto x = slurp(a), y = slurp(b);
  if (x.empty() || x.size() % sr::kOutputRecordBytes != 0) {
    std::fprintf(stderr, "selfstab-compare: %s is empty or not whole records\n", a);
    return 1;
  }
  if (x.size() != y.size()) {
    std::fprintf(stderr, "selfstab-compare: %zu vs %zu bytes\n", x.size(), y.size());
    return 1;
  }
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (x[i] != y[i]) {
      std::fprintf(stderr, "selfstab-compare: first difference at tick %zu, byte %zu of the record\n",
                   i / sr::kOutputRecordBytes, i % sr::kOutputRecordBytes);
      return 1;
    }
  }
  std::printf("selfstab-compare: %zu ticks identical bit for bit (%zu bytes)\n", x.size() / sr::kOutputRecordBytes,
              x.size());
  return 0;
}

struct Scheduled {
  double t_s;
  sr::Command command;
  int axis;
  float value;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--compare") == 0) return compare(argv[2], argv[3]);
  if (argc != 5 || std::strcmp(argv[3], "--profile") != 0) {
    std::fprintf(stderr, "usage: selfstab-vector-recorder <vectors.bin> <host_outputs.bin> --profile <file>\n"
                         "       selfstab-vector-recorder --compare <host_outputs.bin> <target_outputs.bin>\n");
    return 2;
  }
  const auto parsed = maglev::profile::load_profile_file(argv[4]);
  if (!parsed.ok()) {
    std::fprintf(stderr, "%s\n", parsed.errors.front().c_str());
    return 2;
  }
  const sp::StageProfile& prof = parsed.profile;
  ss::SelfstabKernelConfig cfg{};
  const sp::ProfileError e = sp::MakeSelfstabKernelConfig(prof, &cfg);
  if (e != sp::ProfileError::kOk) {
    std::fprintf(stderr, "profile refused: %s\n", sp::to_string(e));
    return 3;
  }
  static ss::SelfstabKernel kernel;
  if (kernel.configure(cfg) != ss::SelfstabConfigError::kOk) return 3;
  pl::Plant plant(maglev::bench::SelfstabPlantParams(prof));
  plant.ResetDocked();
  const double T = 1.0 / prof.servo_rate_Hz;
  const double lsb = prof.sensors[0].resolution;
  const std::vector<Scheduled> timeline = {
      {0.0, sr::Command::kLiftOff, 0, 0.0f},
      {3.0, sr::Command::kMoveTo, ss::kZ, 100e-6f},
      {4.0, sr::Command::kMoveTo, ss::kX, 50e-6f},
      {5.0, sr::Command::kMoveTo, ss::kY, 10e-6f},      // refused: passive
      {5.001, sr::Command::kMoveTo, ss::kZ, 2.1e-3f},   // refused: outside the schedule
      {5.5, sr::Command::kFilterOff, 0, 0.0f},
      {6.0, sr::Command::kMoveTo, ss::kZ, -1.5e-3f},    // a large step: the schedule works
      {7.5, sr::Command::kFilterOn, 0, 0.0f},
      {8.0, sr::Command::kMoveTo, ss::kZ, 0.0f},
      {9.0, sr::Command::kHold, 0, 0.0f},
      {9.5, sr::Command::kLand, 0, 0.0f},
  };
  const auto ticks = static_cast<std::uint32_t>(12.0 / T);
  std::ofstream vec(argv[1], std::ios::binary), out(argv[2], std::ios::binary);
  std::uint8_t hb[sr::kHeaderBytes];
  sr::encode_header({sr::kMagic, sr::kVersion, ticks, static_cast<std::uint32_t>(sizeof(prof))}, hb);
  vec.write(reinterpret_cast<const char*>(hb), sizeof hb);
  vec.write(reinterpret_cast<const char*>(&prof), sizeof prof);
  std::size_t next = 0;
  int refused = 0;
  for (std::uint32_t k = 0; k < ticks; ++k) {
    sr::InputRecord r{};
    r.sample = maglev::bench::SelfstabSampleFromPsd(plant.Measure(), lsb);
    if (next < timeline.size() && static_cast<double>(k) * T >= timeline[next].t_s - 1e-9) {
      r.command = timeline[next].command;
      r.axis = static_cast<std::int8_t>(timeline[next].axis);
      r.value = timeline[next].value;
      ++next;
    }
    std::uint8_t ib[sr::kInputRecordBytes], ob[sr::kOutputRecordBytes];
    sr::encode_input(r, ib);
    vec.write(reinterpret_cast<const char*>(ib), sizeof ib);
    // The host kernel sees exactly what the M7 will: the decoded record.
    sr::InputRecord d{};
    sr::decode_input(ib, &d);
    const ss::SelfstabResult res = sr::apply_command(kernel, d);
    refused += res != ss::SelfstabResult::kOk;
    const ss::SelfstabCoilCommand c = kernel.tick(d.sample);
    sr::encode_output(k, res, c, kernel.telemetry(), ob);
    out.write(reinterpret_cast<const char*>(ob), sizeof ob);
    plant.Step(maglev::bench::SelfstabAmplifierVoltages(c, cfg.dac_A_per_code, prof.solenoid.coil_resistance_Ohm), T);
  }
  std::printf("selfstab-vector-recorder: %s, %u ticks, %d commands refused, final mode %s, z %.3g um\n", prof.name,
              ticks, refused, ss::to_string(kernel.mode()), plant.pose()[2] * 1e6);
  // The session must have done what it says: two refusals, landed at the end.
  return (refused == 2 && kernel.mode() == ss::SelfstabMode::kDocked) ? 0 : 4;
}
