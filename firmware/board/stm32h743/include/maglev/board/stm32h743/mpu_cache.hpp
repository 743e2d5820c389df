// MPU regions and L1 caches (ARMv7-M ARM §B3.5 MPU, §B2.2.7 cache
// maintenance; Cortex-M7 TRM: 16 KB I-cache, 16 KB D-cache, 32-byte lines,
// D-cache 4-way / 128 sets).
//
// MPU (PRIVDEFENA: everything else keeps the default memory map attributes):
//   region 0: D2 SRAM 0x30000000, 512 KB (covers SRAM1/2/3) -- DMA buffers:
//             Normal, NON-cacheable (TEX=001 C=0 B=0), shareable, XN. DMA
//             and CPU then see the same bytes with no cache maintenance.
//   region 1: backup SRAM 0x38800000, 4 KB -- fault log: non-cacheable so a
//             fault record is in the SRAM the moment the store retires.
#pragma once

#include <cstdint>

#include "maglev/stm32h7/register_bus.hpp"

namespace maglev::board::stm32h743 {

struct MpuRegion {
  std::uint32_t base;
  std::uint32_t rasr;
};
constexpr std::uint32_t mpu_size_field(std::uint32_t log2_bytes) { return (log2_bytes - 1u) << 1; }
inline constexpr std::uint32_t kRasrXn = 1u << 28, kRasrApFull = 3u << 24, kRasrTex1 = 1u << 19,
                               kRasrShareable = 1u << 18, kRasrEnable = 1u;
inline constexpr std::uint32_t kRasrNonCacheable = kRasrXn | kRasrApFull | kRasrTex1 | kRasrShareable | kRasrEnable;
inline constexpr MpuRegion kMpuRegions[] = {
    {0x30000000u, kRasrNonCacheable | mpu_size_field(19)},  // 512 KB
    {0x38800000u, kRasrNonCacheable | mpu_size_field(12)},  // 4 KB
};
static_assert(kMpuRegions[0].rasr == 0x130C0025u);

template <stm32h7::RegisterBus Bus>
void configure_mpu(Bus& bus) {
  using namespace stm32h7;
  barrier(bus);
  bus.write32(mpu::kBase + mpu::kCtrl, 0u);
  for (std::uint32_t i = 0; i < sizeof(kMpuRegions) / sizeof(kMpuRegions[0]); ++i) {
    bus.write32(mpu::kBase + mpu::kRnr, i);
    bus.write32(mpu::kBase + mpu::kRbar, kMpuRegions[i].base);
    bus.write32(mpu::kBase + mpu::kRasr, kMpuRegions[i].rasr);
  }
  bus.write32(mpu::kBase + mpu::kCtrl, (1u << 2) | 1u);  // PRIVDEFENA | ENABLE
  barrier(bus);
}

template <stm32h7::RegisterBus Bus>
void enable_caches(Bus& bus) {
  using namespace stm32h7;
  // I-cache: invalidate all, enable.
  barrier(bus);
  bus.write32(scb::kIciallu, 0u);
  barrier(bus);
  modify32(bus, scb::kBase + scb::kCcr, 0u, scb::kCcrIc);
  barrier(bus);
  // D-cache: select L1 data, invalidate every set/way, enable.
  bus.write32(scb::kBase + scb::kCsselr, 0u);
  barrier(bus);
  const std::uint32_t ccsidr = bus.read32(scb::kBase + scb::kCcsidr);
  const std::uint32_t sets = ((ccsidr >> 13) & 0x7FFFu) + 1u;
  const std::uint32_t ways = ((ccsidr >> 3) & 0x3FFu) + 1u;
  for (std::uint32_t set = 0; set < sets; ++set) {
    for (std::uint32_t way = 0; way < ways; ++way) {
      bus.write32(scb::kDcisw, (set << 5) | (way << 30));  // 32-byte lines, 4 ways
    }
  }
  barrier(bus);
  modify32(bus, scb::kBase + scb::kCcr, 0u, scb::kCcrDc);
  barrier(bus);
}

}  // namespace maglev::board::stm32h743
