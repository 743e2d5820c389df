#!/bin/sh
# maglev-hil run/suite --profile jb2002-selfstab reach the paper-001 bench:
# a lift-off run writes its metrics and trace and passes its verdicts; an
# unknown experiment is refused with the list.
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
echo "ok: paper-001 bench from the command line"
