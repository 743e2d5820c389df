// kernel-bitexact-compare: compares two output files of replay_format.hpp
// (host kernel vs. the M7 replay image) bit for bit. On the first mismatch it
// prints the tick, the field (name[index]) and both values in hex and decoded.
//
// usage: kernel-bitexact-compare <host_outputs.bin> <target_outputs.bin>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <algorithm>
#include <string>
#include <vector>

#include "maglev/kernel_replay/replay_format.hpp"

namespace {

namespace kr = maglev::kernel_replay;

bool read_file(const char* path, std::vector<std::uint8_t>* bytes) {
  std::FILE* f = std::fopen(path, "rb");
  if (f == nullptr) return false;
  bytes->clear();
  std::uint8_t chunk[65536];
  std::size_t n = 0;
  while ((n = std::fread(chunk, 1, sizeof(chunk), f)) > 0) bytes->insert(bytes->end(), chunk, chunk + n);
  const bool ok = std::ferror(f) == 0;
  std::fclose(f);
  return ok;
}

std::string show(kr::FieldKind kind, const std::uint8_t* p) {
  char text[128];
  switch (kind) {
    case kr::FieldKind::kU8:
    case kr::FieldKind::kBool:
      std::snprintf(text, sizeof(text), "0x%02x (%u)", p[0], p[0]);
      break;
    case kr::FieldKind::kI16: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      std::snprintf(text, sizeof(text), "0x%04x (%d)", static_cast<unsigned>(static_cast<std::uint16_t>(v)), v);
      break;
    }
    case kr::FieldKind::kU32: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      std::snprintf(text, sizeof(text), "0x%08" PRIx32 " (%" PRIu32 ")", v, v);
      break;
    }
    case kr::FieldKind::kF32: {
      std::uint32_t bits;
      float v;
      std::memcpy(&bits, p, 4);
      std::memcpy(&v, p, 4);
      std::snprintf(text, sizeof(text), "0x%08" PRIx32 " (%.9g)", bits, static_cast<double>(v));
      break;
    }
    case kr::FieldKind::kI64: {
      std::int64_t v;
      std::memcpy(&v, p, 8);
      std::snprintf(text, sizeof(text), "0x%016" PRIx64 " (%" PRId64 ")", static_cast<std::uint64_t>(v), v);
      break;
    }
  }
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s <host_outputs.bin> <target_outputs.bin>\n", argv[0]);
    return 2;
  }
  std::vector<std::uint8_t> host, target;
  if (!read_file(argv[1], &host) || !read_file(argv[2], &target)) {
    std::fprintf(stderr, "compare: cannot read %s or %s\n", argv[1], argv[2]);
    return 2;
  }
  const std::size_t rec = kr::kOutputRecordBytes;
  if (host.empty() || host.size() % rec != 0 || target.size() % rec != 0) {
    std::fprintf(stderr, "compare: FAIL: file sizes %zu / %zu are not whole %zu-byte records\n", host.size(),
                 target.size(), rec);
    return 1;
  }
  const std::size_t ticks = std::min(host.size(), target.size()) / rec;
  for (std::size_t t = 0; t < ticks; ++t) {
    const std::uint8_t* a = &host[t * rec];
    const std::uint8_t* b = &target[t * rec];
    if (std::memcmp(a, b, rec) == 0) continue;
    std::size_t offset = 0;
    for (const kr::FieldInfo& f : kr::kOutputFields) {
      const std::size_t w = kr::field_bytes(f.kind);
      for (int i = 0; i < f.count; ++i, offset += w) {
        if (std::memcmp(a + offset, b + offset, w) != 0) {
          std::printf("compare: FAIL: first difference at tick %zu, field %s[%d]:\n  host   %s\n  target %s\n", t,
                      f.name, i, show(f.kind, a + offset).c_str(), show(f.kind, b + offset).c_str());
          std::size_t differing = 0;
          for (std::size_t u = t; u < ticks; ++u) differing += std::memcmp(&host[u * rec], &target[u * rec], rec) != 0;
          std::printf("compare: %zu of %zu ticks differ\n", differing, ticks);
          return 1;
        }
      }
    }
  }
  if (host.size() != target.size()) {
    std::printf("compare: FAIL: the first %zu ticks match but the host wrote %zu ticks, the target %zu\n", ticks,
                host.size() / rec, target.size() / rec);
    return 1;
  }
  std::printf("compare: OK: %zu ticks, %zu bytes bit-identical (host x86-64 vs. Cortex-M7 under QEMU)\n", ticks,
              host.size());
  return 0;
}
