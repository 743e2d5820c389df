// The register map as constexpr data, expanded from registers.def. Portable,
// heap-free: the firmware server, the TCP bench adapter, persistence,
// stagectl and the docs generator all read this one table.
#pragma once

#include <cstddef>
#include <cstdint>

namespace maglev::modbus {

// kBlock: a read-only window of kBlockWords registers whose content the lab
// tools supply (rec.data: recorder values, float32 ABCD pairs).
enum class RegType : std::uint8_t { kU16, kI32, kF32, kBlock };
inline constexpr std::uint16_t kBlockWords = 124;
enum class Access : std::uint8_t { kReadOnly, kOperator, kEngineer };
// When a write is accepted (else exception 06, server device busy).
enum class WriteWhen : std::uint8_t {
  kNever,      // read-only register
  kAlways,
  kNotMoving,  // no reference running
  kIdle,       // landed / not levitating
  kGains,      // kIdle, or always while tuning.live = 1 (live tuning)
};
// kStage: persisted like kConfig, but not a KernelConfig field (the stage
// profile selection, applied by the controller binding).
// kLab: the lab tools (recorder, wave generator: firmware/lab_tools), served
// by the RegisterServer's LabTools (volatile; refused with 02 when none).
enum class Kind : std::uint8_t { kIdent, kStatus, kConfig, kControl, kStage, kLab };

// Stable identifiers, in table order.
enum class RegId : std::uint16_t {
#define MAGLEV_REG(id, ...) id,
#include "maglev/register_schema/registers.def"
#undef MAGLEV_REG
  kCount
};

struct RegisterDef {
  RegId id;
  const char* name;
  std::uint16_t address;
  RegType type;
  const char* unit;
  double min;
  double max;
  double default_value;
  Access access;
  WriteWhen when;
  bool persisted;
  Kind kind;
  const char* description;
};

namespace detail {
inline constexpr RegType U16 = RegType::kU16;
inline constexpr RegType I32 = RegType::kI32;
inline constexpr RegType F32 = RegType::kF32;
inline constexpr RegType BLOCK = RegType::kBlock;
inline constexpr Access RO = Access::kReadOnly;
inline constexpr Access OP = Access::kOperator;
inline constexpr Access ENG = Access::kEngineer;
inline constexpr WriteWhen NEVER = WriteWhen::kNever;
inline constexpr WriteWhen ALWAYS = WriteWhen::kAlways;
inline constexpr WriteWhen NOT_MOVING = WriteWhen::kNotMoving;
inline constexpr WriteWhen IDLE = WriteWhen::kIdle;
inline constexpr WriteWhen GAINS = WriteWhen::kGains;
inline constexpr bool P = true;
inline constexpr bool V = false;
inline constexpr Kind IDENT = Kind::kIdent;
inline constexpr Kind STATUS = Kind::kStatus;
inline constexpr Kind CONFIG = Kind::kConfig;
inline constexpr Kind CONTROL = Kind::kControl;
inline constexpr Kind STAGE = Kind::kStage;
inline constexpr Kind LAB = Kind::kLab;

inline constexpr RegisterDef kTable[] = {
#define MAGLEV_REG(id, name, address, type, unit, min, max, def, access, when, persist, kind, field, desc) \
  {RegId::id, name, static_cast<std::uint16_t>(address), type, unit, static_cast<double>(min),            \
   static_cast<double>(max), static_cast<double>(def), access, when, persist, kind, desc},
#include "maglev/register_schema/registers.def"
#undef MAGLEV_REG
};
}  // namespace detail

inline constexpr std::size_t kRegisterCount = static_cast<std::size_t>(RegId::kCount);
inline constexpr const RegisterDef* kRegisters = detail::kTable;

constexpr std::uint16_t width(RegType t) {
  return t == RegType::kU16 ? 1 : (t == RegType::kBlock ? kBlockWords : 2);
}

// The attributes' names as tools print them (stagectl --json, the Python
// table generator, docs/REGISTERS.md): one spelling everywhere.
constexpr const char* type_name(RegType t) {
  switch (t) {
    case RegType::kU16: return "u16";
    case RegType::kI32: return "i32";
    case RegType::kF32: return "f32";
    case RegType::kBlock: return "block";
  }
  return "?";
}
constexpr const char* access_name(Access a) {
  switch (a) {
    case Access::kReadOnly: return "read-only";
    case Access::kOperator: return "operator";
    case Access::kEngineer: return "engineer";
  }
  return "?";
}
constexpr const char* when_name(WriteWhen w) {
  switch (w) {
    case WriteWhen::kNever: return "never";
    case WriteWhen::kAlways: return "always";
    case WriteWhen::kNotMoving: return "not-moving";
    case WriteWhen::kIdle: return "idle";
    case WriteWhen::kGains: return "gains";
  }
  return "?";
}
constexpr const char* kind_name(Kind k) {
  switch (k) {
    case Kind::kIdent: return "ident";
    case Kind::kStatus: return "status";
    case Kind::kConfig: return "config";
    case Kind::kControl: return "control";
    case Kind::kStage: return "stage";
    case Kind::kLab: return "lab";
  }
  return "?";
}
constexpr const RegisterDef& def(RegId id) { return detail::kTable[static_cast<std::size_t>(id)]; }

// The engineer key (access.key). A guard against accidental writes by an
// operator tool, not a security boundary: it is documented in REGISTERS.md.
inline constexpr std::uint16_t kEngineerKey = 0x4E47;

// Command codes (cmd.code): can::HostCommandCode values, the one command
// table (firmware/can_link host_commands.hpp). Over Modbus a command carries
// one value (cmd.value): the commands whose fields are at most the axis and
// one position (home, levitate, land, stop, clear_fault, hold, step,
// move_to at the axis' profile limits) run; the others are refused
// (kernel CommandResult kUnsupported) -- send them over CAN.

// persist.flags bits.
enum PersistFlag : std::uint16_t {
  kLoadedBankA = 1u << 0,
  kLoadedBankB = 1u << 1,
  kLoadedDefaults = 1u << 2,
  kBankACorrupt = 1u << 3,
  kBankBCorrupt = 1u << 4,
  kMigrated = 1u << 5,      // stored record had another schema; matched by name
  kRefused = 1u << 6,       // a stored record was refused (see persist.reason)
  kSaveFailed = 1u << 7,    // last save did not verify
  kUnsaved = 1u << 8,       // configuration differs from the loaded/saved record
};

// Register lookup by address: the def whose span contains `address`.
constexpr const RegisterDef* find_by_address(std::uint16_t address) {
  // Table is sorted by address (checked by static_assert below): binary search.
  std::size_t lo = 0;
  std::size_t hi = kRegisterCount;
  while (lo < hi) {
    const std::size_t mid = lo + (hi - lo) / 2;
    const RegisterDef& d = detail::kTable[mid];
    if (address < d.address) {
      hi = mid;
    } else if (address >= d.address + width(d.type)) {
      lo = mid + 1;
    } else {
      return &d;
    }
  }
  return nullptr;
}

constexpr bool str_equal(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {
    ++a;
    ++b;
  }
  return *a == *b;
}

constexpr const RegisterDef* find_by_name(const char* name) {
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    if (str_equal(detail::kTable[i].name, name)) return &detail::kTable[i];
  }
  return nullptr;
}

