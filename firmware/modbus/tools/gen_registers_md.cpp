// Writes the register table of docs/REGISTERS.md from registers.def.
//   maglev_gen_registers_md --write FILE   replace the text between the markers
//   maglev_gen_registers_md --check FILE   exit 1 if the table in FILE differs
//   maglev_gen_registers_md                print the table
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "generated_section.hpp"
#include "maglev/register_schema/register_map.hpp"

namespace {

using namespace maglev::modbus;

const char* kBegin = "<!-- BEGIN GENERATED REGISTER TABLE (maglev_gen_registers_md; do not edit) -->";
const char* kEnd = "<!-- END GENERATED REGISTER TABLE -->";

// The docs' wording of "writable when" (tools use when_name()).
const char* when_text(WriteWhen w) {
  switch (w) {
    case WriteWhen::kNever: return "-";
    case WriteWhen::kAlways: return "always";
    case WriteWhen::kNotMoving: return "not moving";
    case WriteWhen::kIdle: return "idle (landed)";
    case WriteWhen::kGains: return "idle, or live tuning";
  }
  return "?";
}

std::string num(double v, RegType t) {
  char buf[64];
  if (t == RegType::kF32) {
    std::snprintf(buf, sizeof buf, "%.6g", v);
  } else {
    std::snprintf(buf, sizeof buf, "%.0f", v);
  }
  return buf;
}

// Markdown: a '|' inside a cell must be escaped.
std::string cell(const char* text) {
  std::string out;
  for (const char* p = text; *p != '\0'; ++p) {
    if (*p == '|') out += '\\';
    out += *p;
  }
  return out;
}

std::string table() {
  std::ostringstream o;
  o << kBegin << "\n\n";
  char hash[16];
  std::snprintf(hash, sizeof hash, "0x%08X", static_cast<unsigned>(kSchemaHash));
  o << "Schema hash of the persisted entries: `" << hash << "` (" << kPersistedCount << " persisted entries, "
    << kRegisterCount << " registers).\n\n";
  o << "| Address | Name | Type | Unit | Min | Max | Default | Access | Writable when | Persisted | Description |\n";
  o << "|---:|---|---|---|---:|---:|---:|---|---|---|---|\n";
  for (std::size_t i = 0; i < kRegisterCount; ++i) {
    const RegisterDef& d = kRegisters[i];
    std::string addr = std::to_string(d.address);
    if (width(d.type) > 1) addr += "-" + std::to_string(d.address + width(d.type) - 1);
    const bool ro = d.access == Access::kReadOnly;
    std::string def = ro ? "-" : num(d.default_value, d.type);
    o << "| " << addr << " | `" << d.name << "` | " << type_name(d.type) << " | " << cell(d.unit) << " | "
      << (ro ? "-" : num(d.min, d.type)) << " | " << (ro ? "-" : num(d.max, d.type)) << " | " << def << " | "
      << access_name(d.access) << " | " << when_text(d.when) << " | " << (d.persisted ? "yes" : "no") << " | "
      << cell(d.description) << " |\n";
  }
  o << "\n" << kEnd;
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  return maglev::docs::generated_section_main(
      argc, argv, maglev::docs::GeneratedSection{"maglev_gen_registers_md", "registers.def", kBegin, kEnd}, table(),
      " (" + std::to_string(kRegisterCount) + " registers)");
}
