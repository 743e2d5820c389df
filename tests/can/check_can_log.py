#!/usr/bin/python3
"""maglev-hil's --can-log file, read and decoded by independent tools.

    check_can_log.py CAN_LOG DBC TRACE_CSV           a maglev-hil run's --can-log
    check_can_log.py --host-commands CAN_LOG DBC EXPECTED
                                      can_log_host_commands' log (multiplexed)

* python-can (Debian's python3-can, can.CanutilsLogReader) must read every
  line; each message must equal this script's own strict parse of the line
  (id width, FD marker and flags nibble, payload bytes), so a reader that
  silently skipped or mangled a line fails the test.
* canmatrix (Debian's python3-canmatrix) loads the repo's DBC and decodes
  every frame: every id is in the DBC, length and FD format match it, every
  signal the frame carries decodes and lies in the DBC's [min, max].
* The decoded values must be what the bench sent: the E2E CRC recomputed
  here from the DBC's MaglevDataId, the sensor frame's counter = tick mod 256
  once per tick, the actuator frame answering the sensor frame of its tick,
  the amplifiers off while landed and on after levitate, the periodic frames
  on their catalog grid, and controller_status equal to the bench's own
  trace.csv row of that tick (state, pose, commanded currents).
* --host-commands: the in-process bench sends no host_command frames (it
  applies commands directly), so the DBC's multiplexed host_command is checked
  on a log of one frame per command code from the firmware's encoder: the
  multiplexer selects exactly that command's signals, and every binary64
  argument, the axis and the sequence number decode to the values sent.
"""
import csv
import re
import sys

import can
import canmatrix.formats

PERIOD_US = 400  # servo tick at 2500 Hz; the log's timestamps are tick x period
LEVITATE_T_S = 0.2  # tests/can/can_log.scenario

LINE = re.compile(r"^\((\d{10})\.(\d{6})\) (\S+) ([0-9A-F]{3}|[0-9A-F]{8})#(#[0-9A-F])?((?:[0-9A-F]{2})*)$")

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        if len(failures) <= 30:
            print("FAIL:", what)
    return cond


def crc16_ccitt_false(data, crc=0xFFFF):
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else (crc << 1)
            crc &= 0xFFFF
    return crc


