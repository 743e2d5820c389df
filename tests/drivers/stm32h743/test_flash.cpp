// Flash: unlock keys, sector erase and 256-bit flash-word program sequences,
// QW wait, error flags.
#include <CppUTest/TestHarness.h>

#include "maglev/drivers/flash.hpp"

using namespace maglev::drivers;
namespace r = maglev::stm32h7;
namespace f = maglev::stm32h7::flash;
using Bus = r::FakeRegisterBus<64, 256>;

namespace {
constexpr r::Addr kCr2 = f::kBase + f::kBank2Offset + f::kCr;
constexpr r::Addr kSr2 = f::kBase + f::kBank2Offset + f::kSr;
constexpr r::Addr kKeyr2 = f::kBase + f::kBank2Offset + f::kKeyr;
constexpr r::Addr kCcr2 = f::kBase + f::kBank2Offset + f::kCcr;
constexpr r::Addr kCr1 = f::kBase + f::kCr;
constexpr r::Addr kSr1 = f::kBase + f::kSr;

// Hardware model: LOCK clears after KEY1 then KEY2 (any other key keeps it);
// QW rises when an operation starts (START, or the 8th word of a flash word)
// and reads set for `busy_reads` SR reads; `error_bits` appear in SR at the end.
struct FlashModel {
  std::uint32_t last_key = 0;
  int words_in_buffer = 0;
  int qw_reads_left = 0;
  int busy_reads = 5;
  int sr_reads = 0;
  std::uint32_t error_bits = 0;
  bool stuck = false;

  static void on_write(void* ctx, Bus& bus, r::Addr addr, std::uint32_t value) {
    auto& m = *static_cast<FlashModel*>(ctx);
    if (addr == kKeyr2 || addr == f::kBase + f::kKeyr) {
      const r::Addr cr = addr - f::kKeyr + f::kCr;
      if (m.last_key == f::kKey1 && value == f::kKey2) bus.preset(cr, bus.peek(cr) & ~f::kCrLock);
      m.last_key = value;
    } else if ((addr == kCr2 || addr == kCr1) && (value & f::kCrStart) != 0) {
      bus.preset(addr, value & ~f::kCrStart);  // START is cleared by hardware
      m.start();
    } else if (addr >= r::memory::kFlashBank1 && addr < r::memory::kFlashBank1 + 0x200000u) {
      if (++m.words_in_buffer == 8) {
        m.words_in_buffer = 0;
        m.start();
      }
    }
  }
  void start() { qw_reads_left = busy_reads; }
  static std::uint32_t on_read(void* ctx, Bus&, r::Addr addr, std::uint32_t stored) {
    auto& m = *static_cast<FlashModel*>(ctx);
    if (addr != kSr2 && addr != kSr1) return stored;
    ++m.sr_reads;
    if (m.stuck) return f::kSrQw;
    if (m.qw_reads_left > 0) {
      --m.qw_reads_left;
      return f::kSrQw | f::kSrBsy;
    }
    return stored | m.error_bits;
  }
};
}  // namespace

TEST_GROUP(Flash) {
  Bus bus;
  FlashModel model;
  flash::Flash<Bus> drv{bus, 1000};
  void setup() override {
    bus.set_write_hook(&FlashModel::on_write, &model);
    bus.set_read_hook(&FlashModel::on_read, &model);
    bus.preset(kCr1, f::kCrLock);  // reset state: both banks locked
    bus.preset(kCr2, f::kCrLock);
  }
};

TEST(Flash, LocateBankAndSector) {
  constexpr flash::Location a = flash::locate(0x080E0000);
  LONGS_EQUAL(0, a.bank);
  LONGS_EQUAL(7, a.sector);
  constexpr flash::Location b = flash::locate(0x081C0000);
  LONGS_EQUAL(1, b.bank);
  LONGS_EQUAL(6, b.sector);
  CHECK_FALSE(flash::locate(0x07FFFFFF).valid);
  CHECK_FALSE(flash::locate(0x08200000).valid);
}

