#!/bin/sh
# The profiles on the bench: listed, checked, and the paper's 8 um x step
# (<= 3.25 % overshoot, <= 0.32 s settling, paper 000) on every profile whose
# plant the bench builds; a malformed profile stops everything with
# file:line: field: reason.
set -u
HIL=$1; DIR=$2; OUT=$3
rm -rf "$OUT"; mkdir -p "$OUT"
pass=0; fail=0
ok() { pass=$((pass + 1)); echo "ok: $*"; }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }

list=$("$HIL" profiles) || bad "profiles exited non-zero"
echo "$list"
for p in nk2017-cross nk2020-square nk2020-triangle; do
  echo "$list" | grep -q "^  $p " && ok "$p listed" || bad "$p not listed"
  out=$("$HIL" check-profile "$p" 2>&1)
  echo "$out"
  echo "$out" | grep -q "allocation (active axes): rank 6" && ok "$p rank 6" || bad "$p rank"
  echo "$out" | grep -q "loop x        crossover" && ok "$p x loop margins" || bad "$p x loop"
  echo "$out" | grep -q "controller: accepts this profile" && ok "$p accepted" || bad "$p refused"
done

for p in nk2017-cross nk2020-square nk2020-triangle; do
  "$HIL" run x_steps_4um_8um --profile "$p" --out "$OUT/$p" --no-plots --quiet > "$OUT/$p.log" 2>&1 ||
    { bad "$p run failed"; cat "$OUT/$p.log"; continue; }
  grep -q "final state Ready, fault 0" "$OUT/$p.log" && ok "$p levitated (Ready, no fault)" || bad "$p not Ready"
  /usr/bin/python3 - "$OUT/$p/metrics.json" "$p" <<'PY' && ok "$p 8 um step within paper 000's figures" || bad "$p 8 um step"
import json, sys
m = json.load(open(sys.argv[1]))
o, s = m["x_step_8um_overshoot_percent"], m["x_step_8um_settling_time_s"]
print(f"{sys.argv[2]}: 8 um step overshoot {o:.3f} % (paper 3.25), settling {s:.4f} s (paper 0.32)")
sys.exit(0 if m["completed"] == 1 and o <= 3.25 and s <= 0.32 and m["fault_code"] == 0 else 1)
PY
done

# A malformed profile: every bad field reported, nothing runs.
cat > "$OUT/broken.profile" <<'PRO'
[stage]
name = broken
family = halbach_lorentz
servo_rate_Hz = 2500x
[body]
mass_kg = 0
PRO
out=$("$HIL" run x_steps_4um_8um --profile "$OUT/broken.profile" --out "$OUT/broken" --no-plots --quiet 2>&1); rc=$?
echo "$out"
[ $rc -ne 0 ] && ok "broken profile: non-zero exit" || bad "broken profile ran"
echo "$out" | grep -q "broken.profile:4: servo_rate_Hz: not a number" && ok "file:line: field: reason" || bad "no field message"
[ ! -e "$OUT/broken/trace.csv" ] && ok "nothing ran" || bad "a trace was written"

echo "$pass passed, $fail failed"
[ $fail -eq 0 ]
