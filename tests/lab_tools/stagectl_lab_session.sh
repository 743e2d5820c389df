#!/usr/bin/env bash
# stagectl's lab features against the running bench (MAGLEV_TCP=HOST:PORT, set by
# with_serve.sh): --json on get/status/dump/registers (parsed by python3's json),
# watch (plain blocks off a terminal, in place with ANSI on one, JSON lines with
# --json; --count/--interval), progress on stderr for --wait home/levitate/move/land.
# usage: stagectl_lab_session.sh STAGECTL WORKDIR
set -u
STAGECTL=$1; WORK=$2
mkdir -p "$WORK"
S() { "$STAGECTL" --tcp "$MAGLEV_TCP" "$@"; }
fails=0; passes=0
fail() { fails=$((fails + 1)); echo "FAIL: $*"; }
pass() { passes=$((passes + 1)); echo "ok:   $*"; }
# check TEXT PYTHON-EXPR FILE: the expression (j = the parsed JSON of FILE) must be true.
check() {
  if /usr/bin/python3 -c "import json,sys; j=json.load(open('$3')); sys.exit(0 if ($2) else 1)" 2>"$WORK/py.err"; then
    pass "$1"
  else
    fail "$1: $(cat "$WORK/py.err") in: $(head -c 600 "$3")"
  fi
}

S --json get status.state >"$WORK/get.json" && check "get --json" 'j == {"name": "status.state", "value": 0, "unit": ""}' "$WORK/get.json"
S --json status >"$WORK/status.json" &&
  check "status --json" 'j["state_name"] == "Idle" and j["fault_name"] == "None" and sorted(j["pose"]) == sorted(["x","y","z","theta_x","theta_y","theta_z"]) and "unsaved" in j["persist"]' "$WORK/status.json"
"$STAGECTL" --json registers >"$WORK/registers.json" &&
  check "registers --json (no connection needed)" 'len(j) > 100 and j[0]["name"] == "id.magic" and j[0]["default"] == 19788 and all(set(r) >= {"address","type","unit","min","max","access","writable_when"} for r in j)' "$WORK/registers.json"
S --json dump >"$WORK/dump.json" &&
  check "dump --json: every value register of registers --json (the bench serves the lab registers; download windows are not values)" "list(j) == [r['name'] for r in json.load(open('$WORK/registers.json')) if r['type'] != 'block'] and j['id.magic'] == 19788 and 'rec.state' in j" "$WORK/dump.json"

# watch off a terminal: --count blocks, state and fault named.
S --count 3 --interval 0.05 watch >"$WORK/watch.txt"; rc=$?
n=$(grep -c "^stagectl watch" "$WORK/watch.txt")
[ "$rc" = 0 ] && [ "$n" = 3 ] && grep -q "status.state = 0  (Idle)" "$WORK/watch.txt" && grep -q "status.fault = 0  (None)" "$WORK/watch.txt" &&
  ! grep -q $'\033' "$WORK/watch.txt" && pass "watch --count 3: 3 plain blocks" || fail "watch (exit $rc, $n blocks): $(cat "$WORK/watch.txt")"
# watch on a terminal (script(1) gives it a pty): the block is rewritten in place.
script -qec "$STAGECTL --tcp $MAGLEV_TCP --count 3 --interval 0.05 watch status.z status.state" /dev/null >"$WORK/watch.tty" 2>&1
ups=$(grep -o $'\033\\[3A' "$WORK/watch.tty" | wc -l)
[ "$ups" = 2 ] && grep -q $'\033\\[K' "$WORK/watch.tty" && pass "watch on a terminal: 2 in-place refreshes (ESC[3A)" ||
  fail "watch on a terminal: $ups cursor-ups: $(cat -v "$WORK/watch.tty")"
# watch --json: one object per refresh, t rising by about the interval.
S --json --count 4 --interval 0.1 watch status.z status.moving >"$WORK/watch.jsonl"
/usr/bin/python3 - "$WORK/watch.jsonl" <<'PY' && pass "watch --json: 4 JSON lines, interval ~0.1 s" || fail "watch --json: $(cat "$WORK/watch.jsonl")"
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert len(rows) == 4, rows
assert all(set(r) == {"t", "status.z", "status.moving"} for r in rows)
dt = [b["t"] - a["t"] for a, b in zip(rows, rows[1:])]
assert all(0.08 < d < 0.5 for d in dt), dt
PY
S --count 0 watch >/dev/null 2>&1; [ $? = 1 ] && pass "--count 0 is a usage error (exit 1)" || fail "--count 0 accepted"
S watch status.w >/dev/null 2>&1; [ $? = 3 ] && pass "watch of an unknown register: exit 3" || fail "watch status.w"

# Progress on stderr while waiting (stdout stays clean).
S --wait 20 home >"$WORK/home.out" 2>"$WORK/home.err"; rc=$?
[ "$rc" = 0 ] && grep -q "home: .* Idle (done)" "$WORK/home.err" && [ ! -s "$WORK/home.out" ] && pass "home --wait progress" ||
  fail "home --wait (exit $rc): $(cat "$WORK/home.err")"
S --wait 20 levitate 2>"$WORK/lev.err"; rc=$?
[ "$rc" = 0 ] && grep -q "levitate: .* Lift" "$WORK/lev.err" && grep -q "levitate: .* Ready (done)" "$WORK/lev.err" &&
  pass "levitate --wait shows the sequence: $(tr '\n' '|' <"$WORK/lev.err")" || fail "levitate --wait (exit $rc): $(cat "$WORK/lev.err")"
S --wait 20 move-by x 1mm 2>"$WORK/move.err"; rc=$?
[ "$rc" = 0 ] && grep -q "move x: .* um to go (done)" "$WORK/move.err" && pass "move --wait progress" ||
  fail "move --wait (exit $rc): $(cat "$WORK/move.err")"
S --json status >"$WORK/status2.json" && check "status --json while levitated" 'j["state_name"] == "Ready" and j["pose"]["z"] > 20e-6' "$WORK/status2.json"
S --wait 20 land 2>"$WORK/land.err"; rc=$?
[ "$rc" = 0 ] && grep -q "land: .* Landing" "$WORK/land.err" && grep -q "land: .* Idle (done)" "$WORK/land.err" && pass "land --wait progress" ||
  fail "land --wait (exit $rc): $(cat "$WORK/land.err")"

# config export/import: progress on stderr (a line per quarter), the result on stdout.
S config export "$WORK/cfg.txt" >"$WORK/export.out" 2>"$WORK/export.err"; rc=$?
[ "$rc" = 0 ] && [ "$(grep -c "config export: " "$WORK/export.err")" = 4 ] && grep -Eq "config export: .* ([0-9]+)/\1 read$" "$WORK/export.err" &&
  grep -q "^exported" "$WORK/export.out" && pass "config export progress" || fail "config export (exit $rc): $(cat "$WORK/export.err")"
S --engineer config import "$WORK/cfg.txt" >"$WORK/import.out" 2>"$WORK/import.err"; rc=$?
[ "$rc" = 0 ] && grep -Eq "config import: .* ([0-9]+)/\1 written$" "$WORK/import.err" && grep -q "^imported" "$WORK/import.out" &&
  pass "config import progress" || fail "config import (exit $rc): $(cat "$WORK/import.err")"

echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
