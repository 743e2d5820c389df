#!/usr/bin/python3
"""Checks one maglev-hil run directory (tests/hil/bench): real outcomes, not just files."""
import csv
import json
import os
import sys

d = sys.argv[1]
m = json.load(open(os.path.join(d, "metrics.json")))
fails = []


def check(cond, what):
    if not cond:
        fails.append(what)


for k in ["real_time_factor", "bus_load_percent", "levitated", "z_final_height_m", "x_rest_rms_noise_m",
          "x_step_8um_overshoot_percent", "x_step_8um_settling_time_s", "run_peak_coil_current_A"]:
    check(k in m, f"metrics.json lacks {k}")
if not fails:
    check(m["levitated"] == 1, "did not reach Ready")
    check(abs(m["z_final_height_m"] - 30e-6) < 2e-6 and m["z_final_height_m"] <= 40e-6,
          f"z {m['z_final_height_m']} not at the 30 um nominal height (within 40 um)")
    check(0 < m["x_rest_rms_noise_m"] < 50e-9, f"x rest noise {m['x_rest_rms_noise_m']}")
    check(m["x_step_8um_settled"] == 1, "8 um step did not settle")
    check(m["x_step_8um_overshoot_percent"] < 10, f"overshoot {m['x_step_8um_overshoot_percent']}")
    check(m["x_step_8um_settling_time_s"] < 0.32, f"settling {m['x_step_8um_settling_time_s']}")
    check(abs(m["x_step_8um_measured_m"] - 8e-6) < 0.1e-6, f"measured step {m['x_step_8um_measured_m']}")
    check(0.5 < m["run_peak_coil_current_A"] < 4.0, f"peak current {m['run_peak_coil_current_A']}")
    check(m["real_time_factor"] > 1, f"real-time factor {m['real_time_factor']}")
    check(30 < m["bus_load_percent"] < 80, f"bus load {m['bus_load_percent']}")
    check(m["missed_actuator_frames"] == 0, "missed actuator frames")
with open(os.path.join(d, "trace.csv")) as f:
    r = csv.reader(f)
    head = next(r)
    rows = sum(1 for _ in r)
want = ["t_s", "x_m", "y_m", "z_m", "theta_x_rad", "theta_y_rad", "theta_z_rad", "x_ref_m", "theta_z_ref_rad",
        "i1_cmd_A", "i8_cmd_A", "i1_A", "i8_A", "state"]
for c in want:
    check(c in head, f"trace.csv lacks column {c}")
check(len(head) == 1 + 6 + 6 + 8 + 8 + 1, f"trace.csv has {len(head)} columns")
check(rows == 10000, f"trace.csv has {rows} rows, expected 10000 (4 s at 2.5 kHz)")
for p in ["pose.png", "currents.png"]:
    path = os.path.join(d, p)
    check(os.path.exists(path) and os.path.getsize(path) > 10000, f"{p} missing or tiny")
    if os.path.exists(path):
        check(open(path, "rb").read(8) == b"\x89PNG\r\n\x1a\n", f"{p} is not a PNG")
for f_ in fails:
    print("FAIL:", f_)
print(f"{len(want) + 12 - len(fails)} passed, {len(fails)} failed")
sys.exit(1 if fails else 0)
