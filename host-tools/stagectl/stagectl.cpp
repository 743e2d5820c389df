// stagectl: the maglev stage controller's Modbus client (libmodbus).
// The register names, types, units and ranges come from the same
// registers.def the firmware serves (maglev/register_schema/register_map.hpp).
#include <modbus/modbus.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "maglev/io/axis.hpp"
#include "maglev/can_link/host_commands.hpp"
#include "maglev/coupling_calibration/coupling_calibration.hpp"
#include "maglev/controller/controller.hpp"
#include "maglev/register_schema/register_map.hpp"
#include "maglev/supervisor/supervisor.hpp"
#include "exit_codes.hpp"
#include "lab_commands.hpp"

namespace {

using namespace maglev::modbus;
using maglev::can::HostCommandCode;  // cmd.code values: the one command table

// Exit codes: host-tools/stagectl/exit_codes.hpp (also in --help and README.md).
using enum maglev::stagectl::Exit;

const char* kHelp = R"(usage: stagectl (--rtu DEVICE[,BAUD] | --tcp HOST:PORT) [--unit N] [--engineer] [--wait SECONDS]
                [--json] [--count N] [--interval SECONDS] COMMAND

connection:
  --rtu DEVICE[,BAUD]   Modbus RTU on a serial device (default 115200 baud, 8N1)
  --tcp HOST:PORT       Modbus TCP
  --unit N              unit (slave) id, default 1
  --engineer            write the engineer key first (needed for engineer registers)
  --wait SECONDS        after home/levitate/land/move/calibrate: wait until the stage gets
                        there (or the calibration ends), printing its progress (state
                        changes, distance to go, experiment) on stderr
                        (config import/export print theirs too)
  --json                get, dump, status, registers, watch: JSON on stdout (watch: one
                        object per line), for scripts
  --count N             watch: N refreshes, then exit (default: until interrupted)
  --interval SECONDS    watch: time between refreshes (default 0.2)

commands:
  get NAME                 print one register: NAME = value  # unit
  set NAME VALUE[UNIT]     write one register; VALUE in SI or with a unit prefix
                           (1mm, 5um, 20urad, 500mA, 2kHz)
  dump                     print every register
  status                   state, fault, pose, persistence flags
  home | levitate | land | stop | clear-fault
  calibrate                identify and correct the 6x6 effort coupling (Ready; ~30 s). With
                           --wait: its 12 experiments' progress, then the result and the
                           coupling before / after; exit 7 when the kernel kept the old
                           correction (refused, abandoned or failed check: the reason)
  move AXIS VALUE          move AXIS (x y z theta_x theta_y theta_z) to VALUE (absolute)
  move-by AXIS DELTA       move AXIS by DELTA from its measured position
  step AXIS DELTA          reference step (kernel limit: 100 um / 10-20 urad)
  config export FILE       write every persisted register as "name = value  # unit"
  config import FILE       check the whole file, then write every entry
  save                     save the configuration to flash (needs --engineer)
  registers                list the register table (names, addresses, units, ranges)
  watch [NAME...]          live values, refreshed in place (default: state, fault,
                           moving, pose, scale_k); --count, --interval

exit codes:
  0 ok            1 usage        2 cannot connect      3 bad name/value (local check)
  4 refused (02/03/04)           5 busy (06)           6 access (01, engineer needed)
  7 motion command rejected      8 communication error 9 file error     10 --wait timed out
)";

struct Options {
  std::string rtu_device;
  int baud = 115200;
  std::string tcp_host;
  int tcp_port = 0;
  int unit = 1;
  bool engineer = false;
  double wait_s = 0.0;
  bool json = false;        // --json: machine-readable output of the read commands
  long watch_count = 0;     // --count: watch refreshes (0 = until interrupted)
  double interval_s = 0.2;  // --interval: watch period
  std::vector<std::string> args;
};

// Called before exiting: an engineer unlock done by this run is undone, so
// the controller never stays unlocked after stagectl returns.
void (*g_relock)() = nullptr;

[[noreturn]] void die(int code, const std::string& msg) {
  std::cerr << "stagectl: " << msg << "\n";
  if (g_relock != nullptr) g_relock();
  std::exit(code);
}

std::string fmt(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.9g", v);
  return b;
}

std::string range_text(const RegisterDef& d) {
  return "[" + fmt(d.min) + ", " + fmt(d.max) + "]" + (d.unit[0] != '\0' ? std::string(" ") + d.unit : "");
}

const RegisterDef& lookup(const std::string& name) {
  const RegisterDef* d = find_by_name(name.c_str());
  if (d == nullptr) die(kBadValue, "unknown register '" + name + "' (stagectl registers lists them)");
  return *d;
}

