// firmware/board/stm32h743 BoardFlash: persistence::ConfigStore on the real
// flash driver (drivers/flash) over a fake bus with a flash-array model:
// save/load round trip in the two configuration sectors (bank 2 sectors 0/1),
// D-cache invalidation after every erase/program, the ECC "program once" rule,
// and a corrupted bank flagged at load.
#include <cstdint>
#include <vector>

#include "maglev/board/stm32h743/board_flash.hpp"
#include "maglev/drivers/flash.hpp"
#include "maglev/register_schema/register_map.hpp"
#include "maglev/persistence/config_store.hpp"

#include <CppUTest/TestHarness.h>

using namespace maglev;
namespace r = maglev::stm32h7;
namespace f = maglev::stm32h7::flash;
using Bus = r::FakeRegisterBus<64, 16>;

namespace {
constexpr r::Addr kBankA = 0x08100000;  // bank 2 sector 0 (__config_bank_a_start)
constexpr r::Addr kBankB = 0x08120000;  // bank 2 sector 1
constexpr std::size_t kSectorBytes = 128 * 1024;
constexpr r::Addr kCr2 = f::kBase + f::kBank2Offset + f::kCr;
constexpr r::Addr kKeyr2 = f::kBase + f::kBank2Offset + f::kKeyr;

// The two sectors as an array: erase fills 0xFF, programming can only clear
// bits (NOR flash); the status register reads idle (operations are instant).
struct ArrayModel {
  std::vector<std::uint8_t> mem = std::vector<std::uint8_t>(2 * kSectorBytes, 0xFF);
  std::uint32_t last_key = 0;
  int erases = 0;
  int word_writes = 0;
  static bool in_array(r::Addr a) { return a >= kBankA && a < kBankA + 2 * kSectorBytes; }
  static void on_write(void* ctx, Bus& bus, r::Addr addr, std::uint32_t value) {
    auto& m = *static_cast<ArrayModel*>(ctx);
    if (addr == kKeyr2) {
      if (m.last_key == f::kKey1 && value == f::kKey2) bus.preset(kCr2, bus.peek(kCr2) & ~f::kCrLock);
      m.last_key = value;
    } else if (addr == kCr2 && (value & f::kCrStart) != 0 && (value & f::kCrSer) != 0) {
      const std::uint32_t snb = (value & f::kCrSnbMask) >> f::kCrSnbShift;
      if (snb < 2) {
        for (std::size_t i = 0; i < kSectorBytes; ++i) m.mem[snb * kSectorBytes + i] = 0xFF;
      }
      ++m.erases;
    } else if (in_array(addr)) {
      const std::size_t o = addr - kBankA;
      for (unsigned b = 0; b < 4; ++b) m.mem[o + b] &= static_cast<std::uint8_t>(value >> (8 * b));
      ++m.word_writes;
    }
  }
  static std::uint32_t on_read(void* ctx, Bus&, r::Addr addr, std::uint32_t stored) {
    auto& m = *static_cast<ArrayModel*>(ctx);
    if (!in_array(addr)) return stored & ~(f::kSrQw | f::kSrBsy);
    const std::size_t o = addr - kBankA;
    return static_cast<std::uint32_t>(m.mem[o]) | (static_cast<std::uint32_t>(m.mem[o + 1]) << 8) |
           (static_cast<std::uint32_t>(m.mem[o + 2]) << 16) | (static_cast<std::uint32_t>(m.mem[o + 3]) << 24);
  }
};

int g_invalidations = 0;
r::Addr g_last_invalidated = 0;
void count_invalidate(r::Addr a, std::size_t) {
  ++g_invalidations;
  g_last_invalidated = a;
}
}  // namespace

TEST_GROUP(BoardFlash) {
  Bus bus;
  ArrayModel model;
  drivers::flash::Flash<Bus> drv{bus, 1000};
  void setup() override {
    bus.set_write_hook(&ArrayModel::on_write, &model);
    bus.set_read_hook(&ArrayModel::on_read, &model);
    bus.preset(kCr2, f::kCrLock);
    g_invalidations = 0;
  }
};

