// stagectl's exit codes, shared by every command file (stagectl.cpp,
// lab_commands.cpp). Also in --help and host-tools/stagectl/README.md.
#pragma once

namespace maglev::stagectl {

// Exit codes (also in --help and host-tools/stagectl/README.md).
enum Exit : int {
  kOk = 0,
  kUsage = 1,          // bad command line
  kConnect = 2,        // cannot open the serial device / connect
  kBadValue = 3,       // unknown register, unparsable value, wrong unit, out of range (checked locally)
  kRefused = 4,        // the controller answered 02/03/04 (address/value refused, flash failed)
  kBusy = 5,           // 06: not allowed in the present state (e.g. gains while levitated)
  kAccess = 6,         // 01 / engineer register without --engineer
  kCommandRejected = 7,  // the kernel rejected a motion command (cmd.result != 0)
  kComm = 8,           // timeout, CRC, broken connection
  kFile = 9,           // config file cannot be read/written or has errors
  kTimeout = 10,       // --wait elapsed before the stage got there
};

}  // namespace maglev::stagectl
