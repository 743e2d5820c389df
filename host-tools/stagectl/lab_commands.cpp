// stagectl record / stagectl frf: the lab tools over Modbus (docs/LAB-TOOLS.md).
//
// record: stop the recorder, write the whole rec.* configuration and
//   rec.control = 1 (arm) in one 0x10, wait for rec.state = 3 (done), then
//   download: per block one 0x17 (write rec.read_offset, read the 124-register
//   rec.data window = 62 float32 values). Every block is appended to
//   DIR/record.partial (+ DIR/record.partial.json: capture id, channels) so
//   `record --resume` continues an interrupted download where it stopped (the
//   capture id must be unchanged). Then DIR/record.csv (t_s, one column per
//   channel, t = 0 at the trigger sample) and DIR/record.png.
// frf AXIS: multisine (Schroeder, log-spaced tones on the 1 Hz grid) at the
//   axis' effort through the wave generator; the recorder takes the
//   excitation d, the loop's effort u and the total effort u + d over whole
//   1-s periods; per period the DFT at each tone (metrics::frequency_response_segments,
//   hil/metrics: the bench's math), open loop L = -u / (u + d) (H1 over the
//   periods, coherence of u vs u + d), closed loop T = -u / d = L / (1 + L);
//   margins by metrics::loop_margins (crossover, phase margin, closed-loop
//   bandwidth) + gain margin. DIR/frf.csv, DIR/frf_margins.json, DIR/frf.png.
#include "lab_commands.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <numbers>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "exit_codes.hpp"
#include "maglev/io/axis.hpp"
#include "maglev/lab_tools/signals.hpp"
#include "maglev/lab_tools/wave_generator.hpp"
#include "maglev/metrics/metrics.hpp"
#include "maglev/register_schema/register_map.hpp"

#ifndef MAGLEV_LAB_PLOT_SCRIPT
#define MAGLEV_LAB_PLOT_SCRIPT "host-tools/lab_plots/lab_plot.py"
#endif

namespace maglev::stagectl {

const char* const kLabHelp = R"(lab tools (docs/LAB-TOOLS.md):
  record --out DIR [--channels SIG,SIG,...] [--duration S | --length N] [--decimation N]
         [--trigger immediate|command|fault|level:SIGNAL:LEVEL[:rising|falling|either]]
         [--pretrigger S] [--timeout S] [--download] [--resume] [--max-blocks N] [--signals]
                           arm the on-board recorder, wait for the trigger, download (progress
                           on stderr), write DIR/record.csv (t_s + one column per channel) and
                           DIR/record.png. --download: only download the finished capture (e.g.
                           the fault watch's after a fault); --resume: continue an interrupted
                           download of the same capture. --signals: list the signal names.
                           --max-blocks N: stop after N download blocks (an interrupted link)
  frf AXIS --out DIR [--amplitude A] [--f-min HZ] [--f-max HZ] [--tones N] [--periods N]
         [--settle S]      open/closed-loop response of the running loop (Ready): multisine at
                           AXIS's effort; DIR/frf.csv, DIR/frf_margins.json, DIR/frf.png
)";

namespace {

using namespace maglev::modbus;
using enum maglev::stagectl::Exit;  // (modbus has a kRefused too)

struct LabError {
  int code;
  std::string message;
};

[[noreturn]] void fail(int code, const std::string& msg) { throw LabError{code, msg}; }

[[noreturn]] void modbus_fail(const char* what) {
  const int e = errno;
  switch (e - MODBUS_ENOBASE) {
    case 1: fail(kAccess, std::string(what) + ": illegal function (engineer access?)");
    case 2: fail(kRefused, std::string(what) + ": illegal data address (no lab tools on this controller?)");
    case 3: fail(kRefused, std::string(what) + ": illegal data value (configuration refused; see rec.error / wave.error)");
    case 4: fail(kRefused, std::string(what) + ": server device failure");
    case 6: fail(kBusy, std::string(what) + ": controller busy (recorder armed / generator running / nothing to read)");
    default: fail(kComm, std::string(what) + ": " + modbus_strerror(e));
  }
}

class Lab {
 public:
  explicit Lab(modbus_t* ctx) : ctx_(ctx) {}

