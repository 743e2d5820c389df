// A small DBC reader for tests only (BO_ and SG_ lines, Intel or Motorola
// flag recorded, Intel decoding). Independent of the codec on purpose: it is
// what "decode the bytes with the DBC" means in the tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

namespace maglev::can::test {

struct DbcSignal {
  std::string name;
  int start = 0;
  int length = 0;
  bool little_endian = true;
  bool is_signed = false;
  double factor = 1.0;
  double offset = 0.0;
  double min = 0.0;
  double max = 0.0;
  bool is_float64 = false;  // SIG_VALTYPE_ ... : 2
  bool is_multiplexor = false;  // "M": selects which multiplexed signals are present
  int multiplex_value = -1;     // "mN": present only when the multiplexor equals N
};
struct DbcMessage {
  std::uint32_t id = 0;
  std::string name;
  int length = 0;
  std::vector<DbcSignal> signals;
};

inline std::map<std::uint32_t, DbcMessage> parse_dbc(const std::string& path) {
  std::ifstream in(path);
  std::map<std::uint32_t, DbcMessage> out;
  const std::regex bo(R"(^BO_ (\d+) (\w+): (\d+) (\w+)\s*$)");
  const std::regex sg(
      R"(^ SG_ (\w+)(?: (M|m\d+))? : (\d+)\|(\d+)@([01])([+-]) \(([^,]+),([^)]+)\) \[([^|]+)\|([^\]]+)\] \"[^\"]*\" .*$)");
  const std::regex vt(R"(^SIG_VALTYPE_ (\d+) (\w+) : 2;$)");
  std::string line;
  DbcMessage* cur = nullptr;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_match(line, m, bo)) {
      DbcMessage msg;
      msg.id = static_cast<std::uint32_t>(std::stoul(m[1]));
      msg.name = m[2];
      msg.length = std::stoi(m[3]);
      cur = &(out[msg.id] = msg);
    } else if (cur != nullptr && std::regex_match(line, m, sg)) {
      DbcSignal s;
      s.name = m[1];
      const std::string mux = m[2];
      s.is_multiplexor = mux == "M";
      if (!mux.empty() && mux[0] == 'm') s.multiplex_value = std::stoi(mux.substr(1));
      s.start = std::stoi(m[3]);
      s.length = std::stoi(m[4]);
      s.little_endian = m[5] == "1";
      s.is_signed = m[6] == "-";
      s.factor = std::stod(m[7]);
      s.offset = std::stod(m[8]);
      s.min = std::stod(m[9]);
      s.max = std::stod(m[10]);
      cur->signals.push_back(s);
    } else if (std::regex_match(line, m, vt)) {
      auto it = out.find(static_cast<std::uint32_t>(std::stoul(m[1])));
      if (it != out.end()) {
        for (auto& sig : it->second.signals) {
          if (sig.name == m[2]) sig.is_float64 = true;
        }
      }
    } else if (line.empty()) {
      cur = nullptr;
    }
  }
  return out;
}

// Physical value of one signal (Intel byte order, byte*8+bit numbering).
inline double dbc_decode(const DbcSignal& s, const std::uint8_t* data) {
  std::uint64_t v = 0;
  for (int i = 0; i < s.length; ++i) {
    const int bit = s.start + i;
    v |= static_cast<std::uint64_t>((data[bit / 8] >> (bit % 8)) & 1) << i;
  }
  if (s.is_float64) {
    double d = 0.0;
    std::memcpy(&d, &v, sizeof d);
    return d;
  }
  double raw = static_cast<double>(v);
  if (s.is_signed && ((v >> (s.length - 1)) & 1) != 0) raw -= std::ldexp(1.0, s.length);
  return raw * s.factor + s.offset;
}

}  // namespace maglev::can::test
