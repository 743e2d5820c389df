#!/bin/bash
# The closed loop over real SocketCAN: controller and plant as two processes
# over vcan0 inside the test VM (Debian 6.1 kernel, TCG), lockstep, compared
# with the same scenario run in ONE process over the virtual bus on the host.
#   two_process_test.sh MAGLEV_HIL SCENARIO WORKDIR
# Asserts: both processes exit 0; levitated (Ready) at 30 um within 1 um; the
# 8 um x step settles to within 0.1 um; no missed actuator frames, no rejected
# frames; trace.csv and commands.txt byte-identical to the in-process run;
# metrics.json identical except wall-clock and bus-count keys (the two-process
# bus also carries host_command/ack frames and one start-up heartbeat).
# The VM must boot: 125 (no boot) / 124 (timeout) fail the test.
set -u
HERE="$(cd "$(dirname "$0")" && pwd)"
HIL="$1"; SC="$2"; WORK="$3"
rm -rf "$WORK"; mkdir -p "$WORK"
fail() { echo "FAIL: $*"; exit 1; }

echo "== in process, virtual bus (host)"
"$HIL" run "$SC" --out "$WORK/inproc" --no-plots --quiet > "$WORK/inproc.log" 2>&1 || { cat "$WORK/inproc.log"; fail "in-process run"; }

echo "== two processes over vcan0 (VM)"
T0=$(date +%s.%N)
"$HERE/run-in-vm.sh" --share "$(dirname "$HIL")" --share "$HERE" --share "$WORK" --share "$HERE/../../hil/profiles" --timeout 240 -- \
  sh "$HERE/two_process_guest.sh" "$HIL" "$SC" "$WORK/vm"
RC=$?
T1=$(date +%s.%N)
printf 'VM test wall time (boot + both processes): %.1f s\n' "$(echo "$T1 - $T0" | bc -l)"
[ $RC -eq 0 ] || fail "guest run exit code $RC (124 timeout, 125 VM did not boot)"

cmp "$WORK/inproc/trace.csv" "$WORK/vm/trace.csv" || fail "trace.csv differs between in-process and two-process runs"
cmp "$WORK/inproc/commands.txt" "$WORK/vm/commands.txt" || fail "commands.txt differs"
echo "trace.csv identical: $(wc -l < "$WORK/vm/trace.csv") lines, sha256 $(sha256sum < "$WORK/vm/trace.csv" | cut -c1-16)"
/usr/bin/python3 - "$WORK/inproc/metrics.json" "$WORK/vm/metrics.json" <<'PY' || fail "metrics"
import json, sys
a = json.load(open(sys.argv[1])); b = json.load(open(sys.argv[2]))
skip = {"real_time_factor", "wall_time_per_tick_us", "bus_frames", "bus_load_percent", "host_commands_acked"}
bad = [k for k in sorted(set(a) | set(b)) if k not in skip and a.get(k) != b.get(k)]
for k in bad: print("metric differs:", k, a.get(k), b.get(k))
m = b
checks = [
  ("completed", m["completed"] == 1),
  ("levitated", m["levitated"] == 1 and m["final_sequencer_state"] == 6),
  ("z within 1 um of 30 um", abs(m["z_height_error_m"]) < 1e-6),
  ("8 um step settled", m["x_step_8um_settled"] == 1 and abs(m["x_step_8um_measured_m"] - 8e-6) < 1e-7),
  ("no missed actuator frames", m["missed_actuator_frames"] == 0),
  ("no rejected frames", m["controller_rx_rejected_frames"] == 0 and m["plant_rx_rejected_frames"] == 0),
  ("both host commands acked", m["host_commands_acked"] == 2),
]
for name, ok in checks: print(("ok   " if ok else "FAIL ") + name)
print("two-process: %d ticks, %.0f ticks/s, levitation %.3f s, step settling %.4f s, bus frames %d vs %d in process"
      % (m["ticks"], 1e6 / m["wall_time_per_tick_us"], m["levitation_time_s"], m["x_step_8um_settling_time_s"],
         m["bus_frames"], a["bus_frames"]))
sys.exit(1 if bad or not all(ok for _, ok in checks) else 0)
PY
echo "two-process VM test OK"
