// libFuzzer target: the RTU frame parser and the register map semantics
// behind it, plus ConfigStore::load on arbitrary flash contents.
//   byte 0, bit 7 = 1: the rest is flash contents for ConfigStore::load()
//   otherwise: a byte stream on the serial line. Byte value `data[0]` acts as a
//   "silence" marker (t3.5 elapses, the frame ends). Each frame is processed
//   twice: as received (CRC mostly wrong) and with its CRC fixed up, so the
//   PDU handler sees every function code, count and address the fuzzer invents.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "maglev_test/fuzz_device.hpp"
#include "maglev/modbus/crc16.hpp"
#include "maglev/modbus/rtu_server.hpp"
#include "maglev/persistence/config_store.hpp"

namespace {

using namespace maglev::modbus;

using maglev::test::FuzzDevice;  // tests/support/include/maglev_test/fuzz_device.hpp

FuzzDevice g_device;
RegisterServer g_server(g_device, ConfigImage::defaults());
RtuServer g_rtu(g_server, 17, 115200);
std::uint8_t g_tx[kMaxRtuFrame];
std::uint8_t g_flash[2 * 4096];

void fuzz_flash(const std::uint8_t* data, std::size_t size) {
  std::memset(g_flash, 0xFF, sizeof g_flash);
  // Spread the input over the two bank headers and payloads.
  for (std::size_t i = 0; i < size; ++i) g_flash[(i * 37) % sizeof g_flash] = data[i];
  if (size > 8) std::memcpy(g_flash, data, size < 64 ? size : 64);
  maglev::persistence::RamFlash flash(g_flash, 4096, 2);
  maglev::persistence::ConfigStore store(flash, 0, 1);
  const auto r = store.load();
  for (std::size_t s = 0; s < kPersistedCount; ++s) {
    // Whatever loaded must be in range.
    if (!value_in_range(persisted_def(s), decode(persisted_def(s).type, r.config.raw[s]))) __builtin_trap();
  }
  store.save(r.config);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  if ((data[0] & 0x80u) != 0) {
    fuzz_flash(data + 1, size - 1);
    return 0;
  }
  const std::uint8_t marker = data[0];
  std::uint32_t t = 0;
  std::uint8_t frame[kMaxRtuFrame + 2];
  std::size_t n = 0;
  auto fixed_up = [&]() {
    if (n >= 2 && n <= kMaxRtuFrame - 2) {
      frame[0] = (frame[0] & 1u) != 0 ? 17 : 0;  // our unit or broadcast
      const std::uint16_t crc = crc16(frame, n);
      frame[n] = static_cast<std::uint8_t>(crc & 0xFF);
      frame[n + 1] = static_cast<std::uint8_t>(crc >> 8);
      const std::size_t len = g_rtu.process_frame(frame, n + 2, g_tx);
      if (len > kMaxRtuFrame) __builtin_trap();
      if (len > 0 && crc16(g_tx, len) != 0) __builtin_trap();  // every reply carries a good CRC
    }
    n = 0;
  };
  for (std::size_t i = 1; i < size; ++i) {
    if (data[i] == marker) {
      t += 2000;  // > t3.5 at 115200
      if (g_rtu.poll(t, g_tx) > kMaxRtuFrame) __builtin_trap();
      fixed_up();
      continue;
    }
    t += 95;  // one character at 115200 baud
    g_rtu.receive(data[i], t);
    if (n < kMaxRtuFrame) frame[n++] = data[i];
  }
  t += 2000;
  if (g_rtu.poll(t, g_tx) > kMaxRtuFrame) __builtin_trap();
  fixed_up();
  return 0;
}
