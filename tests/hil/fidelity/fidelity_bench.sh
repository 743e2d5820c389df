#!/bin/sh
# Issue 15 on the bench: [plant] refusals as file:line: key: reason, the drawn
# errors in metrics.json (reproducible per error seed), as-built coupling
# above rest noise and above the nominal stage's, ideal unchanged.
#   usage: fidelity_bench.sh MAGLEV_HIL SOURCE_DIR OUT_DIR PYTHON3
. "$2/bench_lib.sh"
expect bad_plant.scenario "bad_plant.scenario:8: coil_yaw_rad: 0.02 is above its physical bound"
expect bad_plant.scenario "bad_plant.scenario:9: com_xy_m: a magnitude, must be >= 0"
expect bad_plant.scenario "bad_plant.scenario:10: amp_gain_error: not a number: 'lots'"
expect bad_plant.scenario "bad_plant.scenario:11: error_scale: must be within \[0, 2\]"
expect bad_model.scenario "bad_model.scenario:7: model: expected default, ideal, nominal or as-built, got 'as_bilt'"
expect bad_model.scenario "bad_model.scenario:8: noise: expected component or fitted, got 'quiet'"
expect bad_nominal.scenario "bad_nominal.scenario:8: bstar_error: an error-set key needs model = as-built"
refused_option fidelity_move.scenario "$OUT/x" "--plant: expected default, ideal, nominal or as-built, got 'bogus'" --plant bogus
# An error seed on a plant that draws no errors changed nothing, silently.
refused_option fidelity_move.scenario "$OUT/x" "--error-seed 3: the plant model is nominal" --plant nominal --error-seed 3
echo "refusals: ok"
run() {  # run NAME ARGS...: a run into OUT/NAME
  name=$1; shift
  "$HIL" run "$DIR/fidelity_move.scenario" --out "$OUT/$name" --no-plots --quiet "$@" > "$OUT/$name.log" 2>&1 ||
    { cat "$OUT/$name.log"; fail "run $name"; }
}
run seed3a --error-seed 3
run seed3b --error-seed 3
run seed4 --error-seed 4
run nominal --plant nominal
# The issue's 2-5 mm CoM band: error seed 5 lifts to theta_x -230 urad, beyond
# the +-200 urad reference range; TiltLock ramps the reference in, so the
# 0.1 urad steps are accepted (they were refused as out of range before).
"$HIL" run "$DIR/../../../hil/scenarios/theta_x_steps.scenario" --plant as-built --error-seed 5 --out "$OUT/level" \
  --no-plots --quiet > "$OUT/level.log" 2>&1 || { cat "$OUT/level.log"; fail "run level"; }
[ "$(grep -c 'step theta_x 0.1urad  -> accepted' "$OUT/level/commands.txt")" = 2 ] ||
  { cat "$OUT/level/commands.txt"; fail "as built, CoM band 2-5 mm: theta_x steps not accepted"; }
"$HIL" run "$DIR/../bench/short.scenario" --plant ideal --out "$OUT/ideal" --no-plots --quiet > "$OUT/ideal.log" 2>&1 ||
  { cat "$OUT/ideal.log"; fail "run ideal"; }
# `ideal` is of the stage the run names (it was always the default stage's:
# the square kernel on the cross plant faulted, fault 6).
"$HIL" run startup --profile nk2020-square --plant ideal --out "$OUT/square_ideal" --no-plots --quiet \
  > "$OUT/square_ideal.log" 2>&1 || { cat "$OUT/square_ideal.log"; fail "run square ideal"; }
grep -q "final state Ready, fault 0" "$OUT/square_ideal.log" ||
  { cat "$OUT/square_ideal.log"; fail "--profile nk2020-square --plant ideal: not Ready"; }
"$PY" - "$OUT" <<'PYEOF' || exit 1
import json, sys
out = sys.argv[1]
m = {n: json.load(open(f"{out}/{n}/metrics.json")) for n in ("seed3a", "seed3b", "seed4", "nominal", "ideal")}
def errors(d): return {k: v for k, v in d.items() if k.startswith("plant_error_")}
a, b, c = errors(m["seed3a"]), errors(m["seed3b"]), errors(m["seed4"])
assert len(a) >= 70, f"only {len(a)} drawn errors recorded"
for key in ("plant_error_amp1_gain_error", "plant_error_coil8_position_m", "plant_error_forcer4_bstar_error",
            "plant_error_com_height_m", "plant_error_x_mirror_yaw_rad", "plant_error_lds3_dy_m",
            "plant_error_ixy_kgm2", "plant_error_magnet_pitch_error", "plant_error_error_seed"):
    assert key in a, f"{key} not in metrics.json"