def read_and_decode(log_path, dbc_path):
    """Steps 1 and 2: [(tick, frame name, {signal: phys}, {signal: raw})]."""
    # ---- 1. python-can reads every line; it must agree with a strict parse.
    with open(log_path) as f:
        lines = [line.rstrip("\n") for line in f]
    check(len(lines) > 0, "the log is empty")
    strict = []
    for i, line in enumerate(lines, 1):
        m = LINE.match(line)
        if not check(m is not None, f"line {i} is not a candump -l line: {line!r}"):
            continue
        secs, usecs, iface, ident, fd, data = m.groups()
        strict.append((int(secs) * 1_000_000 + int(usecs), iface, int(ident, 16), len(ident) == 8,
                       fd is not None, int(fd[1], 16) if fd else 0, bytes.fromhex(data)))
    with can.CanutilsLogReader(log_path) as reader:
        msgs = list(reader)
    check(len(msgs) == len(lines), f"python-can read {len(msgs)} messages from {len(lines)} lines")
    for i, (msg, s) in enumerate(zip(msgs, strict), 1):
        t_us, iface, ident, ext, fd, flags, data = s
        check(round(msg.timestamp * 1e6) == t_us, f"line {i}: python-can timestamp {msg.timestamp} != {t_us} us")
        check(msg.channel == iface and msg.arbitration_id == ident and msg.is_extended_id == ext
              and msg.is_fd == fd and msg.bitrate_switch == bool(flags & 1) and bytes(msg.data) == data
              and not msg.is_error_frame and not msg.is_remote_frame,
              f"line {i}: python-can's message {msg} differs from the line {lines[i - 1]!r}")
    times = [s[0] for s in strict]
    check(all(a <= b for a, b in zip(times, times[1:])), "timestamps go backwards")
    check(all(t % PERIOD_US == 0 for t in times), "a timestamp is not on the 400 us tick grid")

    # ---- 2. canmatrix decodes every frame with the repo's DBC.
    db = next(iter(canmatrix.formats.loadp(dbc_path).values()))
    by_id = {fr.arbitration_id.id: fr for fr in db.frames}
    decoded = []  # (tick, frame name, {signal: phys}, {signal: raw})
    for i, msg in enumerate(msgs, 1):
        fr = by_id.get(msg.arbitration_id)
        if not check(fr is not None, f"line {i}: id 0x{msg.arbitration_id:03X} is not in the DBC"):
            continue
        # Every bench frame is CAN FD with BRS and an 11-bit id, as the DBC says.
        check(msg.is_fd == fr.is_fd and msg.bitrate_switch and not msg.is_extended_id
              and not fr.arbitration_id.extended,
              f"line {i}: {fr.name}: format (FD {msg.is_fd}, BRS {msg.bitrate_switch}, "
              f"extended {msg.is_extended_id}) differs from the DBC (FD {fr.is_fd})")
        if not check(len(msg.data) == fr.size, f"line {i}: {fr.name} has {len(msg.data)} bytes, DBC {fr.size}"):
            continue
        try:
            values = fr.decode(bytes(msg.data))
        except Exception as e:  # any decoder error fails the test, with the line
            check(False, f"line {i}: canmatrix cannot decode {fr.name}: {e!r}")
            continue
        phys = {}
        for name, v in values.items():
            sig = fr.signal_by_name(name)
            p = float(v.phys_value)
            phys[name] = p
            check(float(sig.min) <= p <= float(sig.max),
                  f"line {i}: {fr.name}.{name} = {p} outside the DBC's [{sig.min}, {sig.max}]")
        # The E2E CRC, recomputed here: proves every payload byte is as sent.
        data_id = int(fr.attributes["MaglevDataId"])
        crc = crc16_ccitt_false(bytes(msg.data[2:]) + bytes([data_id & 0xFF, data_id >> 8]))
        check(int(phys["e2e_crc"]) == crc, f"line {i}: {fr.name} E2E CRC {int(phys['e2e_crc']):#06x} != {crc:#06x}")
        raw = {name: v.raw_value for name, v in values.items()}
        decoded.append((round(msg.timestamp * 1e6) // PERIOD_US, fr.name, phys, raw))
    return lines, decoded


def check_host_commands(log_path, dbc_path, expected_path):
    lines, decoded = read_and_decode(log_path, dbc_path)
    with open(expected_path) as f:
        expected = [line.split() for line in f if line.strip()]
    # one command and its ack per host command code (17 since calibrate_coupling)
    check(len(decoded) == len(expected) == 34, f"{len(decoded)} frames decoded, {len(expected)} expected, want 34")
    for (_, name, phys, raw), want in zip(decoded, expected):
        check(name == want[0], f"frame {name}, expected {want[0]}")
        code = int(want[1])
        if name == "host_command":
            axis, seq = int(want[2]), int(want[3])
            check(int(phys["command_code"]) == code and int(phys["axis"]) == axis and int(phys["command_seq"]) == seq,
                  f"host_command {code}: code/axis/seq {phys['command_code']}/{phys['axis']}/{phys['command_seq']}")
            args = dict(kv.split("=") for kv in want[4:])
            # The multiplexer must select exactly this command's signals.
            got_args = set(phys) - {"e2e_crc", "e2e_counter", "command_code", "axis", "command_seq"}
            check(got_args == set(args), f"host_command {code}: signals {sorted(got_args)}, expected {sorted(args)}")
            for k, v in args.items():
                # binary64 on the wire: the value must come back bit for bit.
                check(k in raw and float(raw[k]) == float(v), f"host_command {code}: {k} = {raw.get(k)}, sent {v}")
        else:
            seq, result, state, tick = (int(x) for x in want[2:6])
            check((int(phys["command_code"]), int(phys["command_seq"]), int(phys["result"]),
                   int(phys["sequencer_state"]), int(phys["tick"])) == (code, seq, result, state, tick),
                  f"host_command_ack {code}: {phys}")
    print(f"{log_path}: {len(lines)} lines read by python-can, {len(decoded)} host_command/ack frames decoded by "
          f"canmatrix (multiplexed by command_code) with {dbc_path}")
    return report()


def report():
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    print("all checks passed")
    return 0


def main(log_path, dbc_path, trace_path):
    lines, decoded = read_and_decode(log_path, dbc_path)

    # ---- 3. the decoded values are what the bench sent.
    with open(trace_path) as f:
        trace = list(csv.DictReader(f))
    n_ticks = len(trace)
    frames_of = {}
    for tick, name, phys, _ in decoded:
        frames_of.setdefault(name, []).append((tick, phys))
    expected = {"sensor", "actuator", "current_monitor", "controller_status", "heartbeat_plant",
                "heartbeat_controller"}
    check(expected <= set(frames_of), f"the log lacks {sorted(expected - set(frames_of))}")
    # Only the frames the in-process run puts on its bus.
    check(set(frames_of) <= expected, f"unexpected frames {sorted(set(frames_of) - expected)}")

    sensor = frames_of.get("sensor", [])
    check([t for t, _ in sensor] == list(range(n_ticks)),
          f"sensor frames: {len(sensor)} for {n_ticks} ticks, not one per tick in order")
    for t, p in sensor:
        check(int(p["e2e_counter"]) == t % 256, f"tick {t}: sensor counter {p['e2e_counter']} != tick mod 256")
    sensor_counter = {t: int(p["e2e_counter"]) for t, p in sensor}

    actuator = frames_of.get("actuator", [])
    check([t for t, _ in actuator] == list(range(n_ticks)), "actuator frames: not one per tick in order")
    levitate_tick = round(LEVITATE_T_S * 1e6) // PERIOD_US
    for t, p in actuator:
        check(int(p["e2e_counter"]) == sensor_counter.get(t), f"tick {t}: actuator does not answer the sensor frame")
        enabled = int(p["amplifier_enable"])
        if t < levitate_tick:
            check(enabled == 0 and all(p[f"dac_code_{j}"] == 0.0 for j in range(8)),
                  f"tick {t}: amplifiers on or current commanded before levitate")
    enabled_ticks = [t for t, p in actuator if int(p["amplifier_enable"]) == 1]
    check(enabled_ticks and enabled_ticks[0] >= levitate_tick and enabled_ticks[-1] == n_ticks - 1,
          "amplifier_enable never goes to 1 after levitate, or drops again")
    check(any(abs(p["dac_code_0"]) > 0.01 for t, p in actuator if t >= levitate_tick),
          "no coil current commanded after levitate")

    cm = frames_of.get("current_monitor", [])
    check([t for t, _ in cm] == list(range(0, n_ticks, 5)), "current_monitor not on every 5th tick")
    check([int(p["e2e_counter"]) for _, p in cm] == [k % 256 for k in range(len(cm))],
          "current_monitor counter does not increment by 1")
    hb = frames_of.get("heartbeat_plant", [])
    check([t for t, _ in hb] == list(range(0, n_ticks, 250)), "heartbeat_plant not on every 250th tick")
    for t, p in hb:
        check(int(p["uptime_ms"]) == t * PERIOD_US // 1000, f"tick {t}: heartbeat_plant uptime {p['uptime_ms']} ms")
        check(int(p["node_state"]) == 1, f"tick {t}: plant heartbeat not operational")

    hbc = frames_of.get("heartbeat_controller", [])
    check([t for t, _ in hbc] == list(range(249, n_ticks, 250)), "heartbeat_controller not after every 250th tick")
    for t, p in hbc:
        check(int(p["uptime_ms"]) == (t + 1) * PERIOD_US // 1000 and int(p["node_state"]) == 1,
              f"tick {t}: heartbeat_controller uptime {p['uptime_ms']} ms, state {p['node_state']}")

    status = frames_of.get("controller_status", [])
    # The node counts ticks from 1 and publishes on every 10th: after ticks 9, 19, ...
    check([t for t, _ in status] == list(range(9, n_ticks, 10)), "controller_status not after every 10th tick")
    for t, p in status:
        row = trace[t]
        check(int(p["tick"]) == t + 1, f"tick {t}: controller_status.tick = {p['tick']}, expected {t + 1}")
        check(int(p["sequencer_state"]) == int(row["state"]) & 0x0F,
              f"tick {t}: status state {p['sequencer_state']} != trace.csv state {row['state']}")
        check(abs(p["x_nm"] - float(row["x_m"]) * 1e9) <= 1.0 and abs(p["z_nm"] - float(row["z_m"]) * 1e9) <= 1.0,
              f"tick {t}: status pose x {p['x_nm']} nm, z {p['z_nm']} nm != trace.csv {row['x_m']}, {row['z_m']} m")
        for j in range(8):
            check(abs(p[f"current_command_{j}"] - float(row[f"i{j + 1}_cmd_A"])) <= 0.0011,
                  f"tick {t}: current_command_{j} {p[f'current_command_{j}']} A != trace.csv {row[f'i{j + 1}_cmd_A']}")
    check(any(int(p["sequencer_state"]) != int(status[0][1]["sequencer_state"]) for _, p in status) if status else False,
          "the sequencer state never changes in the log (levitate not seen)")

    counts = {k: len(v) for k, v in sorted(frames_of.items())}
    print(f"{log_path}: {len(lines)} lines read by python-can {can.__version__}, "
          f"{len(decoded)} frames decoded by canmatrix with {dbc_path}: {counts}")
    return report()


if __name__ == "__main__":
    if len(sys.argv) == 5 and sys.argv[1] == "--host-commands":
        sys.exit(check_host_commands(*sys.argv[2:]))
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(*sys.argv[1:]))
