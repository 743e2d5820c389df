// THE host commands, defined once: one struct per command with named fields
// in SI units, its wire code, its name and the quantity of every field. The
// CAN codec (wire layout), the firmware's mapping to kernel motion commands
// (firmware/app host_command.cpp), the bench's scenario verbs (hil/scenario),
// stagectl, the DBC generator (multiplexed signals, one set per command) and
// docs/CAN.md all read these tables; nothing else lists a command's fields.
//
// Wire: the host_command frame carries command_code, axis, command_seq and up
// to kHostCommandMaxFields IEEE-754 binary64 values; field i of a command
// occupies value slot i (catalog.hpp kHostCommandSignals). Only the codec
// knows the slots; everybody else uses the named fields.
// Heap-free, exception-free; host and Cortex-M7.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace maglev::can {

// Codes are stable wire values (and the values of the Modbus cmd.code register).
enum class HostCommandCode : std::uint8_t {
  kHome = 1,
  kLevitate = 2,
  kLand = 3,
  kStop = 4,
  kClearFault = 5,
  kHold = 6,
  kStep = 7,
  kMoveTo = 8,
  kMoveBy = 9,
  kMoveJerkTo = 10,
  kMoveJerkBy = 11,
  kCircle = 12,
  kSinusoid = 13,
  kExcite = 14,
  kStopExcitation = 15,
  kShutdown = 16,
  kCalibrateCoupling = 17,
};
inline constexpr std::uint8_t kHostCommandCodeMax = 17;
inline constexpr std::size_t kHostCommandMaxFields = 5;

// What a field measures, so every parser applies the same unit rule. The
// axis-relative ones are metres on a translational axis and radians on a
// rotational one (per second, per second squared, ...).
enum class ArgQuantity : std::uint8_t {
  kAxisPosition = 0,      // m | rad
  kAxisVelocity = 1,      // m/s | rad/s
  kAxisAcceleration = 2,  // m/s^2 | rad/s^2
  kAxisJerk = 3,          // m/s^3 | rad/s^3
  kLength = 4,            // m
  kTime = 5,              // s
  kFrequency = 6,         // Hz
  kCount = 7,             // dimensionless (turns, harmonics)
  kAxisEffort = 8,        // A of axis effort (the kernel's force/torque units)
};

// Sign rule of a field, checked by the scenario parser and stagectl before a
// command leaves; the kernel checks again (it trusts no host).
enum class ArgRange : std::uint8_t { kAny = 0, kPositive = 1, kNonNegative = 2 };

template <class Args>
struct ArgField {
  const char* name;  // also the DBC signal name suffix: <command>_<name>
  double Args::*member;
  ArgQuantity quantity;
  ArgRange range;
  const char* comment;
};

// ---- one struct per command ------------------------------------------------
struct NoArgs {
  static constexpr std::array<ArgField<NoArgs>, 0> kFields{};
};

struct StepArgs {
  double delta;  // m | rad, added to the present reference at once
  static constexpr HostCommandCode kCode = HostCommandCode::kStep;
  static constexpr std::array<ArgField<StepArgs>, 1> kFields{{
      {"delta", &StepArgs::delta, ArgQuantity::kAxisPosition, ArgRange::kAny, "step size from the present reference"},
  }};
};

struct MoveToArgs {
  double target;        // m | rad, absolute (magnet frame)
  double velocity;      // m/s | rad/s, trapezoid cruise
  double acceleration;  // m/s^2 | rad/s^2
  static constexpr HostCommandCode kCode = HostCommandCode::kMoveTo;
  static constexpr std::array<ArgField<MoveToArgs>, 3> kFields{{
      {"target", &MoveToArgs::target, ArgQuantity::kAxisPosition, ArgRange::kAny, "absolute target"},
      {"velocity", &MoveToArgs::velocity, ArgQuantity::kAxisVelocity, ArgRange::kPositive, "cruise velocity"},
      {"acceleration", &MoveToArgs::acceleration, ArgQuantity::kAxisAcceleration, ArgRange::kPositive,
       "acceleration and deceleration"},
  }};
};