assert a == b, "the same error seed drew different errors"
assert a["plant_error_error_seed"] == 3 and c["plant_error_error_seed"] == 4
assert sum(a[k] != c[k] for k in a) > 60, "another error seed drew the same errors"
assert m["seed3a"]["plant_model"] == 3 and m["nominal"]["plant_model"] == 2
assert not errors(m["nominal"]), "nominal recorded drawn errors"
assert m["ideal"]["plant_model"] == 1 and not errors(m["ideal"])
assert m["ideal"]["completed"] == 1
import csv
rows = list(csv.DictReader(open(f"{out}/level/trace.csv")))
tiltlock = [float(r["theta_x_rad"]) for r in rows if r["state"] == "5"]
ready = [float(r["theta_x_ref_rad"]) for r in rows if r["state"] == "6"]
assert tiltlock and tiltlock[0] < -210e-6, f"error seed 5 captured theta_x {tiltlock[:1]}: not beyond the range"
assert ready and all(-200.0001e-6 <= v <= 200.0001e-6 for v in ready), "a Ready theta_x reference outside +-200 urad"
print(f"levelling: captured theta_x {tiltlock[0]*1e6:.1f} urad, Ready reference {ready[0]*1e6:.1f} urad")
# As built couples: theta_y p-p during the move well above its rest p-p and
# above the nominal stage's (thrust below the raised CoM, roll, b* spread).
for n in ("seed3a", "seed4"):
    pp, rest = m[n]["move_pp_theta_y_rad"], m[n]["move_rest_pp_theta_y_rad"]
    assert m[n]["completed"] == 1 and m[n]["final_sequencer_state"] == m["nominal"]["final_sequencer_state"]
    assert pp > 5 * rest, f"{n}: theta_y p-p {pp} not above 5x rest {rest}"
    assert pp > 3 * m["nominal"]["move_pp_theta_y_rad"], f"{n}: theta_y p-p {pp} vs nominal {m['nominal']['move_pp_theta_y_rad']}"
    print(f"{n}: theta_y p-p {pp:.3g} rad, rest {rest:.3g}, nominal {m['nominal']['move_pp_theta_y_rad']:.3g}")
print("metrics.json: ok")
PYEOF
# The LDS target's block steps (issue 15): the 14 mm move over the target as
# drawn ends Ready with the kernel's repair, and lands without it.
for n in fidelity_move_target fidelity_move_target_off; do
  "$HIL" run "$DIR/$n.scenario" --out "$OUT/$n" --no-plots --quiet > "$OUT/$n.log" 2>&1 ||
    { cat "$OUT/$n.log"; fail "run $n"; }
done
"$PY" - "$OUT" <<'PYEOF' || exit 1
import json, sys
out = sys.argv[1]
on = json.load(open(f"{out}/fidelity_move_target/metrics.json"))
off = json.load(open(f"{out}/fidelity_move_target_off/metrics.json"))
assert on["final_sequencer_state"] == 6 and on["fault_code"] == 0, f"repair on: state {on['final_sequencer_state']}, fault {on['fault_code']}"
assert on.get("lds_target_steps_repaired", 0) >= 1, "repair on: no target step repaired"
assert off["fault_code"] != 0 and "lds_target_steps_repaired" not in off, "repair off: the move did not fault on the target steps"
print(f"LDS target steps: repaired {on['lds_target_steps_repaired']:.0f}, Ready; off: fault {off['fault_code']:.0f}")
PYEOF
# z as the mean of the three height sensors (paper 003 Table 5): reported
# beside the kernel's z, equal to the trace's z + y_c theta_x - x_c theta_y;
# a kernel regulating that mean ([controller] z_point) pulls it back.
sc="$DIR/../../../hil/scenarios/ccq_theta_x_trapezoid.scenario"
sed 's/^\[timeline\]$/[controller]\nz_point = sensor_centroid\n\n[timeline]/' "$sc" > "$OUT/zmean.scenario"
sed 's/^\[timeline\]$/[controller]\nz_point = middle\n\n[timeline]/' "$sc" > "$OUT/zbad.scenario"
out=$("$HIL" check "$OUT/zbad.scenario" 2>&1) && fail "z_point = middle accepted"
echo "$out" | grep -q "z_point = middle: expected centre or sensor_centroid" || { echo "$out"; fail "z_point refusal"; }
"$HIL" run "$sc" --error-seed 1 --out "$OUT/zc" --no-plots --quiet > "$OUT/zc.log" 2>&1 || { cat "$OUT/zc.log"; fail "run zc"; }
"$HIL" run "$OUT/zmean.scenario" --error-seed 1 --out "$OUT/zm" --no-plots --quiet > "$OUT/zm.log" 2>&1 ||
  { cat "$OUT/zm.log"; fail "run zm"; }
