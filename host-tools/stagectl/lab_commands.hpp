// stagectl's lab-tool commands (the on-board recorder and wave generator,
// docs/LAB-TOOLS.md): `record` and `frf`. Kept apart from stagectl.cpp's
// register commands; they talk to the same libmodbus context.
#pragma once

#include <modbus/modbus.h>

#include <string>
#include <vector>

namespace maglev::stagectl {

// The usage text of the lab commands (part of stagectl --help).
extern const char* const kLabHelp;
// args[0] = "record" | "frf"; returns a stagectl exit code.
int run_lab_command(modbus_t* ctx, const std::vector<std::string>& args);

}  // namespace maglev::stagectl