constexpr bool table_is_sorted_and_disjoint() {
  for (std::size_t i = 1; i < kRegisterCount; ++i) {
    const RegisterDef& a = detail::kTable[i - 1];
    if (a.address + width(a.type) > detail::kTable[i].address) return false;
  }
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    if (static_cast<std::size_t>(detail::kTable[i].id) != i) return false;
  }
  return true;
}
static_assert(table_is_sorted_and_disjoint(), "registers.def must be sorted by address, without overlaps");

// --- persisted entries: slots of the configuration image ----------------------
constexpr std::size_t count_persisted() {
  std::size_t n = 0;
  for (std::size_t i = 0; i < kRegisterCount; ++i) n += detail::kTable[i].persisted ? 1u : 0u;
  return n;
}
inline constexpr std::size_t kPersistedCount = count_persisted();

// Slot of a persisted register in ConfigImage, or -1.
constexpr int persisted_slot(RegId id) {
  int slot = 0;
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    if (detail::kTable[i].id == id) return detail::kTable[i].persisted ? slot : -1;
    if (detail::kTable[i].persisted) ++slot;
  }
  return -1;
}

namespace detail {
// Table index of each persisted slot, computed once at compile time:
// persisted_def() runs per slot inside every load, save and defaults(), and
// a table scan per call made those quadratic.
struct PersistedIndex {
  std::uint16_t table_index[kPersistedCount];
};
constexpr PersistedIndex make_persisted_index() {
  PersistedIndex x{};
  std::size_t s = 0;
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    if (kTable[i].persisted) x.table_index[s++] = static_cast<std::uint16_t>(i);
  }
  return x;
}
inline constexpr PersistedIndex kPersistedIndex = make_persisted_index();
}  // namespace detail

