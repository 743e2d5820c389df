#!/bin/sh
# Issue 15 item 5 on the bench: calibrate_coupling refused when not levitated,
# refused while one runs, abandoned by another command (nothing kept), passed
# with its verification on an as-built error seed; `run --calibrate` cuts the
# coupling-driven CCQ of ccq_y_step_2um (theta_z after a y step) and leaves
# the default scenario untouched.
#   usage: calibration_bench.sh MAGLEV_HIL SOURCE_DIR OUT_DIR PYTHON3
set -u
HIL="$1"; DIR="$2"; OUT="$3"; PY="$4"
rm -rf "$OUT"; mkdir -p "$OUT"
fail() { echo "FAIL: $*"; exit 1; }
"$HIL" run "$DIR/calibrate.scenario" --out "$OUT/cal" --no-plots --quiet > "$OUT/cal.log" 2>&1 ||
  { cat "$OUT/cal.log"; fail "run calibrate.scenario"; }
C="$OUT/cal/commands.txt"
grep -q "^0.0000  calibrate_coupling  -> refused: not ready" "$C" || { cat "$C"; fail "not refused before levitation"; }
grep -q "^4.5000  calibrate_coupling  -> accepted" "$C" || { cat "$C"; fail "not accepted in Ready"; }
grep -q "^4.6000  calibrate_coupling  -> refused: busy" "$C" || { cat "$C"; fail "second request not refused while running"; }
grep -q "^7.0000  calibrate_coupling  -> accepted" "$C" || { cat "$C"; fail "restart not accepted"; }
for s in 1 2; do
  "$HIL" run ccq_y_step_2um --error-seed 3 --out "$OUT/y$s" --no-plots --quiet $([ $s = 2 ] && echo --calibrate) \
    > "$OUT/y$s.log" 2>&1 || { cat "$OUT/y$s.log"; fail "ccq_y_step_2um run $s"; }
done
"$PY" - "$OUT" <<'PYEOF' || exit 1
import json, sys
out = sys.argv[1]
m = json.load(open(f"{out}/cal/metrics.json"))
assert m["calibration_result"] == 2, f"calibration result {m['calibration_result']} (2 = Passed)"
b, a = m["calibration_coupling_before"], m["calibration_coupling_after"]
# as-built error seed 3: ~0.11 scaled coupling identified; verified with C applied
assert b > 0.02, f"coupling before {b}: the as-built stage has coupling to find"
assert a * 10 < b, f"coupling after {a} not 10x below {b}"
assert m["calibration_inconsistency"] < 0.05, m["calibration_inconsistency"]
un = json.load(open(f"{out}/y1/metrics.json"))
ca = json.load(open(f"{out}/y2/metrics.json"))
cal = json.load(open(f"{out}/y2/calibration/metrics.json"))
assert "coupling_correction_loaded" not in un, "uncalibrated run loaded a correction"
assert ca["coupling_correction_loaded"] == 1 and cal["calibration_result"] == 2
k = "y_step_2um_ccq_theta_z_rad_s_per_m"
print(f"calibration: coupling {b:.4g} -> {a:.4g}; ccq_y_step_2um {k}: {un[k]:.4g} -> {ca[k]:.4g}")
# theta_z after a y step is the CoM offset's coupling (docs/PERFORMANCE.md):
# measured 8.2x on seed 3; the calibrated value sits at the quantization floor.
assert ca[k] * 4 < un[k], f"{k}: {un[k]} -> {ca[k]} (< 4x)"
for key in ("y_step_2um_ccq_x_s", "y_step_2um_ccq_theta_y_rad_s_per_m"):
    assert ca[key] <= un[key] * 1.5, f"{key} got worse: {un[key]} -> {ca[key]}"
PYEOF
echo "calibration bench: ok"
