"""
The damped swing (the paper's Figs. 9 and 10)
=============================================

The paper's first vacuum experiment: the free end of a 100 mm strip is carried to
(50, −80) mm from the clamp edge, held there while the strip settles, and released at
t = 0. The strip swings and its swing decays, through the hysteresis of its bending law
(D1) and a little viscous damping (γ). A laser line 80 mm below the clamp edge records
where the strip crosses it: that trace is what the lab measures (Fig. 10), and a
stroboscopic overlay of the shape is Fig. 9.

What to read off: the **first period** and **first amplitude** (the numbers a
calibration is checked against first), and how the **log decrement** per half-cycle
changes as the swing decays, which tells hysteretic from viscous damping.

The bundled scene's material and damping are illustrative (the paper's measured curves
are not in its text); :doc:`plot_kes_fit` makes a material from KES data and
:doc:`plot_calibration` fits the damping to a measured trace.
"""

# %%
# Run the bundled scene
# ---------------------
# ``wc.run`` loads a scene by bundled name or path, applies overrides (a dict of dotted
# field names) and simulates it. With ``out=`` it also streams a run directory, which
# :func:`warpcloth.load_recording` reads back. ``WARPCLOTH_EXAMPLES_QUICK=1`` records
# 1 s instead of the scene's 3 s.
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import warpcloth as wc
from warpcloth.metrics import extrema, swing_summary

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
overrides = {"run.duration_s": 1.0} if QUICK else {}
workdir = Path(tempfile.mkdtemp(prefix="warpcloth-swing-"))

result = wc.run("damped_swing", overrides, out=workdir / "damped_swing")
scene = result.scenes[0]
print(
    f"{result.strip_steps:.3g} strip-steps in {result.wall_time_s:.2f} s; "
    f"{len(result.t)} probe samples, {len(result.frame_times)} shape frames"
)

# %%
# Measure the swing as the lab does
# ---------------------------------
# :func:`~warpcloth.metrics.swing_summary` is the one ruler of ``warpcloth run``,
# the sweep summary and ``warpcloth analyse``: turning points of the laser-line
# displacement, the first period from the release (turning point 0) to turning point 2,
# half-cycle amplitudes and log decrements ln(A_i / A_i+1). With the full 3 s record
# the first period is 0.518 s and the first amplitude 43.6 mm; the heavy-chain value for
# a 100 mm strip, 0.528 s, is longer because the bending stiffness of the root and the
# hold-and-release shorten it.
laser = result.probe("laser_x", 0)
summary = swing_summary(result.t, laser, result.probe("tip_x", 0))
print(f"first period     {summary['first_period_s']:.4f} s")
print(f"first amplitude  {summary['first_amplitude_m'] * 1e3:.2f} mm")
print(
    f"mean log decrement {summary['mean_log_decrement']:.4f} per half-cycle over "
    f"{summary['n_half_cycles'] - 1} ratios of {summary['n_half_cycles']} half-cycles"
)
viscous = scene.damping.gamma_per_s * summary["first_period_s"] / 4
print(f"viscous part alone: γT/4 = {viscous:.4f} per half-cycle")
for i, (a, d) in enumerate(zip(summary["half_cycle_amplitude_m"], summary["log_decrement"], strict=False)):
    print(f"  half-cycle {i}: amplitude {a * 1e3:6.2f} mm, log decrement {d:.3f}")

# %%
# The shapes (Fig. 9)
# -------------------
# Left: the strip every 1/60 s (the paper's video rate) over the first swing, from the
# release to the far turning point. Right: the strip at each turning point, where it is
# momentarily still: the amplitude decays, and the root keeps a bend that hysteresis
# leaves behind. Positions are from the clamp edge (the clamp's lowest point), y up; the
# clamp is drawn grey, the laser line dashed.
turn_t, turn_x = extrema(result.t, laser, starts_at_rest=True)
first_swing = np.flatnonzero(result.frame_times <= turn_t[1] + 1e-9)
at_turns = np.unique(np.abs(result.frame_times[None, :] - turn_t[:, None]).argmin(axis=1))
nc = scene.n_clamped
laser_y = scene.output.laser_height_mm

