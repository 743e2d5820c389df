#!/usr/bin/python3
"""Plots of one maglev-hil run, in the style of paper 000 Figs. 7-10 and paper
003 Figs. 15-20: the primary axis large, the five perturbed axes beside it.

Usage: /usr/bin/python3 plot_run.py RUN_DIR [--primary AXIS] [--title TEXT]
Reads RUN_DIR/trace.csv, writes RUN_DIR/pose.png and RUN_DIR/currents.png.
Needs Debian's python3-matplotlib and python3-numpy (not the pyenv python3).
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

AXES = ["x", "y", "z", "theta_x", "theta_y", "theta_z"]
LABEL = {"x": "x", "y": "y", "z": "z", "theta_x": r"$\theta_x$", "theta_y": r"$\theta_y$", "theta_z": r"$\theta_z$"}
STATES = ["Idle", "Homing", "InPlaneLock", "Lift", "ZLock", "TiltLock", "Ready", "Landing", "Fault"]


def scaled(values, rotation):
    """Pick nm/um/mm (nrad/urad/mrad) so the plotted span reads naturally."""
    span = float(np.nanmax(values) - np.nanmin(values)) if values.size else 0.0
    mag = max(span, float(np.nanmax(np.abs(values))) * 1e-3 if values.size else 0.0)
    units = [(1e-9, "nrad" if rotation else "nm"), (1e-6, "urad" if rotation else "um"),
             (1e-3, "mrad" if rotation else "mm")]
    for scale, name in units:
        if mag < 2000 * scale:
            return values / scale, name
    return values, "rad" if rotation else "m"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("run_dir")
    ap.add_argument("--primary", default="x", choices=AXES)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    path = os.path.join(a.run_dir, "trace.csv")
    d = np.genfromtxt(path, delimiter=",", names=True)
    t = d["t_s"]
    # Show from the first Ready tick (levitated) when there is one, like the papers.
    ready = np.nonzero(d["state"] == 6)[0]
    start = 0 if a.primary == "z" or ready.size == 0 else ready[0]
    sl = slice(start, None)

    fig = plt.figure(figsize=(12, 7))
    gs = fig.add_gridspec(5, 2, width_ratios=[1.6, 1.0], hspace=0.45, wspace=0.25)
    col = {a2: (a2 + ("_rad" if a2.startswith("theta") else "_m")) for a2 in AXES}
    ref = {a2: (a2 + ("_ref_rad" if a2.startswith("theta") else "_ref_m")) for a2 in AXES}
    rot = a.primary.startswith("theta")
    ax0 = fig.add_subplot(gs[:, 0])
    y = d[col[a.primary]][sl]
    r = d[ref[a.primary]][sl]
    both, unit = scaled(np.concatenate([y, r]), rot)
    n = y.size
    ax0.plot(t[sl], both[:n], lw=0.7, label="measured")
    ax0.plot(t[sl], both[n:], lw=0.9, ls="--", color="k", label="reference")
    ax0.set_xlabel("time (s)")
    ax0.set_ylabel(f"{LABEL[a.primary]} ({unit})")
    ax0.legend(loc="best", fontsize=8)
    ax0.grid(True, lw=0.3)
    others = [a2 for a2 in AXES if a2 != a.primary]
    for i, a2 in enumerate(others):
        ax = fig.add_subplot(gs[i, 1])
        v = d[col[a2]][sl]
        vs, u2 = scaled(v - np.mean(v), a2.startswith("theta"))
        ax.plot(t[sl], vs, lw=0.5, color="C1")
        ax.set_ylabel(f"{LABEL[a2]} ({u2})", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(True, lw=0.3)
        if i == len(others) - 1:
            ax.set_xlabel("time (s)", fontsize=8)
    fig.suptitle(a.title + "  (perturbed axes: deviation from their mean)", fontsize=10)
    fig.savefig(os.path.join(a.run_dir, "pose.png"), dpi=110)
    plt.close(fig)

    fig, (axc, axs) = plt.subplots(2, 1, figsize=(12, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    for j in range(8):
        axc.plot(t, d[f"i{j + 1}_A"], lw=0.5, color=f"C{j}", label=f"i{j + 1}")
        axc.plot(t, d[f"i{j + 1}_cmd_A"], lw=0.5, ls="--", color=f"C{j}")
    axc.set_ylabel("coil current (A)\n(solid actual, dashed commanded)")
    axc.legend(ncol=8, fontsize=7, loc="upper left")
    axc.grid(True, lw=0.3)
    axs.step(t, d["state"], where="post", lw=0.8)
    axs.set_yticks(range(len(STATES)))
    axs.set_yticklabels(STATES, fontsize=7)
    axs.set_xlabel("time (s)")
    axs.grid(True, lw=0.3)
    fig.suptitle(a.title + ": coil currents and sequencer state", fontsize=10)
    fig.savefig(os.path.join(a.run_dir, "currents.png"), dpi=110)
    plt.close(fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
