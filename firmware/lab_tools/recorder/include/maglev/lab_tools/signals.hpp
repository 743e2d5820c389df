// The kernel signals the lab tools can record or trigger on, defined once:
// pinned numeric ids (they are what rec.channel.N / rec.trigger_signal carry
// over Modbus), names ("x.pose", "coil3.current"), units. stagectl,
// docs/LAB-TOOLS.md and the recorder all read this table.
//
// Id layout: 0 = none; then groups of 6 (one per axis, kernel Axis order
// x, y, theta_z, z, theta_x, theta_y) or 8 (one per coil, coil1..coil8),
// then single signals. Never renumber: append.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::lab {

enum class SignalGroup : std::uint8_t {
  kNone = 0,
  kPose,              // per axis: measured pose (m or rad)
  kReference,         // per axis: reference (m or rad)
  kError,             // per axis: reference - pose (m or rad)
  kEffort,            // per axis: U into the allocation, loop + excitation (A)
  kLoopEffort,        // per axis: the loop's own effort (A)
  kExcitation,        // per axis: effort injection d (kExcite + wave generator, A)
  kRefInjection,      // per axis: reference injection of the wave generator (m or rad)
  kCoilCurrentCmd,    // per coil: commanded current (A)
  kCoilCurrent,       // per coil: measured current, from the current monitor ADC (A)
  kState,             // sequencer state (SequencerState value)
  kFault,             // latched fault code (FaultCode value)
  kScaleK,            // force allocation current scale k
};

struct SignalGroupDef {
  SignalGroup group;
  const char* name;     // "pose": signal "x.pose" / "coil1.current"
  std::uint16_t first;  // id of index 0
  std::uint8_t count;   // 6 per-axis, 8 per-coil, 1 single
  bool rotational_unit; // per-axis groups whose unit is m (translation) / rad (rotation)
  const char* unit;     // unit of a translational axis / the signal
  const char* description;
};

inline constexpr std::uint8_t kAxisSignals = 6;
inline constexpr std::uint8_t kCoilSignals = 8;

inline constexpr SignalGroupDef kSignalGroups[] = {
    {SignalGroup::kPose, "pose", 1, kAxisSignals, true, "m", "measured pose"},
    {SignalGroup::kReference, "reference", 7, kAxisSignals, true, "m", "reference (stored; without the reference injection)"},
    {SignalGroup::kError, "error", 13, kAxisSignals, true, "m", "reference - pose"},
    {SignalGroup::kEffort, "effort", 19, kAxisSignals, false, "A", "effort U into the force allocation (loop + excitation)"},
    {SignalGroup::kLoopEffort, "loop_effort", 25, kAxisSignals, false, "A", "the axis loop's own effort (after its clamp)"},
    {SignalGroup::kExcitation, "excitation", 31, kAxisSignals, false, "A", "effort injection d (kExcite + wave generator)"},
    {SignalGroup::kRefInjection, "ref_injection", 37, kAxisSignals, true, "m", "reference injection of the wave generator"},
    {SignalGroup::kCoilCurrentCmd, "current_cmd", 43, kCoilSignals, false, "A", "commanded coil current"},
    {SignalGroup::kCoilCurrent, "current", 51, kCoilSignals, false, "A", "measured coil current (current monitor)"},
    {SignalGroup::kState, "state", 59, 1, false, "", "sequencer state (0 idle .. 6 ready, 7 landing, 8 fault)"},
    {SignalGroup::kFault, "fault", 60, 1, false, "", "latched fault code, 0 = none"},
    {SignalGroup::kScaleK, "scale_k", 61, 1, false, "1", "force allocation current scale k"},
};
inline constexpr std::size_t kSignalGroupCount = sizeof(kSignalGroups) / sizeof(kSignalGroups[0]);
// One past the largest id (the register table's range for signal ids).
inline constexpr std::uint16_t kSignalIdEnd = 62;

struct SignalRef {
  SignalGroup group = SignalGroup::kNone;
  std::uint8_t index = 0;  // axis or coil index
};

// id -> group + index; group kNone when the id names no signal.
constexpr SignalRef signal_ref(std::uint16_t id) {
  for (const SignalGroupDef& g : kSignalGroups) {
    if (id >= g.first && id < g.first + g.count) return {g.group, static_cast<std::uint8_t>(id - g.first)};
  }
  return {};
}
constexpr bool signal_known(std::uint16_t id) { return signal_ref(id).group != SignalGroup::kNone; }
constexpr const SignalGroupDef* signal_group(std::uint16_t id) {
  for (const SignalGroupDef& g : kSignalGroups) {
    if (id >= g.first && id < g.first + g.count) return &g;
  }
  return nullptr;
}

// "x.pose", "coil3.current", "state" into out (>= 32 bytes); false: unknown id.
bool signal_name(std::uint16_t id, char* out, std::size_t size);
// The unit of signal `id` ("m", "rad", "A", "" for codes); "" when unknown.
const char* signal_unit(std::uint16_t id);
// Name -> id; 0 when unknown.
std::uint16_t find_signal(const char* name);

}  // namespace maglev::lab
