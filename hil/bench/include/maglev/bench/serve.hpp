// `maglev-hil serve --modbus-tcp HOST:PORT`: the simulated stage in real time
// behind the Modbus TCP register map (docs/BENCH.md, docs/REGISTERS.md).
#pragma once

namespace maglev::bench {

// argv[0] is "serve"; returns the process exit status (0 ok, 1 failure,
// 2 usage).
int serve_main(int argc, char** argv);

}  // namespace maglev::bench
