#include "maglev/persistence/config_store.hpp"

namespace maglev::persistence {
namespace {

using modbus::ConfigImage;
using modbus::RegisterDef;

void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void put16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
std::uint32_t get32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
std::uint16_t get16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }

constexpr std::size_t kHeaderCrcBytes = 24;  // magic .. payload_crc

// Record sequence numbers compare in serial-number arithmetic (RFC 1982):
// a is newer than b when (a - b) mod 2^32 lies in 1 .. 2^31 - 1. Saves count
// up by one and wrap 0xFFFFFFFF -> 0; with a plain '>' the record written
// after the wrap lost to the one before it, so a save that reported success
// was silently undone at the next boot (a flash image whose record carries
// sequence 0xFFFFFFFF; fuzz_config_bank's save -> next boot check catches it,
// regression input tests/fuzz/corpus/config_bank/regression_sequence_wrap).
bool newer(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) > 0; }

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t len, std::uint32_t crc) {
  crc = ~crc;
  for (std::size_t i = 0; i < len; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) crc = (crc & 1u) != 0 ? (crc >> 1) ^ 0xEDB88320u : crc >> 1;
  }
  return ~crc;
}

ConfigStore::ConfigStore(Flash& flash, std::size_t sector_a, std::size_t sector_b)
    : flash_(flash), sector_{sector_a, sector_b} {}

BankState ConfigStore::check_bank(int bank, Header& h) {
  std::uint8_t w[kFlashWordBytes];
  if (flash_.read(bank_offset(bank), w, kFlashWordBytes) != FlashError::kOk) return BankState::kCorrupt;
  bool erased = true;
  for (std::uint8_t b : w) erased = erased && b == 0xFF;
  if (erased) {
    // An erased header with a non-erased payload is a save cut before its
    // commit: harmless (the other bank holds the config) but worth a flag.
    std::uint8_t p[kFlashWordBytes];
    if (flash_.read(bank_offset(bank) + kFlashWordBytes, p, kFlashWordBytes) != FlashError::kOk) {
      return BankState::kCorrupt;
    }
    for (std::uint8_t b : p) {
      if (b != 0xFF) return BankState::kCorrupt;
    }
    return BankState::kEmpty;
  }
  h.magic = get32(w + 0);
  h.format_version = get16(w + 4);
  h.entry_count = get16(w + 6);
  h.schema_hash = get32(w + 8);
  h.sequence = get32(w + 12);
  h.payload_bytes = get32(w + 16);
  h.payload_crc = get32(w + 20);
  h.header_crc = get32(w + 24);
  h.commit = get32(w + 28);
  if (h.magic != kRecordMagic || h.commit != kCommitMarker || crc32(w, kHeaderCrcBytes) != h.header_crc) {
    return BankState::kCorrupt;
  }
  if (h.payload_bytes > flash_.sector_size() - kFlashWordBytes || h.entry_count > kMaxStoredEntries ||
      static_cast<std::size_t>(h.entry_count) * kEntryBytes > h.payload_bytes) {
    return BankState::kCorrupt;
  }
  // Payload CRC, read in flash-word chunks (no big buffer).
  std::uint32_t crc = 0;
  for (std::size_t off = 0; off < h.payload_bytes; off += kFlashWordBytes) {
    const std::size_t n = h.payload_bytes - off < kFlashWordBytes ? h.payload_bytes - off : kFlashWordBytes;
    if (flash_.read(bank_offset(bank) + kFlashWordBytes + off, w, n) != FlashError::kOk) return BankState::kCorrupt;
    crc = crc32(w, n, crc);
  }
  return crc == h.payload_crc ? BankState::kValid : BankState::kCorrupt;
}

