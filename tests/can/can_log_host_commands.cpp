// Writes a candump log of one host_command frame per command code (and its
// host_command_ack), plus the values that went into each, for
// check_can_log.py --host-commands: the in-process bench applies commands
// without a bus, so its --can-log never carries the multiplexed host_command;
// this is how the DBC's multiplexing is proven with canmatrix instead. The
// frames come from the firmware's own encoder and the bench's log writer.
//
//   can_log_host_commands LOG EXPECTED
#include <cstdio>
#include <string>
#include <type_traits>

#include "maglev/bench/candump_log.hpp"
#include "maglev/can_link/codec.hpp"

namespace {

using namespace maglev::can;

// Distinct, exactly representable values per field; alternating signs, so a
// wrong sign or slot shows.
double field_value(int code, std::size_t i) {
  const double v = static_cast<double>(code * 8 + static_cast<int>(i) + 1) * 0.125;
  return i % 2 == 0 ? v : -v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: can_log_host_commands LOG EXPECTED\n");
    return 2;
  }
  maglev::bench::CandumpLogWriter log;
  std::string err;
  if (!log.open(argv[1], "virtual", &err)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 1;
  }
  std::FILE* exp = std::fopen(argv[2], "w");
  if (exp == nullptr) {
    std::fprintf(stderr, "cannot write %s\n", argv[2]);
    return 1;
  }
  std::uint8_t counter = 0;
  for (const HostCommandSpec& spec : kHostCommandSpecs) {
    const int code = static_cast<int>(spec.code);
    HostCommandFrame h = make_host_command(spec.code, static_cast<std::uint16_t>(100 * code),
                                           static_cast<std::uint8_t>(code % 6));
    // Field i of the command's argument struct, by the one table.
    with_args(spec.code, h.args, [&](auto& args) {
      using Args = std::remove_reference_t<decltype(args)>;
      for (std::size_t i = 0; i < Args::kFields.size(); ++i) args.*(Args::kFields[i].member) = field_value(code, i);
    });
    CanFrame f{};
    encode_host_command(h, counter++, f);
    const auto t_us = static_cast<std::uint64_t>(code) * 400u;
    log.write(t_us, f);
    std::fprintf(exp, "host_command %d %u %u", code, static_cast<unsigned>(h.axis), static_cast<unsigned>(h.seq));
    for (std::size_t i = 0; i < spec.field_count; ++i) {
      std::fprintf(exp, " %s_%s=%.17g", spec.name, spec.fields[i].name, field_value(code, i));
    }
    std::fprintf(exp, "\n");
    const HostCommandAckFrame ack{h.seq, spec.code, static_cast<std::uint8_t>(code % 16), 7,
                                  static_cast<std::uint32_t>(1000 + code)};
    encode_host_command_ack(ack, static_cast<std::uint8_t>(code - 1), f);
    log.write(t_us, f);
    std::fprintf(exp, "host_command_ack %d %u %u %u %u\n", code, static_cast<unsigned>(ack.seq),
                 static_cast<unsigned>(ack.result), static_cast<unsigned>(ack.sequencer_state),
                 static_cast<unsigned>(ack.tick));
  }
  const bool ok = std::fclose(exp) == 0;
  if (!log.close(&err)) {
    std::fprintf(stderr, "%s\n", err.c_str());
    return 1;
  }
  return ok ? 0 : 1;
}