struct MoveByArgs {
  double distance;      // m | rad, from the present reference
  double velocity;
  double acceleration;
  static constexpr HostCommandCode kCode = HostCommandCode::kMoveBy;
  static constexpr std::array<ArgField<MoveByArgs>, 3> kFields{{
      {"distance", &MoveByArgs::distance, ArgQuantity::kAxisPosition, ArgRange::kAny,
       "distance from the present reference"},
      {"velocity", &MoveByArgs::velocity, ArgQuantity::kAxisVelocity, ArgRange::kPositive, "cruise velocity"},
      {"acceleration", &MoveByArgs::acceleration, ArgQuantity::kAxisAcceleration, ArgRange::kPositive,
       "acceleration and deceleration"},
  }};
};

struct MoveJerkToArgs {
  double target;
  double velocity;
  double acceleration;
  double jerk;  // m/s^3 | rad/s^3, S-curve
  static constexpr HostCommandCode kCode = HostCommandCode::kMoveJerkTo;
  static constexpr std::array<ArgField<MoveJerkToArgs>, 4> kFields{{
      {"target", &MoveJerkToArgs::target, ArgQuantity::kAxisPosition, ArgRange::kAny, "absolute target"},
      {"velocity", &MoveJerkToArgs::velocity, ArgQuantity::kAxisVelocity, ArgRange::kPositive, "cruise velocity"},
      {"acceleration", &MoveJerkToArgs::acceleration, ArgQuantity::kAxisAcceleration, ArgRange::kPositive,
       "peak acceleration"},
      {"jerk", &MoveJerkToArgs::jerk, ArgQuantity::kAxisJerk, ArgRange::kPositive, "jerk limit (S-curve)"},
  }};
};

struct MoveJerkByArgs {
  double distance;
  double velocity;
  double acceleration;
  double jerk;
  static constexpr HostCommandCode kCode = HostCommandCode::kMoveJerkBy;
  static constexpr std::array<ArgField<MoveJerkByArgs>, 4> kFields{{
      {"distance", &MoveJerkByArgs::distance, ArgQuantity::kAxisPosition, ArgRange::kAny,
       "distance from the present reference"},
      {"velocity", &MoveJerkByArgs::velocity, ArgQuantity::kAxisVelocity, ArgRange::kPositive, "cruise velocity"},
      {"acceleration", &MoveJerkByArgs::acceleration, ArgQuantity::kAxisAcceleration, ArgRange::kPositive,
       "peak acceleration"},
      {"jerk", &MoveJerkByArgs::jerk, ArgQuantity::kAxisJerk, ArgRange::kPositive, "jerk limit (S-curve)"},
  }};
};

// In the x-y plane, starting at the present point (centre at -x by the radius).
struct CircleArgs {
  double diameter_m;
  double period_s;  // one turn
  double turns;
  static constexpr HostCommandCode kCode = HostCommandCode::kCircle;
  static constexpr std::array<ArgField<CircleArgs>, 3> kFields{{
      {"diameter_m", &CircleArgs::diameter_m, ArgQuantity::kLength, ArgRange::kPositive, "circle diameter"},
      {"period_s", &CircleArgs::period_s, ArgQuantity::kTime, ArgRange::kPositive, "time of one turn"},
      {"turns", &CircleArgs::turns, ArgQuantity::kCount, ArgRange::kPositive, "number of turns"},
  }};
};

// p0 + A sin(2 pi f t) for duration_s (0: until hold), then holds.
struct SinusoidArgs {
  double amplitude;  // m | rad
  double frequency_Hz;
  double duration_s;
  static constexpr HostCommandCode kCode = HostCommandCode::kSinusoid;
  static constexpr std::array<ArgField<SinusoidArgs>, 3> kFields{{
      {"amplitude", &SinusoidArgs::amplitude, ArgQuantity::kAxisPosition, ArgRange::kAny, "amplitude"},
      {"frequency_Hz", &SinusoidArgs::frequency_Hz, ArgQuantity::kFrequency, ArgRange::kPositive, "frequency"},
      {"duration_s", &SinusoidArgs::duration_s, ArgQuantity::kTime, ArgRange::kNonNegative,
       "how long it runs; 0 = until hold"},
  }};
};