Reason ConfigStore::decode_bank(int bank, const Header& h, ConfigImage& out, bool& migrated) {
  if (h.format_version != kFormatVersion) return Reason::kUnknownFormat;
  migrated = h.schema_hash != modbus::kSchemaHash || h.entry_count != modbus::kPersistedCount;
  out = ConfigImage::defaults();
  // Stored entries are matched to the schema's by name hash in one pass over
  // the flash (each entry read once), then decoded in schema order. Looking
  // every register up by scanning the stored entries read the flash
  // kPersistedCount x entry_count times: ~40 000 reads per load with the
  // filter registers, 2.8 ms per fuzzer execution. 1.2 KiB of stack, at boot.
  std::uint32_t name_hash[modbus::kPersistedCount];
  std::int16_t entry_of[modbus::kPersistedCount];
  for (std::size_t s = 0; s < modbus::kPersistedCount; ++s) {
    name_hash[s] = modbus::fnv1a(modbus::persisted_def(s).name);
    entry_of[s] = -1;
  }
  std::uint8_t entry[kEntryBytes];
  for (std::size_t e = 0; e < h.entry_count; ++e) {
    if (flash_.read(bank_offset(bank) + kFlashWordBytes + e * kEntryBytes, entry, kEntryBytes) != FlashError::kOk) {
      return Reason::kFlashError;
    }
    const std::uint32_t hash = get32(entry);
    for (std::size_t s = 0; s < modbus::kPersistedCount; ++s) {
      if (name_hash[s] == hash) {
        if (entry_of[s] < 0) entry_of[s] = static_cast<std::int16_t>(e);  // the first stored entry wins
        break;
      }
    }
  }
  std::size_t matched = 0;
  for (std::size_t s = 0; s < modbus::kPersistedCount; ++s) {
    const RegisterDef& d = modbus::persisted_def(s);
    if (entry_of[s] < 0) {
      migrated = true;  // new entry: its default stays
      continue;
    }
    const auto e = static_cast<std::size_t>(entry_of[s]);
    if (flash_.read(bank_offset(bank) + kFlashWordBytes + e * kEntryBytes, entry, kEntryBytes) != FlashError::kOk) {
      return Reason::kFlashError;
    }
    if (entry[4] != static_cast<std::uint8_t>(d.type)) return Reason::kTypeChanged;
    const std::uint32_t raw = get32(entry + 8);
    if (!modbus::value_in_range(d, modbus::decode(d.type, raw))) return Reason::kValueOutOfRange;
    out.raw[s] = raw;
    ++matched;
  }
  if (matched != h.entry_count) migrated = true;  // stored entries we no longer have
  return Reason::kNone;
}

LoadResult ConfigStore::load() {
  Header h[2]{};
  status_ = modbus::PersistStatus{};
  for (int b = 0; b < 2; ++b) {
    bank_state_[b] = check_bank(b, h[b]);
  }
  if (bank_state_[0] == BankState::kCorrupt) status_.flags |= modbus::kBankACorrupt;
  if (bank_state_[1] == BankState::kCorrupt) status_.flags |= modbus::kBankBCorrupt;
  if (bank_state_[0] == BankState::kCorrupt || bank_state_[1] == BankState::kCorrupt) {
    status_.reason = static_cast<std::uint16_t>(Reason::kBankCorrupt);
  }

  // Candidates, newest sequence first.
  int order[2] = {0, 1};
  if (bank_state_[1] == BankState::kValid &&
      (bank_state_[0] != BankState::kValid || newer(h[1].sequence, h[0].sequence))) {
    order[0] = 1;
    order[1] = 0;
  }
  LoadResult result{ConfigImage::defaults(), {}};
  for (int b = 0; b < 2; ++b) bank_sequence_[b] = bank_state_[b] == BankState::kValid ? h[b].sequence : 0;
  sequence_ = bank_sequence_[order[0]];
  active_bank_ = -1;
  for (int bank : order) {
    if (bank_state_[bank] != BankState::kValid) continue;
    bool migrated = false;
    ConfigImage image{};
    const Reason r = decode_bank(bank, h[bank], image, migrated);
    if (r != Reason::kNone) {
      status_.flags |= modbus::kRefused;
      status_.reason = static_cast<std::uint16_t>(r);
      continue;
    }
    result.config = image;
    active_bank_ = bank;
    status_.flags |= bank == 0 ? modbus::kLoadedBankA : modbus::kLoadedBankB;
    status_.sequence = h[bank].sequence;
    if (migrated) {
      status_.flags |= modbus::kMigrated;
      if (status_.reason == 0) status_.reason = static_cast<std::uint16_t>(Reason::kSchemaMigrated);
    }
    break;
  }
  if (active_bank_ < 0) {
    status_.flags |= modbus::kLoadedDefaults;
    if (status_.reason == 0) status_.reason = static_cast<std::uint16_t>(Reason::kNoRecord);
  }
  result.status = status_;
  return result;
}

