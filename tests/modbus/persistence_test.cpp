// Persistence: save/load, bank alternation, corrupt-bank fallback, schema
// migration/refusal, FileFlash, and a power cut at every flash step of a save.
#include <CppUTest/TestHarness.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <unistd.h>
#include <vector>

#include "maglev/persistence/power_cut_flash.hpp"
#include "maglev/persistence/config_store.hpp"
#include "maglev/file_flash/file_flash.hpp"

using namespace maglev;
using modbus::ConfigImage;
using modbus::RegId;
using persistence::FlashError;

namespace {

constexpr std::size_t kSector = 4096;

// The brown-out during a save: firmware/persistence's PowerCutFlash.
using CutFlash = persistence::PowerCutFlash;

ConfigImage variant(float kp) {
  ConfigImage c = ConfigImage::defaults();
  c.set(RegId::gain_x_kp, kp);
  c.set(RegId::limit_peak_current, 3.5);
  return c;
}

}  // namespace

TEST_GROUP(Persistence) {
  std::uint8_t storage[kSector * 2];
  void setup() override { std::memset(storage, 0xFF, sizeof storage); }
};

TEST(Persistence, FirstBootLoadsDefaultsAndSaysSo) {
  persistence::RamFlash flash(storage, kSector, 2);
  persistence::ConfigStore store(flash, 0, 1);
  const auto r = store.load();
  CHECK(r.config == ConfigImage::defaults());
  CHECK(r.status.flags & modbus::kLoadedDefaults);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kNoRecord), r.status.reason);
}

TEST(Persistence, SaveAlternatesBanksAndLoadsHighestSequence) {
  persistence::RamFlash flash(storage, kSector, 2);
  {
    persistence::ConfigStore store(flash, 0, 1);
    store.load();
    CHECK(store.save(variant(1000.0f)));
    CHECK(store.save(variant(2000.0f)));
    CHECK(store.save(variant(3000.0f)));  // A(1) B(2) A(3)
  }
  persistence::ConfigStore store(flash, 0, 1);
  const auto r = store.load();
  DOUBLES_EQUAL(3000.0, r.config.get(RegId::gain_x_kp), 0.0);
  DOUBLES_EQUAL(3.5, r.config.get(RegId::limit_peak_current), 0.0);
  CHECK(r.status.flags & modbus::kLoadedBankA);
  LONGS_EQUAL(3, static_cast<long>(r.status.sequence));
  LONGS_EQUAL(0, r.status.flags & (modbus::kBankACorrupt | modbus::kBankBCorrupt | modbus::kMigrated));
}

TEST(Persistence, CorruptNewestBankFallsBackToOtherAndFlags) {
  persistence::RamFlash flash(storage, kSector, 2);
  {
    persistence::ConfigStore store(flash, 0, 1);
    store.load();
    CHECK(store.save(variant(1000.0f)));  // A seq 1
    CHECK(store.save(variant(2000.0f)));  // B seq 2
  }
  storage[kSector + 32 + 9] ^= 0x01;  // flip one payload bit in B
  persistence::ConfigStore store(flash, 0, 1);
  const auto r = store.load();
  DOUBLES_EQUAL(1000.0, r.config.get(RegId::gain_x_kp), 0.0);
  CHECK(r.status.flags & modbus::kLoadedBankA);
  CHECK(r.status.flags & modbus::kBankBCorrupt);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kBankCorrupt), r.status.reason);
  // Both corrupt: defaults, both flagged.
  storage[32 + 9] ^= 0x01;
  const auto r2 = store.load();
  CHECK(r2.config == ConfigImage::defaults());
  CHECK(r2.status.flags & modbus::kLoadedDefaults);
  CHECK(r2.status.flags & modbus::kBankACorrupt);
  CHECK(r2.status.flags & modbus::kBankBCorrupt);
  // The next save still works, into a corrupt bank, and is loaded afterwards.
  CHECK(store.save(variant(4000.0f)));
  // The bank it wrote and read back is flagged corrupt no longer; the other
  // still is, and so is the reason.
  const modbus::PersistStatus after = store.status();
  CHECK((after.flags & modbus::kBankACorrupt) == 0);
  CHECK(after.flags & modbus::kLoadedBankA);
  CHECK(after.flags & modbus::kBankBCorrupt);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kBankCorrupt), after.reason);
  CHECK(store.save(variant(5000.0f)));  // into B: nothing corrupt is left
  CHECK((store.status().flags & (modbus::kBankACorrupt | modbus::kBankBCorrupt)) == 0);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kNone), store.status().reason);
  CHECK(store.save(variant(4000.0f)));
  persistence::ConfigStore again(flash, 0, 1);
  DOUBLES_EQUAL(4000.0, again.load().config.get(RegId::gain_x_kp), 0.0);
}

