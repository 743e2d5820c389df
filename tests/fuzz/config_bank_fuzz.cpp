// libFuzzer target: the configuration bank loader (firmware/persistence
// ConfigStore::load) on arbitrary flash images -- what a board finds in its
// two configuration sectors after a power cut, a bit flip, a flash of
// another firmware, or wear.
//
// Input: byte 0 = fix-ups, the rest = the two banks' bytes (bank A, then
// bank B; missing bytes are erased, 0xFF). A random header never carries the
// magic, the commit marker and two good CRC-32s, so the fix-up bits let the
// harness make them right, as a save would, so the decoding behind them
// (format version, schema migration by name, entry types and ranges,
// sequence numbers) is reached:
//   bit 0/1: bank A: magic + commit marker + header CRC / payload CRC
//   bit 2/3: bank B: the same
// Checked, beyond "no crash, no sanitizer report":
//   * load() only reads: the image is unchanged;
//   * the result is consistent: exactly one of "loaded bank A", "loaded bank
//     B", "defaults"; every loaded value inside its register's range;
//     defaults loaded -> the configuration is ConfigImage::defaults();
//   * save() after load() writes only the bank not in use (the record in use
//     survives a cut save), and the next boot loads exactly what was saved.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev/persistence/config_store.hpp"

namespace {

using namespace maglev::modbus;
using namespace maglev::persistence;

// Small sectors keep the fuzzer's inputs small; a record needs kRecordBytes.
constexpr std::size_t kSectorBytes = 4096;  // 2048 until the 37 coupling entries (issue 15)
static_assert(kRecordBytes <= kSectorBytes);

std::uint8_t g_flash[2 * kSectorBytes];
std::uint8_t g_before[2 * kSectorBytes];

std::uint32_t get32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
void put32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}

// What save() writes into a header, for a bank whose other fields came from
// the input (persistence format: config_store.hpp).
void fix_up(std::uint8_t* bank, bool header, bool payload) {
  if (payload) {
    std::size_t bytes = get32(bank + 16);
    if (bytes > kSectorBytes - kFlashWordBytes) bytes = kSectorBytes - kFlashWordBytes;
    put32(bank + 20, crc32(bank + kFlashWordBytes, bytes));
  }
  if (header) {
    put32(bank + 0, kRecordMagic);
    put32(bank + 28, kCommitMarker);
    put32(bank + 24, crc32(bank, 24));
  }
}

bool one_source(std::uint16_t flags) {
  const int n = ((flags & kLoadedBankA) != 0) + ((flags & kLoadedBankB) != 0) + ((flags & kLoadedDefaults) != 0);
  return n == 1;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t fix = data[0];
  std::memset(g_flash, 0xFF, sizeof g_flash);
  std::memcpy(g_flash, data + 1, size - 1 < sizeof g_flash ? size - 1 : sizeof g_flash);
  fix_up(g_flash, (fix & 1u) != 0, (fix & 2u) != 0);
  fix_up(g_flash + kSectorBytes, (fix & 4u) != 0, (fix & 8u) != 0);
  std::memcpy(g_before, g_flash, sizeof g_flash);

  RamFlash flash(g_flash, kSectorBytes, 2);
  ConfigStore store(flash, 0, 1);
  const LoadResult r = store.load();
  if (std::memcmp(g_before, g_flash, sizeof g_flash) != 0) __builtin_trap();  // load only reads
  if (!one_source(r.status.flags)) __builtin_trap();
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    if (!value_in_range(persisted_def(s), decode(persisted_def(s).type, r.config.raw[s]))) __builtin_trap();
  }
  if ((r.status.flags & kLoadedDefaults) != 0 && !(r.config == ConfigImage::defaults())) __builtin_trap();

  // Save what was loaded with one value changed (so the new record differs),
  // as an operator's "save" would.
  ConfigImage next = r.config;
  const std::size_t slot = size % kPersistedCount;
  const RegisterDef& d = persisted_def(slot);
  const ConfigImage defaults = ConfigImage::defaults();
  next.raw[slot] = next.raw[slot] == defaults.raw[slot] ? encode(d.type, d.min) : defaults.raw[slot];
  if (!value_in_range(d, decode(d.type, next.raw[slot]))) next.raw[slot] = r.config.raw[slot];
  const int in_use = (r.status.flags & kLoadedBankA) != 0 ? 0 : (r.status.flags & kLoadedBankB) != 0 ? 1 : -1;
  if (!store.save(next)) __builtin_trap();  // RamFlash never fails
  if (in_use >= 0 && std::memcmp(g_before + in_use * kSectorBytes, g_flash + in_use * kSectorBytes,
                                 kSectorBytes) != 0) {
    __builtin_trap();  // the record in use was touched
  }
  const LoadResult after = ConfigStore(flash, 0, 1).load();
  if (!(after.config == next)) __builtin_trap();  // the next boot loads what was saved
  const std::uint16_t saved_bank = in_use == 0 ? kLoadedBankB : kLoadedBankA;
  if ((after.status.flags & saved_bank) == 0) __builtin_trap();
  return 0;
}