bool ConfigStore::save(const ConfigImage& config) {
  const int target = active_bank_ == 0 ? 1 : 0;
  const std::size_t base = bank_offset(target);
  // One newer than the record that stays (the other bank), so the next boot
  // prefers the new record whatever sequence the old one carries; without a
  // record there, one newer than the newest seen.
  const int remaining = 1 - target;
  const std::uint32_t sequence =
      (bank_state_[remaining] == BankState::kValid ? bank_sequence_[remaining] : sequence_) + 1u;
  const auto fail = [this]() {
    status_.flags |= modbus::kSaveFailed;
    status_.reason = static_cast<std::uint16_t>(Reason::kFlashError);
    return false;
  };
  if (kRecordBytes > flash_.sector_size()) return fail();
  if (flash_.erase(sector_[target]) != FlashError::kOk) return fail();

  // Payload, one flash word at a time; CRC accumulated over what is written.
  std::uint32_t payload_crc = 0;
  std::uint8_t word[kFlashWordBytes];
  std::size_t fill = 0;
  std::size_t word_index = 0;
  const auto flush = [&]() {
    for (std::size_t i = fill; i < kFlashWordBytes; ++i) word[i] = 0xFF;
    payload_crc = crc32(word, kFlashWordBytes, payload_crc);
    const bool ok = flash_.program(base + kFlashWordBytes * (1 + word_index), word) == FlashError::kOk;
    ++word_index;
    fill = 0;
    return ok;
  };
  for (std::size_t s = 0; s < modbus::kPersistedCount; ++s) {
    const RegisterDef& d = modbus::persisted_def(s);
    std::uint8_t entry[kEntryBytes] = {};
    put32(entry, modbus::fnv1a(d.name));
    entry[4] = static_cast<std::uint8_t>(d.type);
    put32(entry + 8, config.raw[s]);
    for (std::uint8_t b : entry) {
      word[fill++] = b;
      if (fill == kFlashWordBytes && !flush()) return fail();
    }
  }
  if (fill > 0 && !flush()) return fail();

  // Header last: until this word is programmed the bank is not a record.
  std::uint8_t hw[kFlashWordBytes];
  put32(hw + 0, kRecordMagic);
  put16(hw + 4, kFormatVersion);
  put16(hw + 6, static_cast<std::uint16_t>(modbus::kPersistedCount));
  put32(hw + 8, modbus::kSchemaHash);
  put32(hw + 12, sequence);
  put32(hw + 16, static_cast<std::uint32_t>(kPayloadBytes));
  put32(hw + 20, payload_crc);
  put32(hw + 24, crc32(hw, kHeaderCrcBytes));
  put32(hw + 28, kCommitMarker);
  if (flash_.program(base, hw) != FlashError::kOk) return fail();

  // Verify by reading the record back as load() would.
  Header h{};
  if (check_bank(target, h) != BankState::kValid || h.sequence != sequence) return fail();
  bank_state_[target] = BankState::kValid;
  bank_sequence_[target] = sequence;
  active_bank_ = target;
  sequence_ = sequence;
  status_.flags = static_cast<std::uint16_t>(status_.flags & ~(modbus::kLoadedBankA | modbus::kLoadedBankB |
                                                               modbus::kLoadedDefaults | modbus::kSaveFailed));
  status_.flags |= target == 0 ? modbus::kLoadedBankA : modbus::kLoadedBankB;
  // The bank just written and read back is no longer corrupt (the flags said
  // "loaded bank B" and "bank B corrupt" together after such a save).
  status_.flags &= static_cast<std::uint16_t>(~(target == 0 ? modbus::kBankACorrupt : modbus::kBankBCorrupt));
  if (status_.reason == static_cast<std::uint16_t>(Reason::kBankCorrupt) &&
      (status_.flags & (modbus::kBankACorrupt | modbus::kBankBCorrupt)) == 0) {
    status_.reason = static_cast<std::uint16_t>(Reason::kNone);
  }
  status_.sequence = sequence;
  return true;
}

}  // namespace maglev::persistence
