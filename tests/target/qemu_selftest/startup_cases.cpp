// Startup checks: .data copied from its flash load image, .bss zeroed, static
// constructors run exactly once and in init_priority order.
#include <cstdint>
#include <cstring>

#include "maglev/board/mps2_an500/startup.hpp"
#include "maglev/target_test/target_test.hpp"
#include "selftest_expected.hpp"

namespace {

using namespace maglev::selftest;

// Non-const, initialised: lives in .data (RAM), initial bytes in flash.
std::uint32_t g_data_pattern[] = {MAGLEV_SELFTEST_DATA_PATTERN};
// Zero-initialised: .bss.
std::uint32_t g_bss_block[256];

// CRC-32 (IEEE 802.3, reflected, as zlib.crc32), bitwise: no table in RAM.
std::uint32_t crc32(const std::uint8_t* bytes, std::size_t length) {
  std::uint32_t crc = 0xFFFFFFFFU;
  for (std::size_t i = 0; i < length; ++i) {
    crc ^= bytes[i];
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc >> 1) ^ (0xEDB88320U & (0U - (crc & 1U)));
    }
  }
  return ~crc;
}

// Construction log: each constructor appends its id.
std::uint32_t g_construction_log[4];  // .bss, zero before constructors
std::uint32_t g_construction_count;

volatile std::uint32_t g_seed = 0x1234U;  // read at run time: no constant init

struct Recorder {
  explicit Recorder(std::uint32_t id) : value(g_seed + id) {
    if (g_construction_count < 4U) {
      g_construction_log[g_construction_count] = id;
    }
    ++g_construction_count;
  }
  std::uint32_t value;
};

// Declared default-priority first, but priority 200 must be constructed first
// (linker script sorts .init_array.* by priority).
Recorder g_default_priority{2};
[[gnu::init_priority(200)]] Recorder g_early{1};

std::uint32_t g_local_static_constructions = 0;
struct LocalStatic {
  LocalStatic() { ++g_local_static_constructions; }
};
LocalStatic& local_static() {
  static LocalStatic instance;  // -fno-threadsafe-statics: plain guard, no lock
  return instance;
}

}  // namespace

MAGLEV_TARGET_TEST(startup, data_section_crc_matches_host) {
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(g_data_pattern);
  TT_CHECK_EQUAL(kDataPatternCrc32, crc32(bytes, sizeof(g_data_pattern)));
}

MAGLEV_TARGET_TEST(startup, data_section_was_copied_from_flash_load_image) {
  const auto image = maglev::board::mps2_an500::data_image();
  const auto* in_ram = reinterpret_cast<const std::uint8_t*>(g_data_pattern);
  TT_CHECK(in_ram >= image.ram_begin);
  TT_CHECK(in_ram + sizeof(g_data_pattern) <= image.ram_end);
  // The array lives in RAM (0x2000_0000 region), its initial bytes in flash.
  TT_CHECK(reinterpret_cast<std::uintptr_t>(in_ram) >= 0x20000000U);
  TT_CHECK(reinterpret_cast<std::uintptr_t>(image.load_begin) < 0x00400000U);
  const std::uint8_t* in_flash = image.load_begin + (in_ram - image.ram_begin);
  TT_CHECK(std::memcmp(in_ram, in_flash, sizeof(g_data_pattern)) == 0);
}

MAGLEV_TARGET_TEST(startup, bss_is_zero) {
  std::uint32_t ored = 0;
  for (const auto word : g_bss_block) {
    ored |= word;
  }
  TT_CHECK_EQUAL(0U, ored);
}

MAGLEV_TARGET_TEST(startup, static_constructors_ran_once_in_priority_order) {
  TT_CHECK_EQUAL(2U, g_construction_count);
  TT_CHECK_EQUAL(1U, g_construction_log[0]);
  TT_CHECK_EQUAL(2U, g_construction_log[1]);
  TT_CHECK_EQUAL(0x1235U, g_early.value);
  TT_CHECK_EQUAL(0x1236U, g_default_priority.value);
}

MAGLEV_TARGET_TEST(startup, function_local_static_is_constructed_once) {
  static_cast<void>(local_static());
  static_cast<void>(local_static());
  TT_CHECK_EQUAL(1U, g_local_static_constructions);
}

MAGLEV_TARGET_TEST(startup, fpu_enabled_in_cpacr) {
  const volatile auto& cpacr = *reinterpret_cast<const volatile std::uint32_t*>(0xE000ED88U);
  TT_CHECK_EQUAL(0xFU, (cpacr >> 20) & 0xFU);
}