  double get(RegId id) {
    const RegisterDef& d = def(id);
    std::uint16_t w[2] = {};
    if (modbus_read_registers(ctx_, d.address, width(d.type), w) < 0) modbus_fail(d.name);
    return decode(d.type, width(d.type) == 1 ? w[0] : join_words(w));
  }
  // A register image of [first, last] (whole registers), filled by put(), written in one 0x10.
  struct Block {
    std::uint16_t start;
    std::vector<std::uint16_t> words;
    void put(RegId id, double v) {
      const RegisterDef& d = def(id);
      const std::uint32_t raw = encode(d.type, v);
      const std::size_t i = d.address - start;
      if (width(d.type) == 1) {
        words.at(i) = static_cast<std::uint16_t>(raw);
      } else {
        split_words(raw, &words.at(i));
      }
    }
  };
  Block block(RegId first, RegId last) {
    const RegisterDef& a = def(first);
    const RegisterDef& b = def(last);
    Block blk{a.address, std::vector<std::uint16_t>(static_cast<std::size_t>(b.address + width(b.type) - a.address), 0)};
    // Start from what the controller holds (registers left unset keep their value).
    if (modbus_read_registers(ctx_, blk.start, static_cast<int>(blk.words.size()), blk.words.data()) < 0) {
      modbus_fail("read configuration");
    }
    return blk;
  }
  void write(const Block& b, const char* what) {
    if (modbus_write_registers(ctx_, b.start, static_cast<int>(b.words.size()), b.words.data()) < 0) modbus_fail(what);
  }
  void set(RegId id, double v) {
    Block b{def(id).address, std::vector<std::uint16_t>(width(def(id).type), 0)};
    b.put(id, v);
    write(b, def(id).name);
  }
  // One download block: write rec.read_offset, read rec.data (0x17).
  void read_values(std::uint32_t offset, std::uint16_t words, std::uint16_t* out) {
    std::uint16_t w[2];
    split_words(offset, w);
    if (modbus_write_and_read_registers(ctx_, def(RegId::rec_read_offset).address, 2, w, def(RegId::rec_data).address,
                                        words, out) < 0) {
      modbus_fail("download (rec.read_offset + rec.data)");
    }
  }