// "1mm" -> 1e-3 for unit "m". Accepts SI, or the register's unit with a
// k/m/u/n prefix.
bool parse_value(const std::string& text, const std::string& unit, double& out, std::string& why) {
  const char* s = text.c_str();
  char* end = nullptr;
  double v = std::strtod(s, &end);
  if (end == s) {
    // Integers may be given in hex (access key).
    why = "'" + text + "' is not a number";
    return false;
  }
  if (text.rfind("0x", 0) == 0 || text.rfind("0X", 0) == 0) {
    v = static_cast<double>(std::strtoul(s, &end, 16));
  }
  std::string suffix(end);
  while (!suffix.empty() && suffix.front() == ' ') suffix.erase(0, 1);
  if (suffix.empty() || suffix == unit) {
    out = v;
    return true;
  }
  // "m|rad": either
  std::vector<std::string> units;
  std::stringstream us(unit);
  for (std::string u; std::getline(us, u, '|');) units.push_back(u);
  for (const std::string& u : units) {
    if (suffix == u) {
      out = v;
      return true;
    }
    if (suffix.size() == u.size() + 1 && suffix.compare(1, std::string::npos, u) == 0) {
      double scale = 0.0;
      switch (suffix[0]) {
        case 'k': scale = 1e3; break;
        case 'm': scale = 1e-3; break;
        case 'u': scale = 1e-6; break;
        case 'n': scale = 1e-9; break;
        default: break;
      }
      if (scale != 0.0) {
        out = v * scale;
        return true;
      }
    }
  }
  why = "unit '" + suffix + "' does not fit '" + unit + "'";
  return false;
}