fig, axes = plt.subplots(1, 2, figsize=(10, 5.2), sharey=True)
for ax, frames, title in (
    (axes[0], first_swing, "first swing, every 1/60 s"),
    (axes[1], at_turns, "at the turning points"),
):
    times = result.frame_times[frames]
    colour = plt.Normalize(times.min(), times.max())
    for f, when in zip(frames, times, strict=True):
        xy = result.frames[f, 0] * 1e3
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=plt.cm.viridis(colour(when)), lw=1.3)
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.3", lw=5, solid_capstyle="butt")
    ax.axhline(laser_y, color="C3", ls="--", lw=0.8)
    ax.annotate("laser line", (-45, laser_y + 2), color="C3", fontsize=8)
    ax.set(title=title, xlabel="x from the clamp edge (mm)", aspect="equal")
    fig.colorbar(plt.cm.ScalarMappable(colour, "viridis"), ax=ax, label="t after release (s)", shrink=0.8)
axes[0].set_ylabel("y from the clamp edge (mm)")
fig.tight_layout()

# %%
# The laser-line displacement (Fig. 10)
# -------------------------------------
# Top: where the strip crosses the laser line, the free end's x dashed, the turning points
# the ruler found marked. Bottom: the log decrement of each half-cycle against its
# amplitude. A viscous damping alone would give a constant γT/4 (dashed); the hysteretic
# bending law dissipates much more at large curvature than at small, so the decrement is
# high just after the release and falls towards the viscous floor as the swing decays.
# That amplitude dependence is what lets a fit separate D1 from γ.
fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6.5), height_ratios=[3, 2])
top.plot(result.t, laser * 1e3, lw=1.2, label=f"laser line ({laser_y:g} mm)")
top.plot(result.t, result.probe("tip_x", 0) * 1e3, "--", lw=0.8, alpha=0.7, label="free end x")
top.plot(turn_t, turn_x * 1e3, "k.", ms=6, label="turning points")
top.axhline(0, color="0.6", lw=0.6)
top.set(
    xlabel="time after release t (s)",
    ylabel="x (mm)",
    title=f"first period {summary['first_period_s']:.4f} s, first amplitude "
    f"{summary['first_amplitude_m'] * 1e3:.1f} mm",
)
top.legend(fontsize=7, loc="upper right")
amplitude = np.array(summary["half_cycle_amplitude_m"][:-1]) * 1e3
bottom.plot(amplitude, summary["log_decrement"], "o-", ms=4)
bottom.axhline(viscous, color="0.4", ls="--", lw=0.8, label=f"viscous only, γT/4 = {viscous:.3f}")
bottom.set(xlabel="half-cycle amplitude (mm)", ylabel="log decrement per half-cycle")
bottom.invert_xaxis()
bottom.legend(fontsize=7)
fig.tight_layout()

# %%
# The run directory as an xarray Dataset
# --------------------------------------
# The run directory holds ``probes.csv``, ``frames.npy``, ``frame_times.npy``,
# ``scene.toml`` and ``meta.json`` (:doc:`/file_formats`). ``to_xarray()`` labels every probe over (t, variant), the
# frames over (frame_time, variant, node, xy) and carries the per-strip parameters as
# coordinates.
print(sorted(p.name for p in (workdir / "damped_swing").iterdir()))
dataset = wc.load_recording(workdir / "damped_swing").to_xarray()
print(dataset["laser_x"].attrs["units"], dataset["frames"].dims)
print(f"free end at t = 0.5 s: x = {float(dataset['tip_x'].sel(t=0.5, method='nearest')[0]) * 1e3:.2f} mm")
print(dataset)

# %%
# The files were written into a temporary directory; remove it.
shutil.rmtree(workdir)
plt.show()
