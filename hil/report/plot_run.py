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


def primary_steps(run_dir, primary, d, col, sl):
    """(time, sign, small) of every accepted 'step' command on the primary axis;
    small: < 2 % of the plotted span (invisible at full scale)."""
    path = os.path.join(run_dir, "commands.txt")
    if not os.path.exists(path):
        return []
    names = {primary, {"theta_x": "thx", "theta_y": "thy", "theta_z": "thz"}.get(primary, primary)}
    times = []
    with open(path) as f:
        for line in f:
            p = line.split()
            if len(p) >= 4 and p[1] == "step" and p[2] in names and "accepted" in line:
                times.append(float(p[0]))
    v = d[col[primary]][sl]
    span = float(np.nanmax(v) - np.nanmin(v)) if v.size else 0.0
    out = []
    for ts in times:
        # A step moves the reference at once: compare a few ticks after it.
        i = np.searchsorted(d["t_s"], ts)
        j = min(i + 5, d.size - 1)
        ref_col = col[primary].replace("_m", "_ref_m").replace("_rad", "_ref_rad")
        delta = float(d[ref_col][j]) - float(d[ref_col][max(i - 1, 0)])
        out.append((ts, 1.0 if delta >= 0 else -1.0, span > 0 and abs(delta) < 0.02 * span))
    return out


def zoom(ax, d, t, c, r, ts, rot):
    m = (t >= ts - 0.1) & (t < ts + 0.25)
    y, u = scaled(np.concatenate([d[c][m], d[r][m]]), rot)
    n = int(m.sum())
    base = y[n:][0]
    ax.plot(t[m] - ts, y[:n] - base, lw=0.6)
    ax.plot(t[m] - ts, y[n:] - base, lw=0.8, ls="--", color="k")
    ax.set_title(f"step at {ts:g} s ({u})", fontsize=7)
    ax.set_xlabel("t - t_step (s)", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.grid(True, lw=0.3)


def averaged(ax, d, t, c, steps, rot):
    """The steps averaged, each in its own direction from its own level (the
    averaging of the bench's step_avg metric, metrics::average_steps): what a
    step within the noise really does."""
    times = [ts for ts, _, _ in steps]
    gap = min(b - a for a, b in zip(times, times[1:]))
    dt = float(t[1] - t[0])
    n_pre, n_post = int(round(min(0.05, gap / 2) / dt)), int(round((gap - min(0.05, gap / 2)) / dt))
    acc, n = np.zeros(n_pre + n_post), 0
    for ts, sign, _ in steps:
        i0 = int(np.searchsorted(t, ts))
        if i0 >= n_pre and i0 + n_post <= t.size:
            acc += sign * (d[c][i0 - n_pre:i0 + n_post] - d[c][i0 - n_pre:i0].mean())
            n += 1
    ys, u = scaled(acc / n, rot)
    tt = (np.arange(n_pre + n_post) - n_pre) * dt
    size, _ = scaled(np.array([np.mean([abs(float(d[c.replace("_m", "_ref_m").replace("_rad", "_ref_rad")]
                                                  [min(int(np.searchsorted(t, ts)) + 5, t.size - 1)] -
                                                  d[c.replace("_m", "_ref_m").replace("_rad", "_ref_rad")]
                                                  [max(int(np.searchsorted(t, ts)) - 1, 0)]))
                                              for ts, _, _ in steps])]), rot)
    ax.plot(tt, ys, lw=0.8, color="C3")
    ax.plot(tt, np.where(tt < 0, 0.0, size[0]), lw=0.8, ls="--", color="k")
    ax.set_title(f"average of {n} steps ({u})", fontsize=7)
    ax.set_xlabel("t - t_step (s)", fontsize=7)
    ax.tick_params(labelsize=6)
    ax.grid(True, lw=0.3)


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
    # Steps on the primary axis that the full-scale panel cannot show (a 10 nm
    # step beside a 6 mm circle) get zoom panels below it: +-0.1 s around each.
    # A train of 8 or more steps (x_steps_10nm) gets a panel of their average.
    steps = primary_steps(a.run_dir, a.primary, d, col, sl)
    shown = [ts for ts, _, small in steps if small][:3 if len(steps) >= 8 else 4]
    if shown or len(steps) >= 8:
        panels = len(shown) + (1 if len(steps) >= 8 else 0)
        sub = gs[:, 0].subgridspec(2, panels, height_ratios=[2.2, 1.0], hspace=0.35, wspace=0.35)
        ax0 = fig.add_subplot(sub[0, :])
        for k, ts in enumerate(shown):
            zoom(fig.add_subplot(sub[1, k]), d, t, col[a.primary], ref[a.primary], ts, rot)
        if len(steps) >= 8:
            averaged(fig.add_subplot(sub[1, len(shown)]), d, t, col[a.primary], steps, rot)
    else:
        ax0 = fig.add_subplot(gs[:, 0])
    y = d[col[a.primary]][sl]
    r = d[ref[a.primary]][sl]
    both, unit = scaled(np.concatenate([y, r]), rot)
    n = y.size
    ax0.plot(t[sl], both[:n], lw=0.7, label="measured")
    if n > 25 and np.std(both[:n] - both[n:]) > 0.02 * (np.ptp(both[n:]) + 1e-30):
        # Noise-dominated primary (e.g. 0.1 urad steps): also its 10 ms average.
        avg = np.convolve(both[:n], np.ones(25) / 25.0, mode="same")
        ax0.plot(t[sl][12:-12], avg[12:-12], lw=0.9, color="C3", label="measured, 10 ms avg")
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
        # Raw samples (light; per-sample sensor noise) and their 10 ms moving
        # average (dark; what the loops can resolve, ~50 Hz noise bandwidth).
        ax.plot(t[sl], vs, lw=0.4, color="C1", alpha=0.45, label="raw")
        if vs.size > 25:
            avg = np.convolve(vs, np.ones(25) / 25.0, mode="same")
            ax.plot(t[sl][12:-12], avg[12:-12], lw=0.7, color="C3", label="10 ms avg")
        if i == 0:
            ax.legend(fontsize=6, loc="upper right", ncol=2)
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
    axc.legend(ncol=8, fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.0), frameon=False)
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
