// The candump log line format of maglev-hil --can-log (candump_log.hpp) for
// the frame kinds the bench does not put on its bus today -- classical
// frames, 29-bit ids, ESI, error frames -- so a future message with one of
// them is still logged the way candump -l writes it. The bench's own frames
// (FD + BRS, 11-bit) are checked end to end by can_log_bench_decodes.
#include <cstdio>
#include <string>

#include "maglev/bench/candump_log.hpp"

// CppUTest last: its leak-detector macros clash with STL headers.
#include <CppUTest/TestHarness.h>

using maglev::bench::CandumpLogWriter;
using maglev::bench::format_candump_line;
using namespace maglev::can;

namespace {
CanFrame frame(std::uint32_t id, std::uint8_t flags, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f{};
  f.id = id;
  f.flags = flags;
  for (std::uint8_t b : bytes) f.data[f.len++] = b;
  return f;
}
}  // namespace

TEST_GROUP(CandumpLog){};

TEST(CandumpLog, ClassicalStandardId) {
  STRCMP_EQUAL("(0000000001.000400) vcan0 123#DEADBEEF",
               format_candump_line(1000400, "vcan0", frame(0x123, 0, {0xDE, 0xAD, 0xBE, 0xEF})).c_str());
  // Three hex digits even for small ids; an empty classical frame has no data.
  STRCMP_EQUAL("(0000000000.000000) can0 010#", format_candump_line(0, "can0", frame(0x10, 0, {})).c_str());
}

TEST(CandumpLog, ExtendedIdHasEightDigits) {
  STRCMP_EQUAL("(0000000000.000001) vcan0 1ABCDEF0#01",
               format_candump_line(1, "vcan0", frame(0x1ABCDEF0, kFlagExtendedId, {0x01})).c_str());
  STRCMP_EQUAL("(0000000000.000001) vcan0 00000042#",
               format_candump_line(1, "vcan0", frame(0x42, kFlagExtendedId, {})).c_str());
}

TEST(CandumpLog, FdFlagsNibble) {
  STRCMP_EQUAL("(0000000002.500000) virtual 030##1A0B1",
               format_candump_line(2500000, "virtual", frame(0x30, kFlagFd | kFlagBrs, {0xA0, 0xB1})).c_str());
  STRCMP_EQUAL("(0000000000.000000) virtual 030##0FF",
               format_candump_line(0, "virtual", frame(0x30, kFlagFd, {0xFF})).c_str());
  STRCMP_EQUAL("(0000000000.000000) virtual 030##300",
               format_candump_line(0, "virtual", frame(0x30, kFlagFd | kFlagBrs | kFlagEsi, {0x00})).c_str());
}

TEST(CandumpLog, WriterSkipsErrorFramesAndCounts) {
  const std::string path = "candump_log_test.log";
  CandumpLogWriter w;
  std::string err;
  CHECK_TRUE(w.open(path, "vcan0", &err));
  w.write(400, frame(0x123, 0, {0x01}));
  w.write(800, frame(0x20000080, kFlagErrorFrame, {0, 0, 0, 0, 0, 0, 0, 0}));
  w.write(800, frame(0x30, kFlagFd | kFlagBrs, {0x02}));
  CHECK_TRUE(w.close(&err));
  UNSIGNED_LONGS_EQUAL(2, w.frames());
  std::string all;
  std::FILE* in = std::fopen(path.c_str(), "r");
  CHECK_TRUE(in != nullptr);
  char buf[256];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, in)) > 0;) all.append(buf, n);
  std::fclose(in);
  STRCMP_EQUAL("(0000000000.000400) vcan0 123#01\n(0000000000.000800) vcan0 030##102\n", all.c_str());
  std::remove(path.c_str());
}

TEST(CandumpLog, UnwritablePathIsAnError) {
  CandumpLogWriter w;
  std::string err;
  CHECK_FALSE(w.open("/proc/no-such-dir/can.log", "vcan0", &err));
  CHECK_TRUE(err.find("/proc/no-such-dir/can.log") != std::string::npos);
}
