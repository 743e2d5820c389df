// The docs generators' common main(): a generated table lives in a Markdown
// file between a BEGIN and an END marker line.
//   TOOL                print the table
//   TOOL --write FILE   replace the text between the markers
//   TOOL --check FILE   exit 1 if the table in FILE differs (the ctest drift checks)
// Host-only, header-only (maglev_gen_registers_md, maglev_gen_lab_signals_md).
#pragma once

#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace maglev::docs {

struct GeneratedSection {
  const char* tool;    // "maglev_gen_registers_md"
  const char* source;  // "registers.def": what the table is generated from
  const char* begin;   // marker lines (the table text includes both)
  const char* end;
};

inline int generated_section_main(int argc, char** argv, const GeneratedSection& s, const std::string& table,
                                  const std::string& matches_note = "") {
  if (argc < 3) {
    std::cout << table << "\n";
    return 0;
  }
  const std::string mode = argv[1];
  const std::string path = argv[2];
  std::ifstream in(path);
  if (!in) {
    std::cerr << "cannot read " << path << "\n";
    return 2;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  std::string doc = ss.str();
  const auto b = doc.find(s.begin);
  const auto e = doc.find(s.end);
  if (b == std::string::npos || e == std::string::npos || e < b) {
    std::cerr << path << ": generated-table markers missing\n";
    return 2;
  }
  const std::string current = doc.substr(b, e + std::string(s.end).size() - b);
  if (mode == "--check") {
    if (current != table) {
      std::cerr << path << " drifted from " << s.source << "; regenerate with: " << s.tool << " --write " << path << "\n";
      return 1;
    }
    std::cout << path << " matches " << s.source << matches_note << "\n";
    return 0;
  }
  if (mode == "--write") {
    doc.replace(b, current.size(), table);
    std::ofstream out(path);
    out << doc;
    return out ? 0 : 2;
  }
  std::cerr << "usage: " << s.tool << " [--check|--write FILE]\n";
  return 2;
}

}  // namespace maglev::docs