class Client {
 public:
  explicit Client(const Options& o) {
    if (!o.rtu_device.empty()) {
      ctx_ = modbus_new_rtu(o.rtu_device.c_str(), o.baud, 'N', 8, 1);
    } else {
      ctx_ = modbus_new_tcp(o.tcp_host.c_str(), o.tcp_port);
    }
    if (ctx_ == nullptr) die(kConnect, "cannot create a libmodbus context");
    modbus_set_slave(ctx_, o.unit);
    modbus_set_response_timeout(ctx_, 1, 0);
    if (modbus_connect(ctx_) != 0) {
      die(kConnect, std::string("cannot connect to ") +
                        (o.rtu_device.empty() ? o.tcp_host + ":" + std::to_string(o.tcp_port) : o.rtu_device) + ": " +
                        modbus_strerror(errno));
    }
    if (o.engineer) {
      write_raw(def(RegId::access_key), kEngineerKey, "access.key");
      self_ = this;
      g_relock = [] {
        Client* c = self_;
        self_ = nullptr;
        g_relock = nullptr;
        if (c != nullptr) {
          std::uint16_t zero = 0;
          modbus_write_registers(c->ctx_, def(RegId::access_key).address, 1, &zero);
        }
      };
    }
  }
  ~Client() {
    if (g_relock != nullptr) g_relock();
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  modbus_t* context() { return ctx_; }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  std::uint32_t read_raw(const RegisterDef& d) {
    std::uint16_t w[2] = {};
    if (d.type == RegType::kBlock) die(kBadValue, std::string(d.name) + " is a download window: use stagectl record");
    if (modbus_read_registers(ctx_, d.address, width(d.type), w) < 0) fail(d, "read", "");
    return width(d.type) == 1 ? w[0] : join_words(w);
  }
  double read(const RegisterDef& d) { return decode(d.type, read_raw(d)); }

  void write_raw(const RegisterDef& d, std::uint32_t raw, const std::string& shown) {
    std::uint16_t w[2];
    int rc;
    if (width(d.type) == 1) {
      w[0] = static_cast<std::uint16_t>(raw);
      rc = modbus_write_registers(ctx_, d.address, 1, w);
    } else {
      split_words(raw, w);
      rc = modbus_write_registers(ctx_, d.address, 2, w);
    }
    if (rc < 0) fail(d, "write", shown);
  }
  void write(const RegisterDef& d, double v, const std::string& shown) {
    if (!value_in_range(d, v)) {
      die(kBadValue, std::string(d.name) + ": value " + shown + " is out of range " + range_text(d));
    }
    if (d.access == Access::kReadOnly) die(kRefused, std::string(d.name) + " is read-only");
    write_raw(d, encode(d.type, v), shown);
  }

  // cmd.axis, cmd.value, cmd.code in one 0x17, reading cmd.result back.
  std::uint16_t command(HostCommandCode code, std::uint16_t axis, float value) {
    std::uint16_t w[4];
    w[0] = axis;
    split_words(encode(RegType::kF32, static_cast<double>(value)), w + 1);
    w[3] = static_cast<std::uint16_t>(code);
    std::uint16_t result = 0;
    if (modbus_write_and_read_registers(ctx_, def(RegId::cmd_axis).address, 4, w, def(RegId::cmd_result).address, 1,
                                        &result) < 0) {
      fail(def(RegId::cmd_code), "write", std::to_string(static_cast<int>(code)));
    }
    return result;
  }

 private:
  [[noreturn]] void fail(const RegisterDef& d, const char* what, const std::string& shown) {
    const int e = errno;
    const std::string where = std::string(d.name) + " (address " + std::to_string(d.address) + ")";
    const std::string val = shown.empty() ? "" : " value " + shown;
    switch (e - MODBUS_ENOBASE) {
      case 1:
        die(kAccess, std::string("cannot ") + what + " " + where + ": engineer access required (pass --engineer)");
      case 2:
        die(kRefused, std::string("cannot ") + what + " " + where + ": illegal data address (read-only or not in the map)");
      case 3: {
        // The value was in the register's range: the kernel refused the
        // configuration it made (status.config_error says why, e.g. a
        // current limit beyond the selected stage's own).
        std::uint16_t why = 0;
        std::string reason = "see status.config_error";
        if (modbus_read_registers(ctx_, def(RegId::status_config_error).address, 1, &why) == 1 && why != 0) {
          reason = std::string("status.config_error ") + std::to_string(why) + " " +
                   maglev::kernel::to_string(static_cast<maglev::kernel::ConfigError>(why));
        }
        die(kRefused, std::string("cannot ") + what + " " + where + val + ": illegal data value (allowed " +
                          range_text(d) + ", or the controller refused the resulting configuration: " + reason + ")");
      }
      case 4:
        die(kRefused, std::string("cannot ") + what + " " + where + ": server device failure");
      case 6:
        die(kBusy, std::string("cannot ") + what + " " + where + val +
                       " now: controller busy (register writable only when: see stagectl registers)");
      default:
        die(kComm, std::string("cannot ") + what + " " + where + ": " + modbus_strerror(e));
    }
  }
  modbus_t* ctx_ = nullptr;
  static inline Client* self_ = nullptr;
};

using maglev::kernel::kAxisNames;  // the one axis vocabulary, kernel Axis order
const char* state_name(std::uint16_t s) {
  return s <= 255 ? maglev::kernel::to_string(static_cast<maglev::kernel::SequencerState>(s)) : "?";
}
const RegId kPoseReg[] = {RegId::status_x, RegId::status_y, RegId::status_theta_z,
                          RegId::status_z, RegId::status_theta_x, RegId::status_theta_y};

std::uint16_t axis_of(const std::string& s) {
  for (std::uint16_t i = 0; i < 6; ++i) {
    if (s == kAxisNames[i]) return i;
  }
  die(kUsage, "unknown axis '" + s + "' (x, y, z, theta_x, theta_y, theta_z)");
}
bool is_rotation(std::uint16_t axis) { return axis == 2 || axis == 4 || axis == 5; }

std::string line_of(const RegisterDef& d, double v) {
  std::string s = std::string(d.name) + " = " + fmt(v);
  if (d.unit[0] != '\0') s += "  # " + std::string(d.unit);
  return s;
}

double parse_or_die(const RegisterDef& d, const std::string& text, const char* unit_override = nullptr) {
  double v = 0.0;
  std::string why;
  if (!parse_value(text, unit_override != nullptr ? unit_override : d.unit, v, why)) {
    die(kBadValue, std::string(d.name) + ": " + why);
  }
  return v;
}

// Progress of a long operation on stderr (stdout stays the command's result):
// rewritten in place on a terminal, one line per update otherwise (logs, CI).
class Progress {
 public:
  explicit Progress(std::string what) : what_(std::move(what)), tty_(isatty(STDERR_FILENO) == 1) {}
  ~Progress() {
    if (tty_ && shown_) std::cerr << "\n";
  }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  double elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  void update(const std::string& text) {
    char t[32];
    std::snprintf(t, sizeof t, "%6.2f s", elapsed_s());
    std::cerr << (tty_ ? "\r\033[K" : "") << "stagectl: " << what_ << ": " << t << "  " << text << (tty_ ? "" : "\n")
              << std::flush;
    shown_ = true;
  }