TEST(BoardFlash, ConfigStoreRoundTripInBothSectors) {
  board::stm32h743::BoardFlash<Bus> flash(bus, drv, kBankA, kBankB, &count_invalidate);
  LONGS_EQUAL(kSectorBytes, flash.sector_size());
  persistence::ConfigStore store(flash, 0, 1);
  const persistence::LoadResult empty = store.load();
  CHECK((empty.status.flags & modbus::kLoadedDefaults) != 0);

  modbus::ConfigImage image = modbus::ConfigImage::defaults();
  image.set(modbus::RegId::payload_mass, 0.25);
  CHECK_TRUE(store.save(image));
  LONGS_EQUAL(1, model.erases);
  CHECK(g_invalidations >= 2);  // the erased sector, then every programmed word
  image.set(modbus::RegId::payload_mass, 0.5);
  CHECK_TRUE(store.save(image));
  LONGS_EQUAL(2, model.erases);
  // Both sectors hold a committed record (magic "MLCF" at the start of each).
  LONGS_EQUAL(0x4D, model.mem[0]);
  LONGS_EQUAL(0x4D, model.mem[kSectorBytes]);

  persistence::ConfigStore reboot(flash, 0, 1);
  const persistence::LoadResult loaded = reboot.load();
  DOUBLES_EQUAL(0.5, loaded.config.get(modbus::RegId::payload_mass), 1e-6);
  CHECK((loaded.status.flags & (modbus::kBankACorrupt | modbus::kBankBCorrupt)) == 0);

  // Corrupt the newest record's payload: flagged, the older record is used.
  const bool newest_is_a = (loaded.status.flags & modbus::kLoadedBankA) != 0;
  model.mem[(newest_is_a ? 0 : kSectorBytes) + persistence::kFlashWordBytes + 2] ^= 0x01;
  persistence::ConfigStore again(flash, 0, 1);
  const persistence::LoadResult fallback = again.load();
  CHECK((fallback.status.flags & (newest_is_a ? modbus::kBankACorrupt : modbus::kBankBCorrupt)) != 0);
  DOUBLES_EQUAL(0.25, fallback.config.get(modbus::RegId::payload_mass), 1e-6);
}

TEST(BoardFlash, OffsetsMapToTheConfigSectorsAndRulesHold) {
  board::stm32h743::BoardFlash<Bus> flash(bus, drv, kBankA, kBankB, &count_invalidate);
  std::uint8_t word[persistence::kFlashWordBytes];
  for (std::size_t i = 0; i < sizeof word; ++i) word[i] = static_cast<std::uint8_t>(i + 1);
  CHECK(flash.program(kSectorBytes + 64, word) == persistence::FlashError::kOk);  // sector 1 = bank B
  LONGS_EQUAL(kBankB + 64, g_last_invalidated);
  LONGS_EQUAL(1, model.mem[kSectorBytes + 64]);
  LONGS_EQUAL(32, model.mem[kSectorBytes + 95]);
  std::uint8_t back[5] = {};
  CHECK(flash.read(kSectorBytes + 65, back, 5) == persistence::FlashError::kOk);  // unaligned read
  LONGS_EQUAL(2, back[0]);
  LONGS_EQUAL(6, back[4]);
  CHECK(flash.program(kSectorBytes + 64, word) == persistence::FlashError::kNotErased);
  CHECK(flash.program(kSectorBytes + 16, word) == persistence::FlashError::kMisaligned);
  CHECK(flash.program(2 * kSectorBytes, word) == persistence::FlashError::kOutOfRange);
  CHECK(flash.erase(2) == persistence::FlashError::kOutOfRange);
  CHECK(flash.erase(1) == persistence::FlashError::kOk);
  LONGS_EQUAL(0xFF, model.mem[kSectorBytes + 64]);
}
