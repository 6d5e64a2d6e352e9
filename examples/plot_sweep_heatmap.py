"""
A sweep heat map: damping against hysteresis
============================================

How do the viscous damping γ and the hysteresis amplitude D1 shape the damped swing?
A grid sweep over both answers it in one call: every variant of a batch runs in the same
kernel launch, the batches on one thread per core, and the summary holds the swing
metrics of every variant (measured by the same ruler as ``warpcloth run`` and
``warpcloth analyse``).

What to read off: the **mean log decrement** grows with γ everywhere and with D1 up to
about 0.05 gf·cm/cm, where it levels off; in that range its contours run diagonally (more
of one and less of the other give the same average decay), so the decay rate alone cannot
separate them. The **first period** moves by about 20 ms across the range of D1 (the
hysteretic moment stiffens the root) and by only a few ms across γ. A fit to the whole
trace separates them, because they decay the swing differently
(:doc:`plot_damped_swing`, :doc:`plot_calibration`).
"""

# %%
# The sweep
# ---------
# A sweep is a scene with a ``[sweep]`` section; here it is built in Python from the
# bundled damped swing and expanded into validated variant scenes
# (:func:`warpcloth.expand`). ``WARPCLOTH_EXAMPLES_QUICK=1`` sweeps a 4 × 4 grid over 1 s at the auto step
# instead of 7 × 7 over 2 s.
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import warpcloth as wc
from warpcloth.scene import read_scene_file
from warpcloth.viz.plots import sweep_figure

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
n = 4 if QUICK else 7
workdir = Path(tempfile.mkdtemp(prefix="warpcloth-sweep-"))

GAMMA, D1 = "damping.gamma_per_s", "material.hysteresis_d1_gf_cm_per_cm"
raw = read_scene_file("damped_swing")
raw["run"]["duration_s"] = 1.0 if QUICK else 2.0
if QUICK:  # the longest stable, accurate step (docs/model.md §9.6): 4.5× fewer than the scene's
    raw["integrator"]["dt_s"] = "auto"
raw["sweep"] = {
    "grid": {GAMMA: np.linspace(0.0, 1.0, n).round(3).tolist(), D1: np.linspace(0.0, 0.08, n).round(4).tolist()}
}
sweep = wc.expand(raw)
print(f"{len(sweep.scenes)} variants; the first: {sweep.assignments[0]}, the last: {sweep.assignments[-1]}")

# %%
# Run it
# ------
# :func:`warpcloth.run_sweep` streams a sweep directory (per-batch Parquet files, then
# ``summary.csv`` and ``summary.parquet``) and returns the merged summary: one row per
# variant, its swept values and its metrics. Run again into the same directory, it
# resumes: only missing batches are computed.
summary = wc.run_sweep(sweep, workdir / "sweep")
print(sorted(p.name for p in (workdir / "sweep").iterdir()))
print(summary[["variant", GAMMA, D1, "first_period_s", "mean_log_decrement"]].head().to_string(index=False))

# %%
# The mean log decrement per half-cycle
# -------------------------------------
# :func:`warpcloth.viz.plots.sweep_figure` draws a metric over two swept parameters as a
# heat map (a grid) or coloured points (a random sample). With the full 2 s record the
# decrement runs from 0.04 (neither) to about 0.2; the record of the quick version is
# too short for a mean over many half-cycles, and its first, largest decrements dominate.
fig = sweep_figure(summary, "mean_log_decrement", GAMMA, D1)
fig.tight_layout()
table = summary.pivot_table(index=D1, columns=GAMMA, values="mean_log_decrement")
print("mean log decrement (rows: D1, columns: γ)")
print(table.round(3).to_string())

# %%
# The first period
# ----------------
# The period moves by about 20 ms with D1, and by a few ms across the whole range of γ.
fig = sweep_figure(summary, "first_period_s", GAMMA, D1)
fig.tight_layout()
periods = summary.pivot_table(index=D1, columns=GAMMA, values="first_period_s")
print(
    f"first period: {periods.min().min():.4f} to {periods.max().max():.4f} s; "
    f"spread across γ at D1 = {periods.index[-1]:g}: {np.ptp(periods.iloc[-1].to_numpy()) * 1e3:.1f} ms, "
    f"across D1 at γ = {periods.columns[0]:g}: {np.ptp(periods.iloc[:, 0].to_numpy()) * 1e3:.1f} ms"
)

shutil.rmtree(workdir)
plt.show()