// The kernel's own excitation (effort injection, internal multisine).
struct ExciteArgs {
  double amplitude;  // A of axis effort
  double frequency_Hz;
  double duration_s;
  double harmonics;  // 1..255 tones
  static constexpr HostCommandCode kCode = HostCommandCode::kExcite;
  static constexpr std::array<ArgField<ExciteArgs>, 4> kFields{{
      {"amplitude", &ExciteArgs::amplitude, ArgQuantity::kAxisEffort, ArgRange::kPositive, "effort amplitude"},
      {"frequency_Hz", &ExciteArgs::frequency_Hz, ArgQuantity::kFrequency, ArgRange::kPositive,
       "fundamental frequency"},
      {"duration_s", &ExciteArgs::duration_s, ArgQuantity::kTime, ArgRange::kPositive, "duration"},
      {"harmonics", &ExciteArgs::harmonics, ArgQuantity::kCount, ArgRange::kPositive, "tones (1..255)"},
  }};
};

// The arguments of one command; the member that `code` names is the live one.
union HostCommandArgs {
  StepArgs step;
  MoveToArgs move_to;
  MoveByArgs move_by;
  MoveJerkToArgs move_jerk_to;
  MoveJerkByArgs move_jerk_by;
  CircleArgs circle;
  SinusoidArgs sinusoid;
  ExciteArgs excite;
};

// Calls f(args-of-code) with the typed member of `a` that `code` selects
// (NoArgs for a command without fields). The one switch over the codes.
template <class A, class F>
constexpr void with_args(HostCommandCode code, A& a, F&& f) {
  switch (code) {
    case HostCommandCode::kStep: f(a.step); return;
    case HostCommandCode::kMoveTo: f(a.move_to); return;
    case HostCommandCode::kMoveBy: f(a.move_by); return;
    case HostCommandCode::kMoveJerkTo: f(a.move_jerk_to); return;
    case HostCommandCode::kMoveJerkBy: f(a.move_jerk_by); return;
    case HostCommandCode::kCircle: f(a.circle); return;
    case HostCommandCode::kSinusoid: f(a.sinusoid); return;
    case HostCommandCode::kExcite: f(a.excite); return;
    default: {
      NoArgs none{};
      f(none);
      return;
    }
  }
}

// ---- the table, type-erased (generators, parsers, docs) ---------------------
struct ArgFieldInfo {
  const char* name;
  ArgQuantity quantity;
  ArgRange range;
  const char* comment;
};

struct HostCommandSpec {
  HostCommandCode code;
  const char* name;  // wire name, DBC value name, scenario verb, stagectl verb
  bool takes_axis;   // the axis byte is meaningful
  std::uint8_t field_count;
  std::array<ArgFieldInfo, kHostCommandMaxFields> fields;
  const char* comment;
};

namespace host_command_detail {
template <class Args>
constexpr HostCommandSpec spec(HostCommandCode code, const char* name, bool takes_axis, const char* comment) {
  static_assert(Args::kFields.size() <= kHostCommandMaxFields);
  HostCommandSpec s{code, name, takes_axis, static_cast<std::uint8_t>(Args::kFields.size()), {}, comment};
  for (std::size_t i = 0; i < Args::kFields.size(); ++i) {
    s.fields[i] = ArgFieldInfo{Args::kFields[i].name, Args::kFields[i].quantity, Args::kFields[i].range,
                               Args::kFields[i].comment};
  }
  return s;
}
}  // namespace host_command_detail