// Rewrites the record in bank A entry by entry through `edit`, with correct
// CRCs, as an older/newer firmware with another schema would have stored it.
namespace {
std::uint32_t rd32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0] | (p[1] << 8) | (p[2] << 16)) | (static_cast<std::uint32_t>(p[3]) << 24);
}
void wr32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
void reseal(std::uint8_t* bank, std::uint32_t schema_hash) {
  const std::uint32_t payload_bytes = rd32(bank + 16);
  wr32(bank + 8, schema_hash);
  wr32(bank + 20, persistence::crc32(bank + 32, payload_bytes));
  wr32(bank + 24, persistence::crc32(bank, 24));
}
std::uint8_t* find_entry(std::uint8_t* bank, const char* name) {
  const std::uint32_t h = modbus::fnv1a(name);
  for (std::size_t e = 0; e < modbus::kPersistedCount; ++e) {
    if (rd32(bank + 32 + e * 12) == h) return bank + 32 + e * 12;
  }
  return nullptr;
}
}  // namespace

TEST(Persistence, OtherSchemaIsMigratedByName) {
  persistence::RamFlash flash(storage, kSector, 2);
  persistence::ConfigStore store(flash, 0, 1);
  store.load();
  CHECK(store.save(variant(1234.0f)));
  // The "old firmware" had no seq.home_timeout and an entry we dropped since.
  std::uint8_t* e = find_entry(storage, "seq.homing_timeout");
  CHECK(e != nullptr);
  wr32(e, modbus::fnv1a("legacy.removed_entry"));
  wr32(e + 8, 0x12345678);
  reseal(storage, 0xDEADBEEF);
  const auto r = store.load();
  CHECK(r.status.flags & modbus::kLoadedBankA);
  CHECK(r.status.flags & modbus::kMigrated);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kSchemaMigrated), r.status.reason);
  DOUBLES_EQUAL(1234.0, r.config.get(RegId::gain_x_kp), 0.0);  // matched by name
  DOUBLES_EQUAL(modbus::def(RegId::seq_homing_timeout).default_value, r.config.get(RegId::seq_homing_timeout),
                1e-6);  // new entry: default
}

TEST(Persistence, TypeChangeIsRefusedWithReason) {
  persistence::RamFlash flash(storage, kSector, 2);
  persistence::ConfigStore store(flash, 0, 1);
  store.load();
  CHECK(store.save(variant(1234.0f)));
  std::uint8_t* e = find_entry(storage, "gain.y.kp");
  e[4] = static_cast<std::uint8_t>(modbus::RegType::kI32);
  reseal(storage, 0xDEADBEEF);
  const auto r = store.load();
  CHECK(r.config == ConfigImage::defaults());
  CHECK(r.status.flags & modbus::kRefused);
  CHECK(r.status.flags & modbus::kLoadedDefaults);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kTypeChanged), r.status.reason);
}

// Whatever coupling correction the kernel accepts, the record holds: with a
// payload a passed calibration left 12 in a +-10 register, the save reported
// success and the next boot refused the record (the older bank loaded).
TEST(Persistence, ACouplingCorrectionTheKernelAcceptsSavesAndLoads) {
  persistence::RamFlash flash(storage, kSector, 2);
  persistence::ConfigStore store(flash, 0, 1);
  store.load();
  ConfigImage c = variant(1234.0f);
  c.set(RegId::coupling_x_theta_x, 34.0);  // the kernel's bound at 1.5 kg payload
  CHECK(store.save(c));
  persistence::ConfigStore again(flash, 0, 1);
  const auto r = again.load();
  CHECK((r.status.flags & modbus::kRefused) == 0);
  DOUBLES_EQUAL(34.0, r.config.get(RegId::coupling_x_theta_x), 0.0);
}