 private:
  std::string what_;
  bool tty_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

std::string fault_name(double code) {
  return code >= 0 && code <= 255 ? maglev::kernel::to_string(static_cast<maglev::kernel::FaultCode>(code)) : "?";
}

// Waits for status.state == want, printing every state change. `settle`:
// only accept `want` once the stage has left it or `min_s` has passed (home:
// Idle -> Homing -> Idle, the command acts on the next servo ticks).
int wait_state(Client& c, std::uint16_t want, double seconds, const char* what, double min_s = 0.0) {
  Progress progress(what);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int last = -1;
  bool left = false;
  while (std::chrono::steady_clock::now() < deadline) {
    const auto state = static_cast<std::uint16_t>(c.read(def(RegId::status_state)));
    if (state != last) {
      progress.update(std::string(state_name(state)) + (state == want && (left || progress.elapsed_s() >= min_s) ? " (done)" : ""));
      last = state;
    }
    if (state != want) left = true;
    if (state == want && (left || progress.elapsed_s() >= min_s)) return kOk;
    if (state == 8) {
      const double f = c.read(def(RegId::status_fault));
      die(kCommandRejected, "stage faulted (status.fault = " + fmt(f) + " " + fault_name(f) + ")");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  die(kTimeout, std::string("timed out waiting for state '") + state_name(want) + "'");
}

// Sends a host command; exit 7 with the kernel's reason when cmd.result is not 0.
void command_or_die(Client& c, HostCommandCode code, std::uint16_t axis, float value) {
  const std::uint16_t r = c.command(code, axis, value);
  if (r != 0) {
    die(kCommandRejected, std::string("command rejected: ") +
                              (r <= 255 ? maglev::kernel::to_string(static_cast<maglev::kernel::CommandResult>(r))
                                        : "code " + std::to_string(r)));
  }
}

int run_command(Client& c, HostCommandCode code, std::uint16_t axis, float value, const Options& o) {
  command_or_die(c, code, axis, value);
  if (o.wait_s <= 0.0) return kOk;
  switch (code) {
    case HostCommandCode::kHome: return wait_state(c, 0, o.wait_s, "home", 0.2);
    case HostCommandCode::kLevitate: return wait_state(c, 6, o.wait_s, "levitate");
    case HostCommandCode::kLand: return wait_state(c, 0, o.wait_s, "land");
    case HostCommandCode::kMoveTo: {
      Progress progress(std::string("move ") + kAxisNames[axis]);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_s);
      const double tol = is_rotation(axis) ? 1e-6 : 1e-6;
      const char* unit = is_rotation(axis) ? " urad" : " um";
      double next_report_s = 0.0;
      while (std::chrono::steady_clock::now() < deadline) {
        const double to_go = static_cast<double>(value) - c.read(def(kPoseReg[axis]));
        // There, and the move's profile ended: within the tolerance the
        // profile's last ticks may still run, and a command sent then was
        // refused busy (a calibration right after `--wait move`).
        const bool done = std::fabs(to_go) < tol && c.read(def(RegId::status_moving)) == 0.0;
        if (done || progress.elapsed_s() >= next_report_s) {
          char text[64];
          std::snprintf(text, sizeof text, "%.3f%s to go%s", to_go * 1e6, unit, done ? " (done)" : "");
          progress.update(text);
          next_report_s = progress.elapsed_s() + 0.25;
        }
        if (done) return kOk;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      die(kTimeout, "timed out waiting for the move");
    }
    default: return kOk;
  }
}

// calibrate: cmd.code 17 (the kernel's coupling calibration, docs/KERNEL.md
// "Coupling calibration"). With --wait: progress from status.calibration_step,
// then the kernel's result. The result register keeps the last run's value
// until the kernel takes the command on its next tick, so an end is read only
// once this run was seen running, or after 0.2 s (a refusal never runs).
int do_calibrate(Client& c, const Options& o) {
  using maglev::kernel::CouplingCalibrationResult;
  command_or_die(c, HostCommandCode::kCalibrateCoupling, 0, 0.0f);
  if (o.wait_s <= 0.0) {
    std::cout << "calibration started (status.calibration, status.calibration_step; stagectl --wait S calibrate waits)\n";
    return kOk;
  }
  const auto running = static_cast<double>(CouplingCalibrationResult::kRunning);
  const double experiments = def(RegId::status_calibration_step).max;  // 12: identification, then verification
  Progress progress("calibrate");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_s);
  bool seen_running = false;
  double last_step = -1.0, result = 0.0;
  for (;;) {
    if (std::chrono::steady_clock::now() >= deadline) die(kTimeout, "timed out waiting for the calibration");
    result = c.read(def(RegId::status_calibration));
    seen_running = seen_running || result == running;
    if (result != running && (seen_running || progress.elapsed_s() >= 0.2)) break;
    const double step = c.read(def(RegId::status_calibration_step));
    if (result == running && step != last_step) {
      progress.update("experiment " + fmt(step) + "/" + fmt(experiments) +
                      (step < experiments / 2 ? " (identifying)" : " (verifying the correction)"));
      last_step = step;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const auto code = static_cast<CouplingCalibrationResult>(static_cast<int>(result));
  const double before = c.read(def(RegId::status_coupling_before)), after = c.read(def(RegId::status_coupling_after));
  if (code != CouplingCalibrationResult::kPassed) {
    die(kCommandRejected, std::string("calibration ") + maglev::kernel::to_string(code) + " (status.calibration = " +
                              fmt(result) + ", docs/KERNEL.md): the previous correction stays" +
                              (before > 0.0 ? "; coupling found " + fmt(before) + ", after " + fmt(after) : ""));
  }
  std::cout << "calibration " << maglev::kernel::to_string(code) << ": coupling " << fmt(before) << " -> " << fmt(after)
            << " (status.coupling_before / _after); the correction acts (coupling.enabled = "
            << fmt(c.read(def(RegId::coupling_enabled))) << "); stagectl --engineer save keeps it\n";
  return kOk;
}

int do_status(Client& c) {
  const auto state = static_cast<std::uint16_t>(c.read(def(RegId::status_state)));
  std::cout << "state      = " << state_name(state) << " (" << state << ")\n";
  std::cout << "fault      = " << fmt(c.read(def(RegId::status_fault))) << "\n";
  std::cout << "saturation = " << fmt(c.read(def(RegId::status_saturation))) << "  scale_k = "
            << fmt(c.read(def(RegId::status_scale_k))) << "\n";
  std::cout << "x          = " << fmt(c.read(def(RegId::status_x)) * 1e3) << " mm\n";
  std::cout << "y          = " << fmt(c.read(def(RegId::status_y)) * 1e3) << " mm\n";
  std::cout << "z          = " << fmt(c.read(def(RegId::status_z)) * 1e6) << " um\n";
  std::cout << "theta_x    = " << fmt(c.read(def(RegId::status_theta_x)) * 1e6) << " urad\n";
  std::cout << "theta_y    = " << fmt(c.read(def(RegId::status_theta_y)) * 1e6) << " urad\n";
  std::cout << "theta_z    = " << fmt(c.read(def(RegId::status_theta_z)) * 1e6) << " urad\n";
  const auto flags = static_cast<std::uint16_t>(c.read(def(RegId::persist_flags)));
  std::cout << "persist    = flags 0x" << std::hex << flags << std::dec << " reason "
            << fmt(c.read(def(RegId::persist_reason))) << " sequence " << fmt(c.read(def(RegId::persist_sequence)))
            << ((flags & kBankACorrupt) ? " [bank A corrupt]" : "") << ((flags & kBankBCorrupt) ? " [bank B corrupt]" : "")
            << ((flags & kLoadedDefaults) ? " [defaults]" : "") << ((flags & kUnsaved) ? " [unsaved changes]" : "")
            << "\n";
  return kOk;
}

int config_import(Client& c, const std::string& path) {
  std::ifstream in(path);
  if (!in) die(kFile, "cannot read " + path);
  struct Entry {
    const RegisterDef* d;
    double v;
    std::string text;
  };
  std::vector<Entry> entries;
  std::vector<std::string> errors;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto hash = line.find('#');
    std::string unit;
    if (hash != std::string::npos) {
      unit = line.substr(hash + 1);
      line = line.substr(0, hash);
    }
    auto trim = [](std::string s) {
      const auto b = s.find_first_not_of(" \t\r");
      const auto e = s.find_last_not_of(" \t\r");
      return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    line = trim(line);
    unit = trim(unit);
    if (line.empty()) continue;
    const auto eq = line.find('=');
    if (eq == std::string::npos) {
      errors.push_back(path + ":" + std::to_string(n) + ": expected 'name = value'");
      continue;
    }
    const std::string name = trim(line.substr(0, eq));
    const std::string value = trim(line.substr(eq + 1));
    const RegisterDef* d = find_by_name(name.c_str());
    if (d == nullptr || !d->persisted) {
      errors.push_back(path + ":" + std::to_string(n) + ": '" + name + "' is not a configuration register");
      continue;
    }
    double v = 0.0;
    std::string why;
    // The unit comment, when present, applies to a bare number.
    std::string text = value;
    if (!unit.empty() && value.find_first_not_of("0123456789.eE+-") == std::string::npos) text += " " + unit;
    if (!parse_value(text, d->unit, v, why)) {
      errors.push_back(path + ":" + std::to_string(n) + ": " + name + ": " + why);
      continue;
    }
    if (!value_in_range(*d, v)) {
      errors.push_back(path + ":" + std::to_string(n) + ": " + name + ": value " + value + " is out of range " +
                       range_text(*d));
      continue;
    }
    entries.push_back({d, v, value});
  }
  if (!errors.empty()) {
    for (const auto& e : errors) std::cerr << e << "\n";
    die(kFile, std::to_string(errors.size()) + " error(s) in " + path + "; nothing written");
  }
  Progress progress("config import");
  for (std::size_t i = 0; i < entries.size(); ++i) {
    c.write(*entries[i].d, entries[i].v, entries[i].text);
    // A line per 25% (RTU: ~10 ms per entry, a full image takes seconds).
    if ((i + 1) * 4 / entries.size() != i * 4 / entries.size()) {
      progress.update(std::to_string(i + 1) + "/" + std::to_string(entries.size()) + " written");
    }
  }
  std::cout << "imported " << entries.size() << " entries from " << path << "\n";
  return kOk;
}

// ---- machine-readable output (--json) and watch --------------------------------
std::string json_str(const std::string& text) {
  std::string out = "\"";
  for (const char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", static_cast<unsigned>(ch));
      out += b;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}
// JSON has no NaN/inf: null.
std::string json_num(double v) { return std::isfinite(v) ? fmt(v) : "null"; }

int json_get(Client& c, const RegisterDef& d) {
  std::cout << "{\"name\": " << json_str(d.name) << ", \"value\": " << json_num(c.read(d)) << ", \"unit\": "
            << json_str(d.unit) << "}\n";
  return kOk;
}

// What dump prints: every value register; not a download window (kBlock:
// stagectl record), not the lab registers of a controller without them.
bool dumped(const RegisterDef& d, bool lab) {
  return d.type != RegType::kBlock && (d.kind != Kind::kLab || lab);
}

// Every dumped register: {"name": value, ...} in address order (units: registers --json).
int json_dump(Client& c, bool lab) {
  std::cout << "{";
  bool first = true;
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    if (!dumped(kRegisters[i], lab)) continue;
    std::cout << (first ? "\n  " : ",\n  ") << json_str(kRegisters[i].name) << ": " << json_num(c.read(kRegisters[i]));
    first = false;
  }
  std::cout << "\n}\n";
  return kOk;
}

int json_registers() {
  std::cout << "[";
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    const RegisterDef& d = kRegisters[i];
    std::cout << (i == 0 ? "\n  " : ",\n  ") << "{\"name\": " << json_str(d.name) << ", \"address\": " << d.address
              << ", \"type\": " << json_str(type_name(d.type)) << ", \"unit\": " << json_str(d.unit)
              << ", \"min\": " << json_num(d.min) << ", \"max\": " << json_num(d.max)
              << ", \"default\": " << json_num(d.default_value) << ", \"access\": " << json_str(access_name(d.access))
              << ", \"writable_when\": " << json_str(when_name(d.when))
              << ", \"persisted\": " << (d.persisted ? "true" : "false")
              << ", \"description\": " << json_str(d.description) << "}";
  }
  std::cout << "\n]\n";
  return kOk;
}

// status as one object, SI units (pose in m / rad).
int json_status(Client& c) {
  const double state = c.read(def(RegId::status_state));
  const double fault = c.read(def(RegId::status_fault));
  const auto flags = static_cast<std::uint16_t>(c.read(def(RegId::persist_flags)));
  std::cout << "{\"state\": " << json_num(state) << ", \"state_name\": "
            << json_str(state_name(static_cast<std::uint16_t>(state))) << ", \"fault\": " << json_num(fault)
            << ", \"fault_name\": " << json_str(fault_name(fault))
            << ", \"moving\": " << json_num(c.read(def(RegId::status_moving)))
            << ", \"saturation\": " << json_num(c.read(def(RegId::status_saturation)))
            << ", \"scale_k\": " << json_num(c.read(def(RegId::status_scale_k))) << ", \"pose\": {";
  for (std::size_t a = 0; a < 6; ++a) {
    std::cout << (a == 0 ? "" : ", ") << json_str(kAxisNames[a]) << ": " << json_num(c.read(def(kPoseReg[a])));
  }
  std::cout << "}, \"persist\": {\"flags\": " << flags << ", \"reason\": " << json_num(c.read(def(RegId::persist_reason)))
            << ", \"sequence\": " << json_num(c.read(def(RegId::persist_sequence))) << ", \"unsaved\": "
            << ((flags & kUnsaved) ? "true" : "false") << "}}\n";
  return kOk;
}

// watch: the registers' values refreshed every --interval, --count times (0 =
// until interrupted). On a terminal the block is rewritten in place (ANSI
// cursor-up + erase-line); otherwise each refresh is a new block (logs,
// pipes); --json prints one object per refresh ({"t": s, "name": value, ...}).
int do_watch(Client& c, const Options& o, const std::vector<std::string>& names) {
  std::vector<const RegisterDef*> regs;
  if (names.empty()) {
    const RegId defaults[] = {RegId::status_state,   RegId::status_fault,   RegId::status_moving,
                              RegId::status_x,       RegId::status_y,       RegId::status_z,
                              RegId::status_theta_x, RegId::status_theta_y, RegId::status_theta_z,
                              RegId::status_scale_k};
    for (RegId id : defaults) regs.push_back(&def(id));
  } else {
    for (const std::string& n : names) regs.push_back(&lookup(n));
  }
  const bool ansi = !o.json && isatty(STDOUT_FILENO) == 1;
  const auto t0 = std::chrono::steady_clock::now();
  auto next = t0;
  for (long n = 0; o.watch_count == 0 || n < o.watch_count; ++n) {
    std::vector<double> v;
    for (const RegisterDef* d : regs) v.push_back(c.read(*d));
    const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream out;
    if (o.json) {
      out << "{\"t\": " << json_num(t);
      for (std::size_t i = 0; i < regs.size(); ++i) out << ", " << json_str(regs[i]->name) << ": " << json_num(v[i]);
      out << "}\n";
    } else {
      if (ansi && n > 0) out << "\033[" << regs.size() + 1 << "A";  // back to the block's first line
      char head[96];
      std::snprintf(head, sizeof head, "stagectl watch  t = %8.2f s  refresh %ld", t, n + 1);
      out << head << (ansi ? "\033[K" : "") << "\n";
      for (std::size_t i = 0; i < regs.size(); ++i) {
        std::string line = "  " + line_of(*regs[i], v[i]);
        if (regs[i]->address == def(RegId::status_state).address) {
          line += "  (" + std::string(state_name(static_cast<std::uint16_t>(v[i]))) + ")";
        } else if (regs[i]->address == def(RegId::status_fault).address) {
          line += "  (" + fault_name(v[i]) + ")";
        }
        out << line << (ansi ? "\033[K" : "") << "\n";
      }
      if (!ansi) out << "\n";
    }
    std::cout << out.str() << std::flush;
    if (o.watch_count != 0 && n + 1 >= o.watch_count) break;
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(o.interval_s));
    std::this_thread::sleep_until(next);
  }
  return kOk;
}

Options parse_args(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) die(kUsage, a + " needs an argument");
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      std::cout << kHelp << "\n" << maglev::stagectl::kLabHelp;
      std::exit(kOk);
    } else if (a == "--rtu") {
      std::string v = next();
      const auto comma = v.find(',');
      if (comma != std::string::npos) {
        o.baud = std::atoi(v.c_str() + comma + 1);
        v = v.substr(0, comma);
      }
      o.rtu_device = v;
    } else if (a == "--tcp") {
      const std::string v = next();
      const auto colon = v.rfind(':');
      if (colon == std::string::npos) die(kUsage, "--tcp needs HOST:PORT");
      o.tcp_host = v.substr(0, colon);
      o.tcp_port = std::atoi(v.c_str() + colon + 1);
    } else if (a == "--unit") {
      o.unit = std::atoi(next().c_str());
    } else if (a == "--engineer") {
      o.engineer = true;
    } else if (a == "--wait") {
      o.wait_s = std::atof(next().c_str());
    } else if (a == "--json") {
      o.json = true;
    } else if (a == "--count") {
      o.watch_count = std::atol(next().c_str());
      if (o.watch_count <= 0) die(kUsage, "--count needs a positive number");
    } else if (a == "--interval") {
      o.interval_s = std::atof(next().c_str());
      if (!(o.interval_s > 0.0)) die(kUsage, "--interval needs a positive number of seconds");
    } else {
      o.args.push_back(a);
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse_args(argc, argv);
  if (o.args.empty()) die(kUsage, "no command (stagectl --help)");
  const std::string cmd = o.args[0];
  const auto need = [&](std::size_t n) {
    if (o.args.size() != n + 1) die(kUsage, cmd + " takes " + std::to_string(n) + " argument(s)");
  };
  if (cmd == "registers" && o.json) return json_registers();
  if (cmd == "registers") {
    for (std::size_t i = 0; i < kRegisterCount; ++i) {
      const RegisterDef& d = kRegisters[i];
      std::printf("%5u  %-32s %-8s %s\n", d.address, d.name, d.unit,
                  d.access == Access::kReadOnly ? "read-only" : range_text(d).c_str());
    }
    return kOk;
  }
  if (o.rtu_device.empty() && o.tcp_host.empty()) die(kUsage, "give --rtu DEVICE[,BAUD] or --tcp HOST:PORT");
  Client c(o);
  if (cmd == "get") {
    need(1);
    const RegisterDef& d = lookup(o.args[1]);
    if (o.json) return json_get(c, d);
    std::cout << line_of(d, c.read(d)) << "\n";
    return kOk;
  }
  if (cmd == "set") {
    if (o.args.size() != 3 && o.args.size() != 4) die(kUsage, "set NAME VALUE [UNIT]");
    const RegisterDef& d = lookup(o.args[1]);
    const std::string text = o.args.size() == 4 ? o.args[2] + o.args[3] : o.args[2];
    c.write(d, parse_or_die(d, text), text);
    std::cout << line_of(d, c.read(d)) << "\n";
    return kOk;
  }
  if (cmd == "dump") {
    need(0);
    // A controller without the lab tools answers 02 for rec.* / wave.*: left out.
    std::uint16_t probe = 0;
    const bool lab = modbus_read_registers(c.context(), def(RegId::rec_state).address, 1, &probe) == 1;
    if (o.json) return json_dump(c, lab);
    for (std::size_t i = 0; i < kRegisterCount; ++i) {
      if (!dumped(kRegisters[i], lab)) continue;
      std::cout << line_of(kRegisters[i], c.read(kRegisters[i])) << "\n";
    }
    return kOk;
  }
  if (cmd == "status") return o.json ? json_status(c) : do_status(c);
  if (cmd == "watch") return do_watch(c, o, std::vector<std::string>(o.args.begin() + 1, o.args.end()));
  if (cmd == "record" || cmd == "frf") return maglev::stagectl::run_lab_command(c.context(), o.args);
  if (cmd == "home") return run_command(c, HostCommandCode::kHome, 0, 0.0f, o);
  if (cmd == "levitate") return run_command(c, HostCommandCode::kLevitate, 0, 0.0f, o);
  if (cmd == "land") return run_command(c, HostCommandCode::kLand, 0, 0.0f, o);
  if (cmd == "stop") return run_command(c, HostCommandCode::kStop, 0, 0.0f, o);
  if (cmd == "clear-fault") return run_command(c, HostCommandCode::kClearFault, 0, 0.0f, o);
  if (cmd == "calibrate") {
    need(0);
    return do_calibrate(c, o);
  }
  if (cmd == "move" || cmd == "move-by" || cmd == "step") {
    need(2);
    const std::uint16_t axis = axis_of(o.args[1]);
    double v = parse_or_die(def(RegId::cmd_value), o.args[2], is_rotation(axis) ? "rad" : "m");
    if (cmd == "move-by") v += c.read(def(kPoseReg[axis]));
    if (!value_in_range(def(RegId::cmd_value), v)) {
      die(kBadValue, "cmd.value: value " + o.args[2] + " is out of range " + range_text(def(RegId::cmd_value)));
    }
    return run_command(c, cmd == "step" ? HostCommandCode::kStep : HostCommandCode::kMoveTo, axis, static_cast<float>(v), o);
  }
  if (cmd == "save") {
    need(0);
    c.write(def(RegId::config_save), 1.0, "1");
    std::cout << "saved (sequence " << fmt(c.read(def(RegId::persist_sequence))) << ")\n";
    return kOk;
  }
  if (cmd == "config") {
    need(2);
    if (o.args[1] == "export") {
      std::ofstream out(o.args[2]);
      if (!out) die(kFile, "cannot write " + o.args[2]);
      out << "# maglev stage configuration (stagectl config export); schema hash 0x" << std::hex << kSchemaHash
          << std::dec << "\n";
      Progress progress("config export");
      for (std::size_t s = 0; s < kPersistedCount; ++s) {
        out << line_of(persisted_def(s), c.read(persisted_def(s))) << "\n";
        if ((s + 1) * 4 / kPersistedCount != s * 4 / kPersistedCount) {
          progress.update(std::to_string(s + 1) + "/" + std::to_string(kPersistedCount) + " read");
        }
      }
      if (!out) die(kFile, "cannot write " + o.args[2]);
      std::cout << "exported " << kPersistedCount << " entries to " << o.args[2] << "\n";
      return kOk;
    }
    if (o.args[1] == "import") return config_import(c, o.args[2]);
    die(kUsage, "config export FILE | config import FILE");
  }
  die(kUsage, "unknown command '" + cmd + "' (stagectl --help)");
}