// Indexed by code - 1.
inline constexpr std::array<HostCommandSpec, kHostCommandCodeMax> kHostCommandSpecs{{
    host_command_detail::spec<NoArgs>(HostCommandCode::kHome, "home", false, "find the absolute position (Hall) while landed"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kLevitate, "levitate", false, "start-up sequence to Ready"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kLand, "land", false, "controlled landing"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kStop, "stop", false, "stop every motion, hold the reference"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kClearFault, "clear_fault", false, "clear a latched fault once its cause is gone"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kHold, "hold", false, "end the running profiles, hold where they are"),
    host_command_detail::spec<StepArgs>(HostCommandCode::kStep, "step", true, "reference step on one axis"),
    host_command_detail::spec<MoveToArgs>(HostCommandCode::kMoveTo, "move_to", true, "trapezoidal move to an absolute target"),
    host_command_detail::spec<MoveByArgs>(HostCommandCode::kMoveBy, "move", true, "trapezoidal move by a distance"),
    host_command_detail::spec<MoveJerkToArgs>(HostCommandCode::kMoveJerkTo, "move_jerk_to", true, "S-curve move to an absolute target"),
    host_command_detail::spec<MoveJerkByArgs>(HostCommandCode::kMoveJerkBy, "move_jerk", true, "S-curve move by a distance"),
    host_command_detail::spec<CircleArgs>(HostCommandCode::kCircle, "circle", false, "circle in the x-y plane from the present point"),
    host_command_detail::spec<SinusoidArgs>(HostCommandCode::kSinusoid, "sinusoid", true, "sinusoidal reference on one axis"),
    host_command_detail::spec<ExciteArgs>(HostCommandCode::kExcite, "excite_effort", true, "kernel effort excitation (multisine)"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kStopExcitation, "stop_excitation", true, "end the effort excitation"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kShutdown, "shutdown", false, "bench controller node: acknowledge and stop"),
    host_command_detail::spec<NoArgs>(HostCommandCode::kCalibrateCoupling, "calibrate_coupling", false, "identify and correct the 6x6 effort coupling (Ready, ~30 s)"),
}};

constexpr bool host_command_specs_consistent() {
  for (std::size_t i = 0; i < kHostCommandSpecs.size(); ++i) {
    if (static_cast<std::size_t>(kHostCommandSpecs[i].code) != i + 1) return false;
  }
  return true;
}
static_assert(host_command_specs_consistent(), "kHostCommandSpecs must be indexed by code - 1");

// nullptr for a code outside 1..kHostCommandCodeMax.
constexpr const HostCommandSpec* host_command_spec(HostCommandCode c) {
  const auto i = static_cast<std::size_t>(c);
  return i >= 1 && i <= kHostCommandSpecs.size() ? &kHostCommandSpecs[i - 1] : nullptr;
}
// "?" for an unknown code.
constexpr const char* to_string(HostCommandCode c) {
  const HostCommandSpec* s = host_command_spec(c);
  return s != nullptr ? s->name : "?";
}

// One host command as it travels: code, axis (kernel::Axis index), the
// sender's sequence number (echoed by the ack) and the typed arguments.
struct HostCommandFrame {
  HostCommandCode code;
  std::uint8_t axis;
  std::uint16_t seq;
  HostCommandArgs args;
};

// Typed construction: make_host_command(seq, axis, SinusoidArgs{...}); the
// code follows from the arguments' type.
template <class Args>
constexpr HostCommandFrame make_host_command(std::uint16_t seq, std::uint8_t axis, const Args& a) {
  HostCommandFrame h{Args::kCode, axis, seq, {}};
  with_args(Args::kCode, h.args, [&](auto& dst) {
    if constexpr (std::is_same_v<std::remove_reference_t<decltype(dst)>, Args>) dst = a;
  });
  return h;
}
// A command without arguments (home, levitate, ..., shutdown).
constexpr HostCommandFrame make_host_command(HostCommandCode code, std::uint16_t seq, std::uint8_t axis = 0) {
  return HostCommandFrame{code, axis, seq, {}};
}

}  // namespace maglev::can
