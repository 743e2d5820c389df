#!/usr/bin/env bash
# stagectl record / frf against the running HIL bench (`maglev-hil serve`,
# real time), checked against the bench's OWN loop measurement:
#   1. maglev-hil run loop_response: the bench's x crossover / phase margin
#      (metrics.json: its multisine at the plant input, measured offline);
#   2. serve, levitate; stagectl record (2 s, immediate): record.csv has t_s +
#      the channels asked for, 5000 rows, x.pose moving (noise), state 6 (ready);
#   3. an interrupted download (--max-blocks: exit 8) continued with --resume
#      gives the complete capture;
#   4. bad input: unknown signal (exit 3), 9 channels (exit 3), wave amplitude
#      above wave.limit and a sweep past Nyquist refused with 03 (exit 4),
#      nothing started (wave.state 0); a 2 um reference sine: recorded, x follows;
#   5. stagectl frf x: frf.csv columns, coherence, and crossover within 1 Hz,
#      phase margin within 2 deg of the bench's figures from step 1.
# usage: record_frf_bench.sh STAGECTL MAGLEV_HIL WORKDIR
set -u
STAGECTL=$1; HIL=$2; WORK=$3
rm -rf "$WORK"; mkdir -p "$WORK"
PY=/usr/bin/python3
fails=0; passes=0
fail() { fails=$((fails + 1)); echo "FAIL: $*"; }
pass() { passes=$((passes + 1)); echo "ok:   $*"; }
HIL_PID=
cleanup() { [ -n "$HIL_PID" ] && kill "$HIL_PID" 2>/dev/null && wait "$HIL_PID" 2>/dev/null; }
trap cleanup EXIT
finish() {
  if [ "$fails" -ne 0 ] && [ -f "$WORK/hil.log" ]; then echo "---- maglev-hil serve log (tail) ----"; tail -20 "$WORK/hil.log"; fi
  echo "$passes passed, $fails failed"
  [ "$fails" -eq 0 ]; exit $?
}