TEST(Persistence, OutOfRangeStoredValueIsRefused) {
  persistence::RamFlash flash(storage, kSector, 2);
  persistence::ConfigStore store(flash, 0, 1);
  store.load();
  CHECK(store.save(variant(1234.0f)));
  std::uint8_t* e = find_entry(storage, "limit.peak_current");
  wr32(e + 8, modbus::encode(modbus::RegType::kF32, 9.0));  // > 4 A
  reseal(storage, modbus::kSchemaHash);
  const auto r = store.load();
  CHECK(r.status.flags & modbus::kRefused);
  LONGS_EQUAL(static_cast<int>(persistence::Reason::kValueOutOfRange), r.status.reason);
  CHECK(r.config == ConfigImage::defaults());
}

// Caught by fuzz_config_bank's "the next boot loads what was saved" check:
// sequence numbers wrap (0xFFFFFFFF -> 0), and
// load() compared them with '>': the record saved after the wrap lost to
// the one before it, so a save that reported success was undone at the next
// boot. Sequences compare in serial-number order now, and a save is always
// one newer than the record that stays.
TEST(Persistence, ASaveAfterTheSequenceWrapsIsTheOneLoaded) {
  persistence::RamFlash flash(storage, kSector, 2);
  {
    persistence::ConfigStore store(flash, 0, 1);
    store.load();
    CHECK(store.save(variant(1000.0f)));  // bank A
  }
  wr32(storage + 12, 0xFFFFFFFFu);  // bank A's sequence at the end of its range
  reseal(storage, modbus::kSchemaHash);
  persistence::ConfigStore store(flash, 0, 1);
  CHECK(store.load().status.flags & modbus::kLoadedBankA);
  CHECK(store.save(variant(2000.0f)));  // bank B, sequence 0
  persistence::ConfigStore next_boot(flash, 0, 1);
  const auto r = next_boot.load();
  DOUBLES_EQUAL(2000.0, r.config.get(RegId::gain_x_kp), 0.0);
  CHECK(r.status.flags & modbus::kLoadedBankB);
  LONGS_EQUAL(0, static_cast<long>(r.status.sequence));
  // And the one after: bank A, sequence 1.
  CHECK(next_boot.save(variant(3000.0f)));
  persistence::ConfigStore third_boot(flash, 0, 1);
  const auto r3 = third_boot.load();
  DOUBLES_EQUAL(3000.0, r3.config.get(RegId::gain_x_kp), 0.0);
  CHECK(r3.status.flags & modbus::kLoadedBankA);
  LONGS_EQUAL(1, static_cast<long>(r3.status.sequence));
}

TEST(Persistence, PowerCutAtEveryStepLeavesAValidConfiguration) {
  const ConfigImage old_cfg = variant(1000.0f);
  const ConfigImage new_cfg = variant(2000.0f);
  // Count the steps of a save first.
  long steps = 0;
  {
    std::memset(storage, 0xFF, sizeof storage);
    persistence::RamFlash ram(storage, kSector, 2);
    CutFlash counting(ram, 1 << 30);
    persistence::ConfigStore store(counting, 0, 1);
    store.load();
    CHECK(store.save(old_cfg));
    steps = counting.ops;
  }
  LONGS_EQUAL(static_cast<long>(persistence::ConfigStore::kSaveSteps), steps);
  int loaded_old = 0;
  int loaded_new = 0;
  // Two histories: the save targets bank B (old record in A), and bank A
  // (old record in B, after a second save).
  for (int history = 0; history < 2; ++history) {
    for (long n = 0; n <= steps; ++n) {
      std::memset(storage, 0xFF, sizeof storage);
      persistence::RamFlash ram(storage, kSector, 2);
      {
        persistence::ConfigStore setup_store(ram, 0, 1);
        setup_store.load();
        if (history == 1) CHECK(setup_store.save(variant(500.0f)));
        CHECK(setup_store.save(old_cfg));
      }
      CutFlash cut(ram, n);
      persistence::ConfigStore store(cut, 0, 1);
      store.load();
      const bool ok = store.save(new_cfg);
      CHECK_EQUAL(n >= steps, ok);
      // Reboot on healthy flash.
      persistence::ConfigStore rebooted(ram, 0, 1);
      const auto r = rebooted.load();
      CHECK_FALSE(r.status.flags & modbus::kLoadedDefaults);
      if (r.config == new_cfg) {
        ++loaded_new;
        CHECK(n >= steps);
      } else {
        CHECK(r.config == old_cfg);
        ++loaded_old;
      }
      // And the store keeps working after the cut.
      CHECK(rebooted.save(variant(3000.0f)));
      persistence::ConfigStore again(ram, 0, 1);
      DOUBLES_EQUAL(3000.0, again.load().config.get(RegId::gain_x_kp), 0.0);
    }
  }
  LONGS_EQUAL(2 * steps, loaded_old);
  LONGS_EQUAL(2, loaded_new);
}