 private:
  modbus_t* ctx_;
};

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string signal_name(std::uint16_t id) {
  char buf[40];
  return lab::signal_name(id, buf, sizeof buf) ? std::string(buf) : "signal" + std::to_string(id);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

double number(const std::string& opt, const std::string& v) {
  char* end = nullptr;
  const double d = std::strtod(v.c_str(), &end);
  if (end == v.c_str() || *end != '\0' || !std::isfinite(d)) fail(kUsage, opt + ": '" + v + "' is not a number");
  return d;
}

void make_dir(const std::string& dir) {
  if (dir.empty()) fail(kUsage, "--out DIR is required");
  if (::mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST) fail(kFile, "cannot create " + dir + ": " + std::strerror(errno));
}

// Progress on stderr: one line per step, at most every ~0.5 s or 10 %.
class Progress {
 public:
  explicit Progress(std::string what) : what_(std::move(what)), t0_(now_s()) {}
  void update(double done, double total, const char* unit) {
    const double t = now_s();
    const double pct = total > 0 ? 100.0 * done / total : 100.0;
    if (done < total && t - last_t_ < 0.5 && pct - last_pct_ < 10.0) return;
    last_t_ = t;
    last_pct_ = pct;
    std::fprintf(stderr, "%s: %5.1f %% (%.0f / %.0f %s, %.1f s)\n", what_.c_str(), pct, done, total, unit, t - t0_);
  }
  double elapsed() const { return now_s() - t0_; }

 private:
  std::string what_;
  double t0_;
  double last_t_ = -1e9;
  double last_pct_ = -1e9;
};

void run_plot(const std::string& kind, const std::string& dir) {
  const char* env = std::getenv("MAGLEV_LAB_PLOT_SCRIPT");
  const std::string script = env != nullptr ? env : MAGLEV_LAB_PLOT_SCRIPT;
  std::fflush(stdout);
  const std::string cmd = "/usr/bin/python3 '" + script + "' " + kind + " '" + dir + "'";
  const int rc = std::system(cmd.c_str());
  if (rc != 0) {
    std::fprintf(stderr,
                 "stagectl: no plot: '%s' failed (exit %d; needs /usr/bin/python3 with matplotlib); the CSV is "
                 "written\n",
                 cmd.c_str(), rc);
  }
}

// --- the recorder ------------------------------------------------------------

struct Capture {
  std::uint16_t capture_id = 0;
  std::uint32_t samples = 0;
  std::uint32_t trigger_index = 0;
  double sample_rate_Hz = 0;
  std::vector<std::uint16_t> channels;
  std::vector<float> values;  // channel-interleaved
};

std::uint16_t wait_done(Lab& lab, double timeout_s, const std::string& what, double expected_s) {
  Progress p(what);
  for (;;) {
    const auto state = static_cast<int>(lab.get(RegId::rec_state));
    if (state == 3) {
      p.update(1, 1, "");
      return static_cast<std::uint16_t>(lab.get(RegId::rec_capture_id));
    }
    if (state == 0) fail(kRefused, "the recorder was stopped (rec.state 0) before its capture finished");
    if (p.elapsed() > timeout_s) fail(kTimeout, what + ": no capture after " + std::to_string(timeout_s) + " s (rec.state " + std::to_string(state) + ")");
    if (expected_s > 0) p.update(std::min(p.elapsed(), expected_s), expected_s, "s");
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

std::string partial_meta(const std::string& dir) { return dir + "/record.partial.json"; }
std::string partial_data(const std::string& dir) { return dir + "/record.partial"; }

// Download the finished capture (resuming from DIR/record.partial when its
// capture id matches).
Capture download(Lab& lab, const std::string& dir, bool resume, long max_blocks) {
  Capture c;
  c.capture_id = static_cast<std::uint16_t>(lab.get(RegId::rec_capture_id));
  if (static_cast<int>(lab.get(RegId::rec_state)) != 3) fail(kBusy, "no finished capture to download (rec.state != 3)");
  c.samples = static_cast<std::uint32_t>(lab.get(RegId::rec_captured));
  c.trigger_index = static_cast<std::uint32_t>(lab.get(RegId::rec_trigger_index));
  c.sample_rate_Hz = lab.get(RegId::rec_sample_rate);
  const auto n = static_cast<int>(lab.get(RegId::rec_channel_count));
  for (int i = 0; i < n; ++i) c.channels.push_back(static_cast<std::uint16_t>(lab.get(static_cast<RegId>(static_cast<int>(RegId::rec_channel_0) + i))));
  const std::uint32_t total = c.samples * static_cast<std::uint32_t>(n);
  // Resume: the values already downloaded for this same capture.
  std::uint32_t have = 0;
  if (resume) {
    std::ifstream meta(partial_meta(dir));
    std::stringstream ss;
    if (meta) ss << meta.rdbuf();
    const std::string text = ss.str();
    const std::string key = "\"capture_id\": " + std::to_string(c.capture_id) + ",";
    if (!meta || text.find(key) == std::string::npos) {
      fail(kFile, "--resume: " + partial_meta(dir) + " is missing or names another capture (controller has capture " +
                      std::to_string(c.capture_id) + ")");
    }
    std::ifstream in(partial_data(dir), std::ios::binary | std::ios::ate);
    const std::streamoff bytes = in ? static_cast<std::streamoff>(in.tellg()) : 0;
    have = static_cast<std::uint32_t>(bytes / static_cast<std::streamoff>(sizeof(float)));
    if (have > total) have = total;
    c.values.resize(have);
    in.seekg(0);
    in.read(reinterpret_cast<char*>(c.values.data()), static_cast<std::streamsize>(have * sizeof(float)));
    std::fprintf(stderr, "resuming capture %u at value %u of %u\n", c.capture_id, have, total);
  } else {
    std::ofstream meta(partial_meta(dir));
    meta << "{\"capture_id\": " << c.capture_id << ", \"samples\": " << c.samples << ", \"channels\": " << n << "}\n";
    std::ofstream(partial_data(dir), std::ios::binary | std::ios::trunc);
  }
  std::ofstream part(partial_data(dir), std::ios::binary | std::ios::app);
  if (!part) fail(kFile, "cannot write " + partial_data(dir));
  constexpr std::uint16_t kValuesPerBlock = kBlockWords / 2;
  std::uint16_t words[kBlockWords];
  Progress p("download");
  long blocks = 0;
  const double t0 = now_s();
  const std::uint32_t start_have = have;
  while (have < total) {
    if (max_blocks >= 0 && blocks >= max_blocks) {
      part.flush();
      fail(kComm, "download stopped after " + std::to_string(blocks) + " blocks (--max-blocks); " + std::to_string(have) +
                      " of " + std::to_string(total) + " values kept in " + partial_data(dir) + ": continue with --resume");
    }
    const std::uint32_t m = std::min<std::uint32_t>(kValuesPerBlock, total - have);
    lab.read_values(have, static_cast<std::uint16_t>(2 * m), words);
    for (std::uint32_t i = 0; i < m; ++i) {
      const std::uint32_t raw = join_words(words + 2 * i);
      float v;
      std::memcpy(&v, &raw, sizeof v);
      c.values.push_back(v);
    }
    part.write(reinterpret_cast<const char*>(c.values.data() + have), static_cast<std::streamsize>(m * sizeof(float)));
    have += m;
    ++blocks;
    p.update(have, total, "values");
  }
  part.close();
  if (static_cast<std::uint16_t>(lab.get(RegId::rec_capture_id)) != c.capture_id) {
    fail(kComm, "the capture changed during the download (rec.capture_id); record again");
  }
  const double dt = now_s() - t0;
  std::fprintf(stderr, "downloaded %u values (%u samples x %d channels) in %ld blocks, %.3f s (%.0f values/s)\n",
               have - start_have, c.samples, n, blocks, dt, dt > 0 ? (have - start_have) / dt : 0.0);
  return c;
}

void write_record_csv(const Capture& c, const std::string& dir) {
  const std::string path = dir + "/record.csv";
  std::ofstream out(path);
  if (!out) fail(kFile, "cannot write " + path);
  out << "t_s";
  for (std::uint16_t id : c.channels) out << "," << signal_name(id);
  out << "\n";
  const std::size_t n = c.channels.size();
  char buf[64];
  for (std::uint32_t s = 0; s < c.samples; ++s) {
    std::snprintf(buf, sizeof buf, "%.6f", (static_cast<double>(s) - static_cast<double>(c.trigger_index)) / c.sample_rate_Hz);
    out << buf;
    for (std::size_t ch = 0; ch < n; ++ch) {
      std::snprintf(buf, sizeof buf, ",%.9g", static_cast<double>(c.values[s * n + ch]));
      out << buf;
    }
    out << "\n";
  }
  if (!out) fail(kFile, "cannot write " + path);
  std::remove(partial_data(dir).c_str());
  std::remove(partial_meta(dir).c_str());
  std::printf("wrote %s (%u samples x %zu channels, %.1f Hz, trigger at sample %u)\n", path.c_str(), c.samples, n,
              c.sample_rate_Hz, c.trigger_index);
}

int record(Lab& lab, const std::vector<std::string>& args) {
  std::string dir;
  std::vector<std::uint16_t> channels;
  double duration_s = -1, pretrigger_s = 0, timeout_s = 60;
  long length = -1, decimation = 1, max_blocks = -1;
  bool resume = false, download_only = false;
  std::string trigger = "immediate";
  for (std::size_t i = 1; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= args.size()) fail(kUsage, a + " needs a value");
      return args[++i];
    };
    if (a == "--out") dir = next();
    else if (a == "--channels") {
      for (const std::string& name : split(next(), ',')) {
        const std::uint16_t id = lab::find_signal(name.c_str());
        if (id == 0) fail(kBadValue, "unknown signal '" + name + "' (stagectl record --signals lists them)");
        channels.push_back(id);
      }
    } else if (a == "--duration") duration_s = number(a, next());
    else if (a == "--length") length = std::lround(number(a, next()));
    else if (a == "--decimation") decimation = std::lround(number(a, next()));
    else if (a == "--pretrigger") pretrigger_s = number(a, next());
    else if (a == "--trigger") trigger = next();
    else if (a == "--timeout") timeout_s = number(a, next());
    else if (a == "--max-blocks") max_blocks = std::lround(number(a, next()));
    else if (a == "--resume") resume = true;
    else if (a == "--download") download_only = true;
    else if (a == "--signals") {
      char buf[40];
      for (std::uint16_t id = 1; id < lab::kSignalIdEnd; ++id) {
        if (lab::signal_name(id, buf, sizeof buf)) std::printf("%3u  %-22s %s\n", id, buf, lab::signal_unit(id));
      }
      return kOk;
    } else fail(kUsage, "record: unknown option '" + a + "'");
  }
  make_dir(dir);
  if (!resume && !download_only) {
    if (channels.empty()) {
      for (const char* s : {"x.pose", "x.reference", "x.error", "x.effort", "z.pose", "z.effort", "state", "fault"}) {
        channels.push_back(lab::find_signal(s));
      }
    }
    if (channels.size() > 8) fail(kBadValue, "at most 8 channels (got " + std::to_string(channels.size()) + ")");
    // Servo rate from the recorder itself (rec.sample_rate at decimation 1 is
    // unknown until configured): the register map's servo rate is rec.sample_rate x decimation.
    lab.set(RegId::rec_control, 3);  // stop (the fault watch is armed at boot)
    const double servo_rate = lab.get(RegId::rec_sample_rate) * lab.get(RegId::rec_decimation);
    const double fs = servo_rate / static_cast<double>(decimation);
    if (length < 0) length = std::lround((duration_s > 0 ? duration_s : 1.0) * fs);
    Lab::Block b = lab.block(RegId::rec_control, RegId::rec_trigger_level);
    b.put(RegId::rec_channel_count, static_cast<double>(channels.size()));
    for (std::size_t i = 0; i < 8; ++i) {
      b.put(static_cast<RegId>(static_cast<int>(RegId::rec_channel_0) + static_cast<int>(i)), i < channels.size() ? channels[i] : 0);
    }
    b.put(RegId::rec_decimation, static_cast<double>(decimation));
    b.put(RegId::rec_length, static_cast<double>(length));
    b.put(RegId::rec_pretrigger, static_cast<double>(std::lround(pretrigger_s * fs)));
    const std::vector<std::string> t = split(trigger, ':');
    double mode = 0;
    if (t[0] == "immediate") mode = 0;
    else if (t[0] == "command") mode = 1;
    else if (t[0] == "fault") mode = 3;
    else if (t[0] == "level" && (t.size() == 3 || t.size() == 4)) {
      mode = 2;
      const std::uint16_t sig = lab::find_signal(t[1].c_str());
      if (sig == 0) fail(kBadValue, "unknown trigger signal '" + t[1] + "'");
      b.put(RegId::rec_trigger_signal, sig);
      b.put(RegId::rec_trigger_level, number("--trigger level", t[2]));
      const std::string edge = t.size() == 4 ? t[3] : "rising";
      b.put(RegId::rec_trigger_edge, edge == "rising" ? 0 : edge == "falling" ? 1 : edge == "either" ? 2 : -1);
      if (edge != "rising" && edge != "falling" && edge != "either") fail(kUsage, "--trigger level edge: rising|falling|either");
    } else {
      fail(kUsage, "--trigger immediate|command|fault|level:SIGNAL:LEVEL[:rising|falling|either]");
    }
    b.put(RegId::rec_trigger_mode, mode);
    b.put(RegId::rec_control, 1);  // arm, after the configuration of the same request
    lab.write(b, "recorder configuration + arm");
    std::fprintf(stderr, "recorder armed: %zu channels, %ld samples at %.1f Hz (%.2f s), trigger %s\n", channels.size(),
                 length, fs, static_cast<double>(length) / fs, trigger.c_str());
    if (mode == 1) {
      std::this_thread::sleep_for(std::chrono::duration<double>(pretrigger_s + 0.05));
      lab.set(RegId::rec_control, 2);
    }
    wait_done(lab, timeout_s + static_cast<double>(length) / fs, "recording", mode == 0 ? static_cast<double>(length) / fs : 0.0);
  }
  const Capture c = download(lab, dir, resume, max_blocks);
  write_record_csv(c, dir);
  run_plot("record", dir);
  return kOk;
}

// --- frf ---------------------------------------------------------------------

int frf(Lab& lab, const std::vector<std::string>& args) {
  if (args.size() < 2) fail(kUsage, "frf AXIS --out DIR [options]");
  int axis = -1;
  for (int a = 0; a < kernel::kAxisCount; ++a) {
    if (args[1] == kernel::kAxisNames[a]) axis = a;
  }
  if (axis < 0) fail(kUsage, "frf: unknown axis '" + args[1] + "' (x y theta_z z theta_x theta_y)");
  std::string dir;
  // The default peak: 0.1 A on x, y and z; 0.01 A on the tilts and theta_z,
  // whose unit of effort drives the coils ~10x harder (a 0.1 A multisine at
  // theta_z or theta_x put the default stage into FollowingError within 4 ms,
  // 2026-11-29; 0.02 A measured theta_z at 83.3 Hz / 47.1 deg, as the bench).
  const bool rotation = kernel::is_rotation(kernel::kAllAxes[axis]);
  constexpr lab::WaveConfig kDefault = lab::LoopResponseMultisine();
  double amplitude = static_cast<double>(kDefault.amplitude) * (rotation ? 0.1 : 1.0);
  double f_min = static_cast<double>(kDefault.f_start_Hz), f_max = static_cast<double>(kDefault.f_end_Hz);
  double settle_s = 1.0;
  long tones = kDefault.tones, periods = 4;
  bool periods_given = false;
  for (std::size_t i = 2; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= args.size()) fail(kUsage, a + " needs a value");
      return args[++i];
    };
    if (a == "--out") dir = next();
    else if (a == "--amplitude") amplitude = number(a, next());
    else if (a == "--f-min") f_min = number(a, next());
    else if (a == "--f-max") f_max = number(a, next());
    else if (a == "--tones") tones = std::lround(number(a, next()));
    else if (a == "--periods") {
      periods = std::lround(number(a, next()));
      periods_given = true;
    }
    else if (a == "--settle") settle_s = number(a, next());
    else fail(kUsage, "frf: unknown option '" + a + "'");
  }
  make_dir(dir);
  if (periods < 2) fail(kUsage, "--periods: at least 2 (coherence needs more than one period)");
  if (static_cast<int>(lab.get(RegId::status_state)) != 6) fail(kBusy, "frf needs the stage levitated (state ready)");
  const std::string ax = kernel::kAxisNames[axis];
  // Recorder: d, u_loop, u_total of the axis, whole periods at the servo rate.
  lab.set(RegId::rec_control, 3);
  lab.set(RegId::wave_control, 2);
  const double fs = lab.get(RegId::rec_sample_rate) * lab.get(RegId::rec_decimation);
  const auto period = static_cast<long>(std::lround(fs));  // the generator's 1 Hz grid: one period = 1 s
  // What the recorder holds of three channels: its memory is rec.capacity x
  // rec.channel_count samples now (floored: at most one sample a channel
  // short). At 20 kHz the default 4 periods (80 000 samples) do not fit the
  // board's 43 690; without --periods, as many as fit (at least 2).
  const auto pool = static_cast<long>(lab.get(RegId::rec_capacity)) * static_cast<long>(lab.get(RegId::rec_channel_count));
  const long fit = pool / 3 / period;
  if (periods > fit) {
    if (periods_given || fit < 2) {
      fail(kUsage, "frf: " + std::to_string(periods) + " periods of " + std::to_string(period) +
                       " samples do not fit the recorder (" + std::to_string(pool / 3) + " samples of 3 channels): --periods " +
                       std::to_string(fit < 2 ? 2 : fit) + (fit < 2 ? " does not fit either" : ""));
    }
    std::fprintf(stderr, "frf %s: %ld periods of %ld samples fit the recorder (%ld samples of 3 channels): measuring %ld\n",
                 kernel::kAxisNames[axis], fit, period, pool / 3, fit);
    periods = fit;
  }
  Lab::Block r = lab.block(RegId::rec_control, RegId::rec_trigger_level);
  const std::uint16_t ch[3] = {lab::find_signal((ax + ".excitation").c_str()), lab::find_signal((ax + ".loop_effort").c_str()),
                               lab::find_signal((ax + ".effort").c_str())};
  r.put(RegId::rec_channel_count, 3);
  for (int i = 0; i < 8; ++i) r.put(static_cast<RegId>(static_cast<int>(RegId::rec_channel_0) + i), i < 3 ? ch[i] : 0);
  r.put(RegId::rec_decimation, 1);
  r.put(RegId::rec_length, static_cast<double>(periods * period));
  r.put(RegId::rec_pretrigger, 0);
  r.put(RegId::rec_trigger_mode, 0);
  lab.write(r, "recorder configuration");
  // Wave generator: multisine at the effort, until stopped.
  Lab::Block w = lab.block(RegId::wave_control, RegId::wave_duration);
  w.put(RegId::wave_axis, axis);
  w.put(RegId::wave_point, 0);
  w.put(RegId::wave_shape, 2);
  w.put(RegId::wave_tones, static_cast<double>(tones));
  w.put(RegId::wave_amplitude, amplitude);
  w.put(RegId::wave_f_start, f_min);
  w.put(RegId::wave_f_end, f_max);
  w.put(RegId::wave_duration, 0);
  w.put(RegId::wave_control, 1);
  lab.write(w, "wave generator start");
  std::fprintf(stderr, "frf %s: multisine %ld tones %.3g..%.3g Hz, peak %.3g A at the effort; settling %.1f s\n", ax.c_str(),
               tones, f_min, f_max, amplitude, settle_s);
  {
    Progress p("settling");
    while (p.elapsed() < settle_s) {
      p.update(p.elapsed(), settle_s, "s");
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  lab.set(RegId::rec_control, 1);
  try {
    wait_done(lab, 30.0 + static_cast<double>(periods), "measuring", static_cast<double>(periods));
  } catch (const LabError&) {
    lab.set(RegId::wave_control, 2);
    throw;
  }
  const int wave_state = static_cast<int>(lab.get(RegId::wave_state));
  lab.set(RegId::wave_control, 2);
  if (wave_state != 1) fail(kRefused, "the wave generator stopped during the measurement (wave.state " + std::to_string(wave_state) + ": left Ready?)");
  const Capture c = download(lab, dir, false, -1);
  std::remove(partial_data(dir).c_str());
  std::remove(partial_meta(dir).c_str());
  // Columns.
  const std::size_t n = c.samples;
  std::vector<double> d(n), u(n), tot(n);
  for (std::size_t s = 0; s < n; ++s) {
    d[s] = c.values[3 * s];
    u[s] = -static_cast<double>(c.values[3 * s + 1]);  // -u: L = -u / (u + d)
    tot[s] = c.values[3 * s + 2];
  }
  // The tones: the 1 Hz-grid lines where d has energy (the generator's own
  // lines, found in the data: one-period DFT of d).
  std::vector<double> freqs;
  {
    // Up to f_max only: above 4096 Hz the generator holds its table samples
    // (lab::MultisineHoldTicks), whose images around multiples of
    // servo_rate / hold (>= 2500 Hz) would otherwise be taken for tones.
    std::vector<double> grid;
    for (long k = 1; k < period / 2; ++k) {
      const double f = static_cast<double>(k) * fs / static_cast<double>(period);
      if (f > f_max + 1.0) break;  // tones are f_max rounded to the 1 Hz grid at most
      grid.push_back(f);
    }
    // |D| of one period at each grid line; the tones are the lines above 5 % of the largest.
    std::vector<double> mag(grid.size());
    double peak = 0;
    for (std::size_t k = 0; k < grid.size(); ++k) {
      std::complex<double> x{0, 0};
      for (long i = 0; i < period; ++i) {
        const double ph = 2.0 * std::numbers::pi * grid[k] * static_cast<double>(i) / fs;
        x += d[static_cast<std::size_t>(i)] * std::complex<double>{std::cos(ph), -std::sin(ph)};
      }
      mag[k] = std::abs(x);
      peak = std::max(peak, mag[k]);
    }
    for (std::size_t k = 0; k < grid.size(); ++k) {
      if (mag[k] > 0.05 * peak) freqs.push_back(grid[k]);
    }
  }
  if (freqs.empty()) fail(kRefused, "no excitation in the recording (x.excitation all zero?)");
  const auto open = metrics::frequency_response_segments(tot, u, fs, freqs, static_cast<std::size_t>(period));
  const auto closed = metrics::frequency_response_segments(d, u, fs, freqs, static_cast<std::size_t>(period));
  std::vector<std::complex<double>> L(freqs.size());
  for (std::size_t k = 0; k < freqs.size(); ++k) L[k] = open[k].h;
  const metrics::LoopMargins m = metrics::loop_margins(freqs, L);
  // frf.csv
  const std::string path = dir + "/frf.csv";
  std::ofstream out(path);
  if (!out) fail(kFile, "cannot write " + path);
  out << "f_Hz,open_loop_gain_db,open_loop_phase_deg,closed_loop_gain_db,closed_loop_phase_deg,coherence\n";
  double prev = 0;
  for (std::size_t k = 0; k < freqs.size(); ++k) {
    double ph = std::arg(L[k]) * 180.0 / std::numbers::pi;
    if (k == 0) {
      while (ph > 0) ph -= 360;
    } else {
      while (ph - prev > 180) ph -= 360;
      while (ph - prev < -180) ph += 360;
    }
    prev = ph;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%.6g,%.6f,%.6f,%.6f,%.6f,%.6f\n", freqs[k], 20.0 * std::log10(std::abs(L[k])), ph,
                  20.0 * std::log10(std::abs(closed[k].h)), std::arg(closed[k].h) * 180.0 / std::numbers::pi,
                  open[k].coherence);
    out << buf;
  }
  if (!out) fail(kFile, "cannot write " + path);
  out.close();
  // Margins (the plot marks them; the test reads them).
  std::ofstream js(dir + "/frf_margins.json");
  auto num = [](bool ok, double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.6g", v);
    return ok ? std::string(b) : std::string("null");
  };
  js << "{\n  \"axis\": \"" << ax << "\",\n  \"crossover_Hz\": " << num(m.crossover_found, m.crossover_Hz)
     << ",\n  \"phase_margin_deg\": " << num(m.crossover_found, m.phase_margin_deg)
     << ",\n  \"phase_crossover_Hz\": " << num(m.gain_margin_found, m.phase_crossover_Hz)
     << ",\n  \"gain_margin_dB\": " << num(m.gain_margin_found, m.gain_margin_dB)
     << ",\n  \"closed_loop_bandwidth_Hz\": " << num(m.bandwidth_found, m.closed_loop_bandwidth_Hz)
     << ",\n  \"closed_loop_peak_dB\": " << num(true, m.closed_loop_peak_dB) << ",\n  \"tones\": " << freqs.size()
     << ",\n  \"periods\": " << periods << ",\n  \"amplitude_A\": " << num(true, amplitude) << "\n}\n";
  js.close();
  if (!js) fail(kFile, "cannot write " + dir + "/frf_margins.json");
  std::printf("wrote %s (%zu tones)\n", path.c_str(), freqs.size());
  std::printf("%s: crossover %s Hz, phase margin %s deg, gain margin %s dB (at %s Hz), closed-loop bandwidth %s Hz\n",
              ax.c_str(), num(m.crossover_found, m.crossover_Hz).c_str(), num(m.crossover_found, m.phase_margin_deg).c_str(),
              num(m.gain_margin_found, m.gain_margin_dB).c_str(), num(m.gain_margin_found, m.phase_crossover_Hz).c_str(),
              num(m.bandwidth_found, m.closed_loop_bandwidth_Hz).c_str());
  run_plot("frf", dir);
  return kOk;
}

}  // namespace

int run_lab_command(modbus_t* ctx, const std::vector<std::string>& args) {
  Lab lab(ctx);
  try {
    if (args.at(0) == "record") return record(lab, args);
    if (args.at(0) == "frf") return frf(lab, args);
    fail(kUsage, "unknown lab command '" + args.at(0) + "'");
  } catch (const LabError& e) {
    std::cerr << "stagectl: " << e.message << "\n";
    return e.code;
  }
}

}  // namespace maglev::stagectl