// The def of a persisted slot (the table's first def for a slot out of range).
constexpr const RegisterDef& persisted_def(std::size_t slot) {
  return slot < kPersistedCount ? detail::kTable[detail::kPersistedIndex.table_index[slot]] : detail::kTable[0];
}

// FNV-1a, 32 bit: stable, constexpr, tiny.
constexpr std::uint32_t fnv1a(const char* s, std::uint32_t h = 2166136261u) {
  while (*s != '\0') {
    h ^= static_cast<std::uint8_t>(*s++);
    h *= 16777619u;
  }
  return h;
}
constexpr std::uint32_t fnv1a_byte(std::uint8_t b, std::uint32_t h) {
  h ^= b;
  return h * 16777619u;
}

// Schema hash: names, types and order of the persisted entries.
constexpr std::uint32_t schema_hash() {
  std::uint32_t h = 2166136261u;
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    const RegisterDef& d = detail::kTable[i];
    if (!d.persisted) continue;
    h = fnv1a(d.name, h);
    h = fnv1a_byte(static_cast<std::uint8_t>(d.type), h);
    h = fnv1a_byte(0, h);  // separator: "ab"+"c" != "a"+"bc"
  }
  return h;
}
inline constexpr std::uint32_t kSchemaHash = schema_hash();

// ABCD word order: the high 16 bits at the lower address. (Do not use
// libmodbus 3.1.6's modbus_set_float_abcd()/modbus_get_float_abcd(): on
// little-endian hosts they produce BADC; use these.)
constexpr void split_words(std::uint32_t raw, std::uint16_t* words) {
  words[0] = static_cast<std::uint16_t>(raw >> 16);
  words[1] = static_cast<std::uint16_t>(raw & 0xFFFFu);
}
constexpr std::uint32_t join_words(const std::uint16_t* words) {
  return (static_cast<std::uint32_t>(words[0]) << 16) | words[1];
}

// Raw 32-bit encodings (the bits that two registers carry, ABCD order).
std::uint32_t encode(RegType type, double value);
double decode(RegType type, std::uint32_t raw);
// True when `value` is a legal value of `d` (finite, inside [min, max], an
// integer for U16/I32).
bool value_in_range(const RegisterDef& d, double value);

// The configuration as the register map sees it: one raw 32-bit word per
// persisted entry (U16 in the low half, I32 two's complement, F32 IEEE bits).
// What the persistence layer reports about the stored configuration
// (persist.* registers).
struct PersistStatus {
  std::uint16_t flags = 0;   // PersistFlag bits
  std::uint16_t reason = 0;  // persistence::Reason
  std::uint32_t sequence = 0;
};

struct ConfigImage {
  std::uint32_t raw[kPersistedCount];

  double get(RegId id) const;
  void set(RegId id, double value);
  static ConfigImage defaults();
};
bool operator==(const ConfigImage& a, const ConfigImage& b);

}  // namespace maglev::modbus
