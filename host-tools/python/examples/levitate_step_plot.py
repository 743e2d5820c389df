# %% [markdown]
# # Levitate, step, record, plot
# Notebook-style (cells: `# %%`, opens as a notebook in Jupyter/VS Code via
# jupytext, or runs as a script):
#
#     MAGLEV_TCP=127.0.0.1:1502 python3 levitate_step_plot.py [OUT.png]
#
# against a controller or the bench stand-in `maglev-hil serve --modbus-tcp
# 127.0.0.1:1502`. Stage.record() uses the controller's recorder (servo-rate
# samples); Stage.poll() reads over the link (its jitter included).

# %%
import os
import sys
import time

import numpy as np

import maglev

host, port = os.environ.get("MAGLEV_TCP", "127.0.0.1:1502").rsplit(":", 1)
out_png = sys.argv[1] if len(sys.argv) > 1 else "step_x.png"
stage = maglev.Stage.tcp(host, int(port))
print(f"id.magic 0x{stage.read('id.magic'):04X}, schema hash 0x{stage.read('id.schema_hash') & 0xFFFFFFFF:08X}"
      f" (package 0x{maglev.SCHEMA_HASH:08X}), state {stage.state().name}")

# %% Levitate, printing the start-up sequence as it goes.
stage.levitate(timeout_s=30, progress=lambda state, t: print(f"  {t:5.2f} s  {state.name}"))
time.sleep(2.0)  # z is still settling (a few 100 nm) for a second or two after Ready
pose = stage.pose()
print("pose:", ", ".join(f"{axis} {value * 1e6:+.3f} um" if axis in ("x", "y", "z") else f"{axis} {value * 1e6:+.3f} urad"
                         for axis, value in pose.items()))

# %% A 2 um reference step in x, recorded by the controller's own recorder at the
# servo rate (2.5 kHz): a level trigger on the x reference, 50 ms before it.
x_start = stage.read("status.x")
rec = stage.record(["x.pose", "x.reference", "x.effort", "z.pose"], duration_s=0.4, pretrigger_s=0.05,
                   trigger="level", level=("x.reference", x_start + 1e-6, "rising"),
                   during=lambda: stage.step("x", 2e-6))
t = rec.t * 1e3  # ms from the trigger (the step)
x = rec["x.pose"]
x0 = x[t < 0].mean()
x1 = x[t > 300].mean()
rise = t[np.argmax(x - x0 >= 0.9 * (x1 - x0))] - t[np.argmax(x - x0 >= 0.1 * (x1 - x0))]
print(f"{len(rec)} samples at {1 / np.median(np.diff(rec.t)):.0f} Hz, from {t[0]:.1f} to {t[-1]:.1f} ms")
print(f"step measured {(x1 - x0) * 1e6:.4f} um, 10-90 % rise {rise:.1f} ms,"
      f" overshoot {max(0.0, (x.max() - x1) / (x1 - x0) * 100):.2f} %,"
      f" peak effort {np.abs(rec['x.effort']).max():.3f} A")

# %% The same step polled from the host over Modbus (Stage.poll): link jitter included.
polled = stage.step_response("x", -2e-6, duration_s=0.2, pre_s=0.02, rate_Hz=1000)
print(f"host polling: {len(polled)} samples, median interval {np.median(polled.intervals()) * 1e3:.2f} ms,"
      f" worst {polled.intervals().max() * 1e3:.2f} ms")

# %% Plot (matplotlib; MPLBACKEND=Agg writes the file without a display).
import matplotlib.pyplot as plt

fig, ax = plt.subplots(3, 1, sharex=True, figsize=(7, 6))
ax[0].plot(t, (x - x0) * 1e6, label="x")
ax[0].plot(t, (rec["x.reference"] - rec["x.reference"][t < 0].mean()) * 1e6, "k--", lw=0.8, label="reference")
ax[0].set_ylabel("x - x0 [um]")
ax[0].legend()
ax[0].set_title("2 um step in x (on-board recorder, 2.5 kHz)")
ax[1].plot(t, rec["x.effort"])
ax[1].set_ylabel("x effort [A]")
ax[2].plot(t, (rec["z.pose"] - rec["z.pose"][t < 0].mean()) * 1e9)
ax[2].set_ylabel("z [nm]")
ax[2].set_xlabel("time from the step [ms]")
fig.tight_layout()
fig.savefig(out_png, dpi=100)
print("plot:", out_png)

# %% A closed-loop FRF, reference -> x, host-driven stepped sine (2 um).
frf = stage.frf("x", [2.0, 5.0, 10.0, 20.0], amplitude=2e-6, cycles=4, settle_cycles=1, rate_Hz=400,
                progress=lambda i, n, f: print(f"  sweep {i + 1}/{n}: {f:g} Hz"))
for f, mag, ph, coh in zip(frf.f_Hz, frf.magnitude_dB, frf.phase_deg, frf.coherence):
    print(f"  {f:5.1f} Hz  {mag:+6.2f} dB  {ph:+7.1f} deg  (fit explains {coh * 100:.1f} %)")

# %% Back down.
stage.move_to("x", pose["x"])
stage.land(progress=lambda state, t: print(f"  {t:5.2f} s  {state.name}"))
stage.close()