TEST(Flash, SectorEraseSequence) {
  CHECK(drv.erase_sector(0x081C0000) == flash::Status::kOk);  // bank 2, sector 6
  // KEYR2: 0x45670123 then 0xCDEF89AB; clear flags; SER|SNB=6|PSIZE=x32; +START.
  LONGS_EQUAL(0, bus.index_of_write(kKeyr2, 0));
  UNSIGNED_LONGS_EQUAL(0x45670123u, bus.log(0).value);
  UNSIGNED_LONGS_EQUAL(kKeyr2, bus.log(1).addr);
  UNSIGNED_LONGS_EQUAL(0xCDEF89ABu, bus.log(1).value);
  UNSIGNED_LONGS_EQUAL(kCcr2, bus.log(2).addr);
  UNSIGNED_LONGS_EQUAL(kCr2, bus.log(3).addr);
  UNSIGNED_LONGS_EQUAL(0x624u, bus.log(3).value);
  UNSIGNED_LONGS_EQUAL(0x6A4u, bus.log(4).value);
  CHECK(model.sr_reads >= 5 + 1 + 1);  // idle check + 5 QW polls + final status
  // Afterwards SER/SNB are cleared and the bank is locked again.
  UNSIGNED_LONGS_EQUAL(0x21u, bus.peek(kCr2));
  LONGS_EQUAL(0, bus.writes_to(kCr1));  // bank 1 untouched
}

TEST(Flash, ProgramOneFlashWord) {
  const std::uint32_t words[8] = {0x11111111, 0x22222222, 0x33333333, 0x44444444,
                                  0x55555555, 0x66666666, 0x77777777, 0x88888888};
  CHECK(drv.program_flash_word(0x080C0020, words) == flash::Status::kOk);  // bank 1, sector 6
  const long pg = bus.index_of_write(kCr1, 0);
  UNSIGNED_LONGS_EQUAL(0x22u, bus.log(static_cast<std::size_t>(pg)).value);  // PG | PSIZE x32
  for (unsigned i = 0; i < 8; ++i) {
    const auto& w = bus.log(static_cast<std::size_t>(pg) + 1 + i);
    UNSIGNED_LONGS_EQUAL(0x080C0020u + 4 * i, w.addr);
    UNSIGNED_LONGS_EQUAL(words[i], w.value);
  }
  UNSIGNED_LONGS_EQUAL(0x21u, bus.peek(kCr1));  // PG cleared, locked
}

TEST(Flash, ProgramBytesPadsTheLastFlashWordWithErasedValue) {
  std::uint8_t data[40];
  for (int i = 0; i < 40; ++i) data[i] = static_cast<std::uint8_t>(i);
  CHECK(drv.program(0x080E0000, data, sizeof data) == flash::Status::kOk);
  UNSIGNED_LONGS_EQUAL(0x03020100u, bus.peek(0x080E0000));
  UNSIGNED_LONGS_EQUAL(0x27262524u, bus.peek(0x080E0024));
  UNSIGNED_LONGS_EQUAL(0xFFFFFFFFu, bus.peek(0x080E0028));
  UNSIGNED_LONGS_EQUAL(0xFFFFFFFFu, bus.peek(0x080E003C));
}

TEST(Flash, ErrorFlagsAreReportedAndCleared) {
  model.error_bits = f::kSrPgserr;
  const std::uint32_t words[8] = {};
  CHECK(drv.program_flash_word(0x080E0000, words) == flash::Status::kSequenceError);
  model.error_bits = f::kSrWrperr;
  CHECK(drv.erase_sector(0x080E0000) == flash::Status::kWriteProtected);
  model.error_bits = f::kSrStrberr;
  CHECK(drv.program_flash_word(0x080E0000, words) == flash::Status::kStrobeError);
  // The clear register got every error bit after the failing operation.
  const std::size_t n = bus.writes_to(f::kBase + f::kCcr);
  const long last_ccr = bus.index_of_write(f::kBase + f::kCcr, n - 1);
  UNSIGNED_LONGS_EQUAL(f::kSrAllErrors | f::kSrEop, bus.log(static_cast<std::size_t>(last_ccr)).value);
}

TEST(Flash, StuckQueueTimesOutAndBadAddressesWriteNothing) {
  CHECK(drv.erase_sector(0x080E0100) == flash::Status::kBadAddress);    // not a sector start
  const std::uint32_t words[8] = {};
  CHECK(drv.program_flash_word(0x080E0004, words) == flash::Status::kBadAddress);  // not 32-byte aligned
  LONGS_EQUAL(0, bus.log_size());
  model.stuck = true;
  CHECK(drv.erase_sector(0x080E0000) == flash::Status::kTimeout);
}

TEST(Flash, WrongKeyLeavesTheBankLocked) {
  // A previous bad key sequence locks CR until reset: model by ignoring keys.
  bus.set_write_hook(nullptr, nullptr);
  CHECK(drv.erase_sector(0x080E0000) == flash::Status::kLocked);
}
