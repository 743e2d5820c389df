#!/bin/sh
# Issue 15 on the bench: the floor under the base (docs/PLANT.md section 12).
# Refusals as file:line: key: reason; the floor in metrics.json; the in-plane
# rest noise it makes: far above the components' on a rigid base, linear in
# the class's velocity, and cut by an isolator.
#   usage: floor_bench.sh MAGLEV_HIL SOURCE_DIR OUT_DIR PYTHON3
. "$2/bench_lib.sh"
expect bad_floor.scenario "bad_floor.scenario:7: floor: expected none, workshop, office, residential, operating-theatre, vc-a, vc-b, vc-c, vc-d or vc-e, got 'vc-z'"
expect bad_floor.scenario "bad_floor.scenario:8: floor_isolator_hz: 0 (no isolator) or \[0.3, 20\] Hz"
expect bad_floor.scenario "bad_floor.scenario:9: floor_isolator_damping: 5 is outside \[0.01, 2\]"
expect bad_floor.scenario "bad_floor.scenario:10: floor_band_velocity_m_per_s: give floor or floor_band_velocity_m_per_s, not both"
expect bad_floor_velocity.scenario "bad_floor_velocity.scenario:7: floor_band_velocity_m_per_s: 0.01 is outside \[0, 2e-3\] m/s"
refused_option fidelity_floor.scenario "$OUT/x" "--floor: expected none, workshop, .* got 'basement'" --floor basement
refused_option fidelity_floor.scenario "$OUT/x" "--floor-isolator-hz: 0 (no isolator) or \[0.3, 20\] Hz, got 0.1" \
  --floor vc-c --floor-isolator-hz 0.1
# A bad scenario key is refused whatever --floor puts in its place.
refused_option bad_floor_velocity.scenario "$OUT/x" "bad_floor_velocity.scenario:7: floor_band_velocity_m_per_s: 0.01 is outside" \
  --floor vc-b
echo "refusals: ok"
# docs/PLANT.md's floor table is `maglev-hil floor-classes` (kFloorClasses, the one source).
"$HIL" floor-classes > "$OUT/floor_classes.md" || fail "floor-classes"
while IFS= read -r line; do
  grep -qxF -- "$line" "$DIR/../../../docs/PLANT.md" || fail "docs/PLANT.md lacks the floor-classes line: $line"
done < "$OUT/floor_classes.md"
echo "docs/PLANT.md floor table: ok"
run() {  # run NAME SCENARIO ARGS...
  name=$1; sc=$2; shift 2
  "$HIL" run "$DIR/$sc" --out "$OUT/$name" --no-plots --quiet "$@" > "$OUT/$name.log" 2>&1 ||
    { cat "$OUT/$name.log"; fail "run $name"; }
}
run none fidelity_floor.scenario
run vcd fidelity_floor.scenario --floor vc-d
run vcc fidelity_floor.scenario --floor vc-c
run table fidelity_floor_table.scenario
run table_cli fidelity_floor.scenario --floor vc-c --floor-isolator-hz 1.5
# The command line replacing the scenario's floor says so.
run table_over fidelity_floor_table.scenario --floor vc-d --floor-isolator-hz 2
grep -q "note: --floor vc-d replaces the scenario's \[plant\] floor = vc-c" "$OUT/table_over.log" ||
  fail "--floor replaced the scenario's floor silently"
grep -q "note: --floor-isolator-hz 2 replaces the scenario's \[plant\] floor_isolator_hz = 1.5" "$OUT/table_over.log" ||
  fail "--floor-isolator-hz replaced the scenario's isolator silently"
"$PY" - "$OUT" <<'PYEOF' || exit 1
import json, sys
out = sys.argv[1]
m = {n: json.load(open(f"{out}/{n}/metrics.json")) for n in ("none", "vcd", "vcc", "table")}
cli = json.load(open(f"{out}/table_cli/metrics.json"))
assert cli["x_rest_rms_noise_m"] == m["table"]["x_rest_rms_noise_m"], "--floor-isolator-hz is not the scenario key"
for n, d in m.items():
    assert d["completed"] == 1 and d["fault_code"] == 0 and d["final_sequencer_state"] == 6, f"{n}: not Ready"
assert not any(k.startswith("plant_floor_") for k in m["none"]), "no floor, yet plant_floor_* recorded"
assert m["vcc"]["plant_floor_band_velocity_m_per_s"] == 12.5e-6 and m["vcc"]["plant_floor_isolator_hz"] == 0
assert m["table"]["plant_floor_isolator_hz"] == 1.5 and m["table"]["plant_floor_isolator_damping"] == 0.1
over = json.load(open(f"{out}/table_over/metrics.json"))
assert over["plant_floor_band_velocity_m_per_s"] == 6.25e-6 and over["plant_floor_isolator_hz"] == 2
x = {n: d["x_rest_rms_noise_m"] for n, d in m.items()}
y = {n: d["y_rest_rms_noise_m"] for n, d in m.items()}
z = {n: d["z_rest_rms_noise_m"] for n, d in m.items()}
print("x rest rms (nm): " + ", ".join(f"{n} {v*1e9:.2f}" for n, v in x.items()))
print("y rest rms (nm): " + ", ".join(f"{n} {v*1e9:.2f}" for n, v in y.items()))
print("z rest rms (nm): " + ", ".join(f"{n} {v*1e9:.2f}" for n, v in z.items()))
# The floor moves vertically too: z's rest noise (the LDS's ~11 nm without
# a floor) grows on a rigid base, and the isolator takes most of it away.
assert z["vcc"] > 1.5 * z["none"], "VC-C on a rigid base adds no z noise"
assert z["table"] < z["none"] + 0.5 * (z["vcc"] - z["none"]), "the isolator did not cut the floor's z noise"
for r in (x, y):
    # A rigid base: the floor reaches the loops through S(f) and its 13 dB
    # peak near 45 Hz -- far above the components' ~0.5 nm.
    assert r["vcc"] > 20 * r["none"], "VC-C on a rigid base is not far above the component noise"
    # Linear in the class's velocity (the noise is the floor's: the
    # components add in quadrature, < 0.1 %).
    ratio = r["vcc"] / r["vcd"]
    assert 1.9 < ratio < 2.1, f"VC-C / VC-D = {ratio}, not 2"
    # A 1.5 Hz isolator: |T| ~ 0.0076 at 40 Hz.
    assert r["table"] < r["vcc"] / 20, "the isolator did not cut the floor's noise"
    assert r["table"] > r["none"], "the isolated floor adds nothing"
print("floor: ok")
PYEOF
echo "hil_fidelity_floor: passed"
