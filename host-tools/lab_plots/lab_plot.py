#!/usr/bin/python3
"""Plots of the lab tools' results (called by stagectl record / frf).

  lab_plot.py record DIR   DIR/record.csv -> DIR/record.png (one panel per channel)
  lab_plot.py frf DIR      DIR/frf.csv + DIR/frf_margins.json -> DIR/frf.png
                           (Bode: open and closed loop, coherence; crossover,
                           phase margin, gain margin and bandwidth marked)
Needs matplotlib; exits 2 with a clear message when it is missing.
"""
import csv
import json
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError as e:  # pragma: no cover
    print(f"lab_plot.py: matplotlib is not available ({e}); no plot written", file=sys.stderr)
    sys.exit(2)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], rows[1:]
    cols = {h: [float(r[i]) for r in data] for i, h in enumerate(header)}
    return header, cols


def plot_record(d):
    header, cols = read_csv(os.path.join(d, "record.csv"))
    chans = header[1:]
    fig, axes = plt.subplots(len(chans), 1, sharex=True, figsize=(9, 1.6 * len(chans) + 1), squeeze=False)
    t = cols["t_s"]
    for ax, name in zip(axes[:, 0], chans):
        ax.plot(t, cols[name], lw=0.8)
        ax.set_ylabel(name, fontsize=8)
        ax.axvline(0.0, color="r", lw=0.6, ls="--")
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t [s] (0 = trigger)")
    fig.suptitle("stagectl record")
    fig.tight_layout()
    out = os.path.join(d, "record.png")
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


def plot_frf(d):
    _, c = read_csv(os.path.join(d, "frf.csv"))
    with open(os.path.join(d, "frf_margins.json")) as f:
        m = json.load(f)
    f_hz = c["f_Hz"]
    fig, (a1, a2, a3) = plt.subplots(3, 1, sharex=True, figsize=(9, 9), gridspec_kw={"height_ratios": [3, 3, 1]})
    a1.semilogx(f_hz, c["open_loop_gain_db"], "o-", ms=3, label="open loop L")
    a1.semilogx(f_hz, c["closed_loop_gain_db"], "s-", ms=3, label="closed loop T = L/(1+L)")
    a1.axhline(0, color="k", lw=0.6)
    a1.axhline(-3, color="gray", lw=0.6, ls=":")
    a2.semilogx(f_hz, c["open_loop_phase_deg"], "o-", ms=3, label="open loop")
    a2.semilogx(f_hz, c["closed_loop_phase_deg"], "s-", ms=3, label="closed loop")
    a2.axhline(-180, color="k", lw=0.6)
    a3.semilogx(f_hz, c["coherence"], ".-")
    a3.set_ylim(0, 1.05)
    if m.get("crossover_Hz"):
        fc, pm = m["crossover_Hz"], m["phase_margin_deg"]
        for a in (a1, a2, a3):
            a.axvline(fc, color="r", lw=0.8, ls="--")
        a1.annotate(f"crossover {fc:.1f} Hz", (fc, 0), xytext=(5, 10), textcoords="offset points", color="r")
        a2.plot([fc, fc], [-180, -180 + pm], color="r", lw=2)
        a2.annotate(f"PM {pm:.1f} deg", (fc, -180 + pm), xytext=(5, 5), textcoords="offset points", color="r")
    if m.get("gain_margin_dB") is not None and m.get("phase_crossover_Hz"):
        fp, gm = m["phase_crossover_Hz"], m["gain_margin_dB"]
        a1.plot([fp, fp], [0, -gm], color="m", lw=2)
        a1.annotate(f"GM {gm:.1f} dB @ {fp:.0f} Hz", (fp, -gm), xytext=(5, -12), textcoords="offset points", color="m")
    if m.get("closed_loop_bandwidth_Hz"):
        fb = m["closed_loop_bandwidth_Hz"]
        a1.plot([fb], [-3], "kx", ms=8)
        a1.annotate(f"bandwidth {fb:.1f} Hz", (fb, -3), xytext=(5, -14), textcoords="offset points")
    a1.set_ylabel("gain [dB]")
    a2.set_ylabel("phase [deg]")
    a3.set_ylabel("coherence")
    a3.set_xlabel("f [Hz]")
    for a in (a1, a2, a3):
        a.grid(True, which="both", alpha=0.3)
    a1.legend(fontsize=8)
    fig.suptitle(f"stagectl frf {m.get('axis', '')}: loop measured on the running loop")
    fig.tight_layout()
    out = os.path.join(d, "frf.png")
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in ("record", "frf"):
        print(__doc__, file=sys.stderr)
        return 1
    (plot_record if sys.argv[1] == "record" else plot_frf)(sys.argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main())