# 1. The bench's own loop figures.
"$HIL" run loop_response --out "$WORK/bench" --no-plots --quiet >"$WORK/bench.log" 2>&1 || { fail "maglev-hil run loop_response"; finish; }
read -r BENCH_FC BENCH_PM < <($PY -c "
import json; m = json.load(open('$WORK/bench/metrics.json')); m = m.get('metrics', m)
print(m['x_loop_crossover_Hz'], m['x_loop_phase_margin_deg'])")
pass "bench loop_response: x crossover $BENCH_FC Hz, phase margin $BENCH_PM deg"

# 2. serve + levitate + record.
PORT=$($PY -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
"$HIL" serve --modbus-tcp "127.0.0.1:$PORT" --flash "$WORK/flash.bin" >"$WORK/hil.log" 2>&1 &
HIL_PID=$!
S() { "$STAGECTL" --tcp "127.0.0.1:$PORT" "$@"; }
expect() {
  local want=$1 what=$2; shift 2
  S "$@" >"$WORK/last.out" 2>&1; local rc=$?
  if [ "$rc" -eq "$want" ]; then pass "$what (exit $rc)"; else fail "$what: exit $rc, expected $want: $(tail -3 "$WORK/last.out")"; fi
}
val() { S get "$1" | sed -e 's/.* = //' -e 's/ *#.*//'; }
for _ in $(seq 100); do S get id.magic >/dev/null 2>&1 && break; sleep 0.1; done
S get id.magic >/dev/null 2>&1 || { fail "maglev-hil serve did not come up"; finish; }
[ "$(val rec.state)" = 1 ] && [ "$(val rec.trigger_mode)" = 3 ] && pass "recorder armed in fault watch at boot" || fail "recorder not in fault watch at boot"
expect 0 "levitate" --wait 30 levitate

expect 0 "record 2 s" record --out "$WORK/rec" --duration 2 --channels x.pose,x.error,x.effort,z.pose,coil1.current,coil1.current_cmd,state
grep -q "download: 100.0 %" "$WORK/last.out" && pass "download progress printed" || fail "no download progress: $(cat "$WORK/last.out")"
$PY - "$WORK/rec/record.csv" <<'PYEOF' && pass "record.csv: columns, 5000 rows, moving pose, state ready" || fail "record.csv content"
import csv, sys, statistics
rows = list(csv.reader(open(sys.argv[1])))
head, data = rows[0], rows[1:]
want = ["t_s", "x.pose", "x.error", "x.effort", "z.pose", "coil1.current", "coil1.current_cmd", "state"]
assert head == want, head
assert len(data) == 5000, len(data)
col = {h: [float(r[i]) for r in data] for i, h in enumerate(head)}
dt = col["t_s"][1] - col["t_s"][0]
assert abs(dt - 0.0004) < 1e-9, dt
assert statistics.pstdev(col["x.pose"]) > 0, "x.pose constant"
assert statistics.pstdev(col["x.effort"]) > 0, "x.effort constant"
assert all(abs(z - 30e-6) < 5e-6 for z in col["z.pose"]), "z not at the levitation height"
assert all(s == 6 for s in col["state"]), "not ready throughout"
assert all(abs(c) > 0.1 for c in col["coil1.current"]), "coil 1 carries no current"
PYEOF

# 3. Interrupted download, resumed.
expect 8 "download interrupted after 50 blocks" record --out "$WORK/resume" --duration 2 --max-blocks 50
[ -s "$WORK/resume/record.partial" ] && pass "partial download kept" || fail "no record.partial"
expect 0 "download resumed" record --out "$WORK/resume" --resume
grep -q "resuming capture" "$WORK/last.out" && pass "resumed, not restarted" || fail "not resumed: $(cat "$WORK/last.out")"
[ "$(wc -l < "$WORK/resume/record.csv")" = 5001 ] && pass "resumed capture complete (5000 rows)" || fail "resumed record.csv rows: $(wc -l < "$WORK/resume/record.csv")"

# 4. Bad input: refused, nothing changed.
expect 3 "unknown signal refused" record --out "$WORK/bad" --channels x.pose,nonsense
expect 3 "9 channels refused" record --out "$WORK/bad" --channels x.pose,x.pose,x.pose,x.pose,x.pose,x.pose,x.pose,x.pose,x.pose
expect 0 "wave.amplitude 0.6 A held" set wave.amplitude 0.6
expect 4 "wave start above wave.limit (0.5 A) refused (03)" set wave.control 1
[ "$(val wave.state)" = 0 ] && [ "$(val wave.error)" = 4 ] && pass "nothing started (wave.error 4 amplitude)" || fail "wave.state $(val wave.state) error $(val wave.error)"
expect 0 "wave.amplitude 0.05 A" set wave.amplitude 0.05
expect 0 "wave.shape sweep" set wave.shape 1
expect 0 "wave.duration 2 s" set wave.duration 2
expect 0 "wave.f_end 1300 Hz" set wave.f_end 1300
expect 4 "sweep past Nyquist refused (03)" set wave.control 1
[ "$(val wave.state)" = 0 ] && [ "$(val wave.error)" = 6 ] && pass "nothing started (wave.error 6 Nyquist)" || fail "wave.state $(val wave.state) error $(val wave.error)"
expect 0 "wave.f_end back to 400 Hz" set wave.f_end 400

# 4b. A reference injection: 2 um 20 Hz sine on x's reference for 1.5 s,
# recorded: the injected reference and x following it.
expect 0 "wave: x reference sine 2 um 20 Hz 1.5 s" set wave.point 1
expect 0 "wave.shape sine" set wave.shape 0
expect 0 "wave.amplitude 2 um" set wave.amplitude 2e-6
expect 0 "wave.f_start 20 Hz" set wave.f_start 20
expect 0 "wave.duration 1.5 s" set wave.duration 1.5
expect 0 "wave start" set wave.control 1
expect 0 "record the reference injection" record --out "$WORK/refinj" --duration 0.5 --channels x.ref_injection,x.pose,x.reference
$PY - "$WORK/refinj/record.csv" <<'PYEOF' && pass "reference injection: 2 um peak at 20 Hz, x follows it" || fail "reference injection content"
import csv, sys, math
rows = list(csv.reader(open(sys.argv[1])))
col = {h: [float(r[i]) for r in rows[1:]] for i, h in enumerate(rows[0])}
inj, x = col["x.ref_injection"], col["x.pose"]
assert abs(max(inj) - 2e-6) < 0.05e-6 and abs(min(inj) + 2e-6) < 0.05e-6, (max(inj), min(inj))
assert len(set(col["x.reference"])) == 1, "the stored reference moved"
n = len(x); mx = sum(x) / n
# x's 20 Hz component (the loop tracks the injected reference; |T(20 Hz)| ~ 1.2)
c = sum((x[i] - mx) * math.cos(2 * math.pi * 20 * i / 2500) for i in range(n)) * 2 / n
s_ = sum((x[i] - mx) * math.sin(2 * math.pi * 20 * i / 2500) for i in range(n)) * 2 / n
a = math.hypot(c, s_)
print(f"x 20 Hz amplitude {a * 1e6:.3f} um for a 2 um reference sine")
assert 1.0e-6 < a < 4e-6, a
PYEOF
sleep 1.2
[ "$(val wave.state)" = 2 ] && pass "generator finished after its duration (wave.state 2)" || fail "wave.state $(val wave.state), expected 2"
expect 0 "wave.point back to effort" set wave.point 0

# 5. frf x against the bench's own figures.
expect 0 "frf x" frf x --out "$WORK/frf"
grep -q "measuring:" "$WORK/last.out" && pass "frf progress printed" || fail "no frf progress"
$PY - "$WORK/frf/frf.csv" "$WORK/frf/frf_margins.json" "$BENCH_FC" "$BENCH_PM" <<'PYEOF' && pass "frf: within 1 Hz / 2 deg of the bench" || fail "frf vs bench"
import csv, json, sys
rows = list(csv.reader(open(sys.argv[1])))
assert rows[0] == ["f_Hz", "open_loop_gain_db", "open_loop_phase_deg", "closed_loop_gain_db", "closed_loop_phase_deg", "coherence"], rows[0]
data = [[float(x) for x in r] for r in rows[1:]]
assert len(data) >= 20, len(data)
# Near crossover the estimate is clean; at the lowest lines |S| is small (high
# loop gain: u + d ~ 0), so noise weighs more there.
assert min(r[5] for r in data if 20 <= r[0] <= 200) > 0.95, "coherence below 0.95 between 20 and 200 Hz"
assert min(r[5] for r in data) > 0.5, "coherence below 0.5"
m = json.load(open(sys.argv[2]))
fc, pm = m["crossover_Hz"], m["phase_margin_deg"]
bfc, bpm = float(sys.argv[3]), float(sys.argv[4])
print(f"stagectl frf x: crossover {fc:.2f} Hz, PM {pm:.2f} deg; bench {bfc:.2f} Hz, {bpm:.2f} deg; "
      f"gain margin {m['gain_margin_dB']} dB at {m['phase_crossover_Hz']} Hz, bandwidth {m['closed_loop_bandwidth_Hz']} Hz")
assert abs(fc - bfc) <= 1.0, (fc, bfc)
assert abs(pm - bpm) <= 2.0, (pm, bpm)
PYEOF
cat "$WORK/last.out" | grep "crossover" || true
[ "$(val wave.state)" = 0 ] && pass "generator stopped after frf" || fail "wave.state $(val wave.state) after frf"
[ "$(val status.state)" = 6 ] && pass "still ready after frf" || fail "state $(val status.state) after frf"
expect 0 "land" --wait 30 land
finish
