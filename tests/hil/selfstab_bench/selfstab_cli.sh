#!/bin/sh
# maglev-hil run/suite --profile jb2002-selfstab reach the paper-001 bench:
# a lift-off run writes its metrics and trace and passes its verdicts; an
# unknown experiment is refused with the list; list, check-profile and
# profiles know the family.
set -u
HIL=$1; OUT=$2
rm -rf "$OUT"; mkdir -p "$OUT"
"$HIL" run lift_off --profile jb2002-selfstab --out "$OUT/lift" > "$OUT/lift.log" 2>&1
rc=$?
cat "$OUT/lift.log"
[ $rc -eq 0 ] || { echo "FAIL: run lift_off exited $rc"; exit 1; }
grep -q "2 of 2 verdicts pass" "$OUT/lift.log" || { echo "FAIL: verdicts"; exit 1; }
[ -s "$OUT/lift/metrics.json" ] && [ -s "$OUT/lift/lift_off/trace.csv" ] || { echo "FAIL: no metrics/trace"; exit 1; }
/usr/bin/python3 - "$OUT/lift/metrics.json" <<'PY' || { echo "FAIL: metrics"; exit 1; }
import json, sys
m = json.load(open(sys.argv[1]))
assert m["lift_off.levitated"] == 1, m
assert abs(m["lift_off.final_z_error_m"]) < 1.1475e-6, m
assert m["lift_off.final_z_error_m"] >= 0
PY
if "$HIL" run no_such_experiment --profile jb2002-selfstab --out "$OUT/x" > "$OUT/bad.log" 2>&1; then
  echo "FAIL: an unknown experiment ran"; exit 1
fi
grep -q "free_vibration" "$OUT/bad.log" || { echo "FAIL: the refusal does not list the experiments"; cat "$OUT/bad.log"; exit 1; }
"$HIL" list --profile jb2002-selfstab > "$OUT/list.txt" 2>&1 || { echo "FAIL: list"; exit 1; }
for e in free_vibration z_step_10um z_step_100um lift_off schedule_margins filter_cost ours; do
  grep -q "$e" "$OUT/list.txt" || { echo "FAIL: list does not name $e"; exit 1; }
done
"$HIL" check-profile jb2002-selfstab > "$OUT/check.txt" 2>&1 || { echo "FAIL: check-profile"; cat "$OUT/check.txt"; exit 1; }
grep -q "selfstab kernel (paper 001): accepts this profile" "$OUT/check.txt" || { echo "FAIL: check-profile verdict"; exit 1; }
"$HIL" profiles | grep -q "jb2002-selfstab *runs" || { echo "FAIL: profiles"; exit 1; }
echo "ok: paper-001 bench from the command line"
