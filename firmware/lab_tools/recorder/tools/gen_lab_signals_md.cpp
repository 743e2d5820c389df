// Writes the signal table of docs/LAB-TOOLS.md from maglev/lab_tools/signals.hpp.
//   maglev_gen_lab_signals_md --write FILE   replace the text between the markers
//   maglev_gen_lab_signals_md --check FILE   exit 1 if the table in FILE differs
//   maglev_gen_lab_signals_md                print the table
#include <sstream>
#include <string>

#include "generated_section.hpp"
#include "maglev/lab_tools/signals.hpp"

namespace {

const char* kBegin = "<!-- BEGIN GENERATED SIGNAL TABLE (maglev_gen_lab_signals_md; do not edit) -->";
const char* kEnd = "<!-- END GENERATED SIGNAL TABLE -->";

std::string table() {
  using namespace maglev::lab;
  std::ostringstream o;
  o << kBegin << "\n\n| Id | Signal | Unit | Meaning |\n|---:|---|---|---|\n";
  char name[40];
  for (std::uint16_t id = 1; id < kSignalIdEnd; ++id) {
    const SignalGroupDef* g = signal_group(id);
    if (g == nullptr || !signal_name(id, name, sizeof name)) continue;
    const char* unit = signal_unit(id);
    o << "| " << id << " | `" << name << "` | " << (unit[0] != '\0' ? unit : "-") << " | "
      << g->description << " |\n";
  }
  o << "\n" << kEnd;
  return o.str();
}

}  // namespace

int main(int argc, char** argv) {
  return maglev::docs::generated_section_main(
      argc, argv, maglev::docs::GeneratedSection{"maglev_gen_lab_signals_md", "signals.hpp", kBegin, kEnd}, table());
}