TEST(Persistence, FileFlashKeepsConfigurationAcrossInstances) {
  char path[] = "/tmp/maglev_fileflash_XXXXXX";
  const int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  std::remove(path);
  {
    persistence::FileFlash flash(path, kSector, 2);
    CHECK(flash.ok());
    persistence::ConfigStore store(flash, 0, 1);
    CHECK(store.load().status.flags & modbus::kLoadedDefaults);
    CHECK(store.save(variant(777.0f)));
    std::uint8_t word[32] = {};
    LONGS_EQUAL(static_cast<int>(FlashError::kNotErased), static_cast<int>(flash.program(0, word)));
  }
  {
    persistence::FileFlash flash(path, kSector, 2);
    persistence::ConfigStore store(flash, 0, 1);
    const auto r = store.load();
    DOUBLES_EQUAL(777.0, r.config.get(RegId::gain_x_kp), 0.0);
    CHECK(r.status.flags & modbus::kLoadedBankA);
  }
  std::remove(path);
}

// Issue 17: a flash file of the wrong size (truncated, empty, or a valid one
// with 1 MiB appended) and any unrelated file were overwritten with 0xFF and
// reported as "first boot", destroying the saved settings. Now refused, untouched.
TEST(Persistence, AFlashFileOfTheWrongSizeIsRefusedUntouched) {
  char path[] = "/tmp/maglev_fileflash_XXXXXX";
  const int fd = mkstemp(path);
  CHECK(fd >= 0);
  close(fd);
  std::remove(path);
  {  // a real flash file with saved settings
    persistence::FileFlash flash(path, kSector, 2);
    CHECK(flash.ok());
    persistence::ConfigStore store(flash, 0, 1);
    CHECK(store.save(variant(555.0f)));
  }
  auto bytes_of = [](const char* p) {
    std::FILE* f = std::fopen(p, "rb");
    std::vector<std::uint8_t> b;
    if (f == nullptr) return b;
    int c;
    while ((c = std::fgetc(f)) != EOF) b.push_back(static_cast<std::uint8_t>(c));
    std::fclose(f);
    return b;
  };
  const std::vector<std::uint8_t> good = bytes_of(path);
  LONGS_EQUAL(2 * kSector, good.size());
  auto write_bytes = [](const char* p, const std::vector<std::uint8_t>& b) {
    std::FILE* f = std::fopen(p, "wb");
    if (!b.empty()) std::fwrite(b.data(), 1, b.size(), f);
    std::fclose(f);
  };
  std::vector<std::uint8_t> appended = good;
  appended.resize(good.size() + (1u << 20), 0x42);
  const std::vector<std::vector<std::uint8_t>> bad = {
      std::vector<std::uint8_t>(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(good.size() / 2)),  // truncated
      {},                                                                                                     // empty
      appended,                                                                                               // + 1 MiB
      std::vector<std::uint8_t>(1234, 0x7A),                                                                  // unrelated
  };
  for (const auto& b : bad) {
    write_bytes(path, b);
    {
      persistence::FileFlash flash(path, kSector, 2);
      CHECK_FALSE(flash.ok());
      CHECK_TRUE(flash.error().find("left untouched") != std::string::npos);
    }
    CHECK_TRUE(bytes_of(path) == b);  // not a byte changed
  }
  // The real file still loads its settings.
  write_bytes(path, good);
  {
    persistence::FileFlash flash(path, kSector, 2);
    CHECK(flash.ok());
    persistence::ConfigStore store(flash, 0, 1);
    DOUBLES_EQUAL(555.0, store.load().config.get(RegId::gain_x_kp), 0.0);
  }
  std::remove(path);
}
