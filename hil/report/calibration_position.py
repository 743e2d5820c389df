#!/usr/bin/env python3
"""Does a coupling calibration made at home hold away from home? (issue 15, item 5)

For each error seed and each x offset: levitate, level, calibrate_coupling at home (the
kernel keeps its correction), move x by the offset, calibrate_coupling again. The second
calibration's "coupling before" is the coupling left with the home correction applied, at
the new position (docs/KERNEL.md "Coupling calibration": with C0 active the identified plant
is M C0). The LDS target is flat here (target_cell_height_m = 0): its steps are a sensor
error that trips the tilt envelope on mm moves, not the actuator coupling measured here.

  usage: calibration_position.py MAGLEV_HIL OUT_DIR [--seeds N] [--plant as-built|nominal|ideal]
"""
import json
import os
import subprocess
import sys

OFFSETS_MM = [0.0, 3.175, 6.35, 9.525, 12.7]

SCENARIO = """[scenario]
name = calibration_at_x
title = coupling left at x + {d} mm after a calibration at home
duration_s = 72
primary = x
seed = 1

[plant]
model = {plant}
{errors}
[timeline]
0.0 levitate
2.5 move_to theta_x 0urad 1mrad/s 10mrad/s^2
2.5 move_to theta_y 0urad 1mrad/s 10mrad/s^2
4.5 calibrate_coupling
36.0 {move}
38.0 calibrate_coupling
"""


def main():
    args = sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    hil, out = args[0], args[1]
    seeds = int(args[args.index("--seeds") + 1]) if "--seeds" in args else 3
    plant = args[args.index("--plant") + 1] if "--plant" in args else "as-built"
    os.makedirs(out, exist_ok=True)
    rows = []
    for seed in range(1, seeds + 1) if plant == "as-built" else [0]:
        for d in OFFSETS_MM:
            errors = f"error_seed = {seed}\ntarget_cell_height_m = 0\n" if plant == "as-built" else ""
            move = "hold" if d == 0.0 else f"move x {d}mm 70mm/s 0.7m/s^2"
            path = os.path.join(out, f"seed{seed}_x{d}.scenario")
            with open(path, "w") as f:
                f.write(SCENARIO.format(d=d, plant=plant, errors=errors, move=move))
            run_dir = os.path.join(out, f"seed{seed}_x{d}")
            subprocess.run([hil, "run", path, "--out", run_dir, "--no-plots", "--quiet"], check=False,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            m = json.load(open(os.path.join(run_dir, "metrics.json")))
            rows.append((seed, d, m.get("calibration_coupling_before", float("nan")),
                         m.get("calibration_result", -1), int(m.get("final_sequencer_state", -1)),
                         m.get("coupling_correction_54", float("nan"))))
    # The entry that moves with x: theta_x effort into theta_y (row theta_y, column theta_x).
    print("| error seed | x offset (mm) | coupling left with the home correction (scaled) | "
          "result of the 2nd calibration | final state | correction theta_y <- theta_x after it |")
    print("|---|---|---|---|---|---|")
    for seed, d, before, res, state, val in rows:
        print(f"| {seed if plant == 'as-built' else plant} | {d:g} | {before:.4f} | {int(res)} | {state} | {val:+.4f} |")


if __name__ == "__main__":
    main()
