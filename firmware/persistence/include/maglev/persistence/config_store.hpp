// Configuration records in two flash banks (A, B: one sector each).
//
// Record layout (at the start of a bank):
//   word 0   header (32 bytes, programmed LAST = the commit):
//            magic 'MLCF', format version, entry count, schema hash,
//            sequence, payload bytes, payload CRC32, header CRC32, commit
//   word 1.. payload: per persisted entry {FNV-1a(name) u32, type u8, 3 pad,
//            raw value u32} (12 bytes), padded with 0xFF to whole words.
// Save always writes the OTHER bank (erase, payload words, header last), so a
// power cut at any step leaves the previous record intact and loadable.
// Load picks the valid bank with the newest sequence (serial-number order:
// 0 follows 0xFFFFFFFF); a damaged bank is flagged (persist.flags) and the
// other bank, then defaults, are used.
// A record of another schema is migrated by name (defaults for new entries)
// or refused with a reason (persist.reason) when a stored entry changed type
// or holds a value outside the current range.
#pragma once

#include <cstddef>
#include <cstdint>

#include "maglev/register_schema/register_map.hpp"
#include "maglev/persistence/flash.hpp"

namespace maglev::persistence {

inline constexpr std::uint32_t kRecordMagic = 0x46434C4D;   // "MLCF" little-endian
inline constexpr std::uint32_t kCommitMarker = 0x0C0FFEE5;
inline constexpr std::uint16_t kFormatVersion = 1;
inline constexpr std::size_t kEntryBytes = 12;
inline constexpr std::size_t kPayloadBytes =
    (modbus::kPersistedCount * kEntryBytes + kFlashWordBytes - 1) / kFlashWordBytes * kFlashWordBytes;
inline constexpr std::size_t kRecordBytes = kFlashWordBytes + kPayloadBytes;
// Largest stored record load() accepts (a record of an older/newer schema may
// hold more entries than ours).
inline constexpr std::size_t kMaxStoredEntries = 256;

// persist.reason codes.
enum class Reason : std::uint16_t {
  kNone = 0,
  kNoRecord = 1,          // both banks empty (first boot): defaults
  kBankCorrupt = 2,       // a non-empty bank failed magic/CRC/commit checks
  kUnknownFormat = 3,     // record format version unknown to this firmware
  kTypeChanged = 4,       // a stored entry of the same name has another type: refused
  kValueOutOfRange = 5,   // a stored value is outside the current range: refused
  kFlashError = 6,        // flash read/erase/program failed
  kSchemaMigrated = 7,    // record of another schema, migrated by name
};

enum class BankState : std::uint8_t { kEmpty, kValid, kCorrupt };

std::uint32_t crc32(const std::uint8_t* data, std::size_t len, std::uint32_t crc = 0);

struct LoadResult {
  modbus::ConfigImage config;
  modbus::PersistStatus status;
};

class ConfigStore {
 public:
  ConfigStore(Flash& flash, std::size_t sector_a, std::size_t sector_b);

  // Boot: read both banks, return the configuration to use and why.
  LoadResult load();
  // Write `config` to the bank not holding the active record. On success the
  // new record becomes active. A failure leaves the active record untouched.
  bool save(const modbus::ConfigImage& config);

  const modbus::PersistStatus& status() const { return status_; }
  BankState bank_state(int bank) const { return bank_state_[bank]; }
  // Flash operations (erase + programs) one save performs.
  static constexpr std::size_t kSaveSteps = 1 + kRecordBytes / kFlashWordBytes;

 private:
  struct Header {
    std::uint32_t magic;
    std::uint16_t format_version;
    std::uint16_t entry_count;
    std::uint32_t schema_hash;
    std::uint32_t sequence;
    std::uint32_t payload_bytes;
    std::uint32_t payload_crc;
    std::uint32_t header_crc;
    std::uint32_t commit;
  };
  BankState check_bank(int bank, Header& header);
  Reason decode_bank(int bank, const Header& header, modbus::ConfigImage& out, bool& migrated);
  std::size_t bank_offset(int bank) const { return sector_[bank] * flash_.sector_size(); }

  Flash& flash_;
  std::size_t sector_[2];
  BankState bank_state_[2] = {BankState::kEmpty, BankState::kEmpty};
  int active_bank_ = -1;  // bank holding the record in use, -1: none
  std::uint32_t sequence_ = 0;                // newest valid record's sequence
  std::uint32_t bank_sequence_[2] = {0, 0};  // each valid bank's sequence
  modbus::PersistStatus status_;
};

}  // namespace maglev::persistence
