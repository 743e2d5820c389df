// stagectl: the maglev stage controller's Modbus client (libmodbus).
// The register names, types, units and ranges come from the same
// registers.def the firmware serves (maglev/register_schema/register_map.hpp).
#include <modbus/modbus.h>

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
#include "maglev/controller/controller.hpp"
#include "maglev/register_schema/register_map.hpp"
#include "exit_codes.hpp"
#include "lab_commands.hpp"

namespace {

using namespace maglev::modbus;
using maglev::can::HostCommandCode;  // cmd.code values: the one command table

// Exit codes: host-tools/stagectl/exit_codes.hpp (also in --help and README.md).
using enum maglev::stagectl::Exit;

const char* kHelp = R"(usage: stagectl (--rtu DEVICE[,BAUD] | --tcp HOST:PORT) [--unit N] [--engineer] [--wait SECONDS] COMMAND

connection:
  --rtu DEVICE[,BAUD]   Modbus RTU on a serial device (default 115200 baud, 8N1)
  --tcp HOST:PORT       Modbus TCP
  --unit N              unit (slave) id, default 1
  --engineer            write the engineer key first (needed for engineer registers)
  --wait SECONDS        after home/levitate/land/move: wait until the stage gets there

commands:
  get NAME                 print one register: NAME = value  # unit
  set NAME VALUE[UNIT]     write one register; VALUE in SI or with a unit prefix
                           (1mm, 5um, 20urad, 500mA, 2kHz)
  dump                     print every register
  status                   state, fault, pose, persistence flags
  home | levitate | land | stop | clear-fault
  move AXIS VALUE          move AXIS (x y z theta_x theta_y theta_z) to VALUE (absolute)
  move-by AXIS DELTA       move AXIS by DELTA from its measured position
  step AXIS DELTA          reference step (kernel limit: 100 um / 10-20 urad)
  config export FILE       write every persisted register as "name = value  # unit"
  config import FILE       check the whole file, then write every entry
  save                     save the configuration to flash (needs --engineer)
  registers                list the register table (names, addresses, units, ranges)

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
      case 3:
        die(kRefused, std::string("cannot ") + what + " " + where + val + ": illegal data value (allowed " +
                          range_text(d) + ", or the controller refused the resulting configuration; see status.config_error)");
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

int wait_state(Client& c, std::uint16_t want, double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < deadline) {
    const auto state = static_cast<std::uint16_t>(c.read(def(RegId::status_state)));
    if (state == want) return kOk;
    if (state == 8) die(kCommandRejected, "stage faulted (status.fault = " + fmt(c.read(def(RegId::status_fault))) + ")");
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  die(kTimeout, std::string("timed out waiting for state '") + state_name(want) + "'");
}

int run_command(Client& c, HostCommandCode code, std::uint16_t axis, float value, const Options& o) {
  const std::uint16_t r = c.command(code, axis, value);
  if (r != 0) {
    die(kCommandRejected, std::string("command rejected: ") +
                              (r <= 255 ? maglev::kernel::to_string(static_cast<maglev::kernel::CommandResult>(r))
                                        : "code " + std::to_string(r)));
  }
  if (o.wait_s <= 0.0) return kOk;
  switch (code) {
    case HostCommandCode::kLevitate: return wait_state(c, 6, o.wait_s);
    case HostCommandCode::kLand: return wait_state(c, 0, o.wait_s);
    case HostCommandCode::kMoveTo: {
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.wait_s);
      const double tol = is_rotation(axis) ? 1e-6 : 1e-6;
      while (std::chrono::steady_clock::now() < deadline) {
        if (std::fabs(c.read(def(kPoseReg[axis])) - static_cast<double>(value)) < tol) return kOk;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
      die(kTimeout, "timed out waiting for the move");
    }
    default: return kOk;
  }
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
  for (const Entry& e : entries) c.write(*e.d, e.v, e.text);
  std::cout << "imported " << entries.size() << " entries from " << path << "\n";
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
    for (std::size_t i = 0; i < kRegisterCount; ++i) {
      if (kRegisters[i].type == RegType::kBlock) continue;  // a download window (stagectl record), not a value
      if (kRegisters[i].kind == Kind::kLab && !lab) continue;
      std::cout << line_of(kRegisters[i], c.read(kRegisters[i])) << "\n";
    }
    return kOk;
  }
  if (cmd == "status") return do_status(c);
  if (cmd == "record" || cmd == "frf") return maglev::stagectl::run_lab_command(c.context(), o.args);
  if (cmd == "home") return run_command(c, HostCommandCode::kHome, 0, 0.0f, o);
  if (cmd == "levitate") return run_command(c, HostCommandCode::kLevitate, 0, 0.0f, o);
  if (cmd == "land") return run_command(c, HostCommandCode::kLand, 0, 0.0f, o);
  if (cmd == "stop") return run_command(c, HostCommandCode::kStop, 0, 0.0f, o);
  if (cmd == "clear-fault") return run_command(c, HostCommandCode::kClearFault, 0, 0.0f, o);
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
      for (std::size_t s = 0; s < kPersistedCount; ++s) out << line_of(persisted_def(s), c.read(persisted_def(s))) << "\n";
      if (!out) die(kFile, "cannot write " + o.args[2]);
      std::cout << "exported " << kPersistedCount << " entries to " << o.args[2] << "\n";
      return kOk;
    }
    if (o.args[1] == "import") return config_import(c, o.args[2]);
    die(kUsage, "config export FILE | config import FILE");
  }
  die(kUsage, "unknown command '" + cmd + "' (stagectl --help)");
}
