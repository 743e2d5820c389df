#!/bin/sh
# Scenario files that once bypassed the controller's limits (issue 17):
# every one is refused before anything runs (exit 2, a message naming the
# field), and the bench's own excitation cannot push a coil past its limit.
set -u
HIL=$1; OUT=$2
rm -rf "$OUT"; mkdir -p "$OUT/work"
pass=0; fail=0
ok() { pass=$((pass + 1)); echo "ok: $*"; }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

refused() {  # NAME EXPECTED-TEXT, scenario body on stdin
  f="$OUT/$1.scenario"; cat > "$f"
  out=$("$HIL" run "$f" --out "$OUT/work/$1" --no-plots --quiet 2>&1); rc=$?
  if [ $rc -eq 2 ] && echo "$out" | grep -q "$2" && [ ! -e "$OUT/work/$1/trace.csv" ]; then ok "$1 refused: $2"
  else bad "$1: exit $rc: $out"; fi
}

refused name_traversal "name '../../x'" <<'S'
[scenario]
name = ../../x
duration_s = 0.1
[timeline]
0.0 levitate
S
[ ! -e "$OUT/../x" ] && [ ! -e "$OUT/x" ] && ok "nothing written outside --out" || bad "a file outside --out"

refused huge_gain "z.kp = 1e30: outside gain.z.kp" <<'S'
[scenario]
name = huge_gain
duration_s = 0.1
[controller]
z.kp = 1e30
[timeline]
0.0 levitate
S

refused off_the_stage "initial_x_m = 1: outside the travel" <<'S'
[scenario]
name = off_the_stage
duration_s = 0.1
[plant]
initial_x_m = 1
[timeline]
0.0 levitate
S

# The bench's multisine at 2 A per tone on top of the controller: the coils
# stay at or below the 4 A peak (it once drove 5.0 A).
cat > "$OUT/big_excite.scenario" <<'S'
[scenario]
name = big_excite
duration_s = 5.5
[timeline]
0.0 levitate
3.0 excite x 2A 5Hz 50Hz 2s 4
[metrics]
currents 3.0 5.0 excite
S
"$HIL" run "$OUT/big_excite.scenario" --out "$OUT/work/big_excite" --no-plots --quiet > "$OUT/big_excite.log" 2>&1
/usr/bin/python3 - "$OUT/work/big_excite/metrics.json" <<'PY' && ok "excitation kept inside the peak coil current" || bad "excitation beyond the coil limit"
import json, sys
m = json.load(open(sys.argv[1]))
peak = m["excite_peak_coil_current_A"]
print(f"peak coil current under a 2 A-per-tone excitation: {peak:.3f} A (limit 4 A)")
sys.exit(0 if peak <= 4.0 + 0.05 else 1)   # 0.05 A: amplifier loop overshoot and noise
PY
echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