"$PY" - "$OUT" <<'PYEOF' || exit 1
import csv, json, sys
out = sys.argv[1]
c, k = (json.load(open(f"{out}/{n}/metrics.json")) for n in ("zc", "zm"))
xc, yc = -0.0615 / 3, 0.0615 / 3  # nk2017-cross: sensors at (a, a), (-a, a), (-a, -a), a = 61.5 mm
rows = [r for r in csv.DictReader(open(f"{out}/zc/trace.csv")) if 6.0 <= float(r["t_s"]) <= 7.3]
zm = [float(r["z_m"]) + yc * float(r["theta_x_rad"]) - xc * float(r["theta_y_rad"]) for r in rows]
pp = c["theta_x_move1_pp_z_sensor_mean_m"]
assert abs((max(zm) - min(zm)) - pp) < 2e-9, f"sensor mean p-p {pp} vs trace {max(zm) - min(zm)}"
assert 0.8 * 148e-6 * yc < pp < 1.2 * 148e-6 * yc, f"sensor mean p-p {pp}: not 20.5 mm x 148 urad"
assert c["theta_x_move1_pp_z_m"] < 0.05 * pp, "the kernel's z (centre) moved with the tilt"
assert k["theta_x_move1_pp_z_sensor_mean_m"] == k["theta_x_move1_pp_z_m"], "z_point = sensor_centroid: offset counted twice"
assert k["theta_x_move1_pp_z_m"] < 0.2 * pp, f"a kernel regulating the mean left {k['theta_x_move1_pp_z_m']}"
print(f"z as the sensors' mean: p-p {pp:.3g} m (kernel z {c['theta_x_move1_pp_z_m']:.3g}); regulated: {k['theta_x_move1_pp_z_m']:.3g}")
PYEOF
# run --seeds prints the z entries with the paper's z read as the sensors' mean, and both counts.
"$HIL" run "$sc" --seeds 2 --out "$OUT/zs" --no-plots > "$OUT/zs.log" 2>&1 || { cat "$OUT/zs.log"; fail "run zs"; }
grep -Eq "theta_x_move1_ccq_z_m_s_per_rad .* within  \(z as the height sensors' mean\)" "$OUT/zs.log" ||
  { cat "$OUT/zs.log"; fail "run --seeds: no sensor-mean z line"; }
grep -Eq "^  [0-9]+ of 10 with the paper's z read as the mean of its three height sensors" "$OUT/zs.log" ||
  { cat "$OUT/zs.log"; fail "run --seeds: no sensor-mean count"; }
# Verdicts against the paper are a ratio with a band, never "<= paper"; a
# rest noise from the fitted density says so (the default plant's).
sc="$DIR/../../../hil/scenarios/x_steps_10nm.scenario"
"$HIL" run "$sc" --out "$OUT/v_default" --no-plots > "$OUT/v_default.log" 2>&1 || { cat "$OUT/v_default.log"; fail "run v_default"; }
"$HIL" run "$sc" --plant as-built --out "$OUT/v_asbuilt" --no-plots > "$OUT/v_asbuilt.log" 2>&1 ||
  { cat "$OUT/v_asbuilt.log"; fail "run v_asbuilt"; }
grep -q "<= paper" "$OUT/v_default.log" "$OUT/v_asbuilt.log" && fail "a '<= paper' verdict"
grep -Eq "x_rest_rms_noise_m .*ratio [0-9.]+ \(within 0.5-2x\) FITTED \(noise = fitted\)" "$OUT/v_default.log" ||
  { cat "$OUT/v_default.log"; fail "the default plant's rest noise is not labelled fitted"; }
grep -Eq "x_rest_rms_noise_m .*ratio 0\.[0-9]+ \(OUTSIDE 0.5-2x, below\)$" "$OUT/v_asbuilt.log" ||
  { cat "$OUT/v_asbuilt.log"; fail "the as-built rest noise verdict"; }
grep -q "FITTED" "$OUT/v_asbuilt.log" && fail "component noise labelled fitted"
echo "verdicts: ok"
echo "hil_fidelity_bench: passed"
