"""
A woven sheet pushed sideways: markers and the shear loop
=========================================================

Stage 3 of the paper's roadmap (docs/model.md §17): the bundled ``shear_swing`` scene hangs
a 100 × 100 mm sheet of the bundled wool/nylon from its top edge and moves the clamp 20 mm
sideways, in the sheet's own plane, in 0.1 s. The sheet's inertia makes it lag behind the
clamp, which shears it, most at the clamp's corners; then it swings sideways and shears back
and forth until the shear law's hysteresis and the air damp it.

What to read off: the **markers' lag behind the clamp** (what a lab's video of dark marks on
the sheet measures: at most 0.15 mm for the bottom marks in the full run, 0.10 mm for the
centre), and the **probed cell's shear loop** (Fs against φ, in KES-FB1's units), whose
slope is the shear law's in the swing's own, small, range of angles.
"""

# %%
# Run the scene into a sheet run directory
# ----------------------------------------
# :func:`warpcloth.load_scene` reads a sheet scene as it reads a strip's (with ``--set``
# style overrides), :func:`warpcloth.simulate` runs it and streams the sheet run
# directory (``warpcloth run shear_swing`` does the same); the figures read the directory
# back. ``WARPCLOTH_EXAMPLES_QUICK=1`` runs 0.3 s at 10 mm cells instead of the bundled 1 s
# at 5 mm.
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from warpcloth.kernels.sheet import SHEET_PROBE_INDEX

import warpcloth as wc
from warpcloth import units
from warpcloth.io.sheet_run_dir import read_sheet_run
from warpcloth.viz.figures.sheet import SheetSetting, sheet_run_figure, sheet_shapes_figure

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
COARSE = [
    "run.duration_s=0.3",
    "release.settle_time_s=0.1",
    "sheet.spacing_warp_mm=10",
    "sheet.spacing_weft_mm=10",
]
workdir = Path(tempfile.mkdtemp(prefix="warpcloth-sheet-"))
scene = wc.load_scene("shear_swing", COARSE if QUICK else [])
result = wc.simulate(scene, out=workdir / "shear_swing")
run = read_sheet_run(workdir / "shear_swing")
samples = run.samples()  # the arrays the figures read: probes, markers, frames
setting = SheetSetting.of_scene(run.scene, "shear_swing", run.rest_positions)  # titles, the clamp's frame
print(f"{run.meta['n_nodes']} nodes, {len(samples.t)} samples, {len(samples.frame_times)} frames")
print(f"simulated {samples.t[-1]:.2f} s in {result.wall_time_s:.1f} s of wall time")

# %%
# The run at a glance
# -------------------
# :func:`~warpcloth.viz.figures.sheet.sheet_run_figure` draws the four markers' displacement
# from t = 0, the probed cell's shear loop (the cell at the clamp's corner), the probed
# hinge's bending loop (this motion in the sheet's plane barely bends it) and the energy
# budget, which stays constant to O(dt): the simulation's own check that the numbers on
# the other panels are not an integration artefact. ``warpcloth plot RUN_DIR`` writes this
# figure and the next as ``sheet_run.png`` and ``sheet_shapes.png``.
sheet_run_figure(samples, setting)
plt.show()

# %%
# What a lab measures: the markers against the clamp
# --------------------------------------------------
# A camera facing the sheet tracks the dark marks (``output.markers_mm``: the two bottom
# corners, the bottom middle and the centre) and an encoder the clamp's slide. Their
# difference, the marks' sideways (z) position relative to the clamp, is what the sheet's
# shear stiffness and its hysteresis decide: the lag while the clamp accelerates, the
# overshoot when it stops, and the decay of the swing after. Each mark's rest z is taken
# away, so the curves start at 0.
clamp = samples.probes[:, SHEET_PROBE_INDEX["clamp_displacement"], 0]
fig, ax = plt.subplots(figsize=(8, 4))
for k, marker in enumerate(run.meta["markers"]):
    y_mm, z_mm = (v * 1e3 for v in marker["rest_position_m"][1:])
    relative = samples.markers[:, 0, k, 2] - marker["rest_position_m"][2] - clamp
    ax.plot(samples.t, relative * 1e3, lw=1, label=f"marker {k} (y = {y_mm:.0f} mm, z = {z_mm:.0f} mm)")
    print(
        f"marker {k}: largest lag behind the clamp {-relative.min() * 1e3:.3f} mm, "
        f"largest lead {relative.max() * 1e3:.3f} mm"
    )
ax.set(xlabel="t (s)", ylabel="z − rest z − clamp displacement (mm)", title="the marks against the clamp")
ax.legend(fontsize=8)
plt.show()

# %%
# The probed cell's shear loop in KES-FB1's units
# -----------------------------------------------
# Fs against φ, in gf/cm and degrees as KES-FB1 reports them. KES-FB1 defines G as the
# slope between 0.5° and 5° of shear either way, and 2HG, 2HG5 as the loop's width at
# ±0.5° and ±5° (docs/model.md §17.1); this push shears the corner cell far less than 0.5° (−0.11° to
# +0.13° in the full run), so the loop here is the law's small-amplitude branch, and its
# slope is not KES's G. The masing law's branch leaves a reversal with the tangent
# G + D1·α (docs/model.md §4.10: the hysteretic part's slope D1·α adds to G), 2.8
# gf/(cm·°) for the bundled wool; the loop's secant between its extremes is 2.4 — nearly
# elastic, at more than three times G. A lab would read the same angles from a video of
# a grid drawn on the sheet (φ from the angle between its warp and weft lines); with the
# marks' lag above, they are what to hold a fitted shear law to, and they say that a
# swing this small tests the law's small-amplitude stiffness, not its KES-range loop.
phi = samples.probes[:, SHEET_PROBE_INDEX["cell_shear_angle"], 0] / units.ANGLE_DEGREE
force = samples.probes[:, SHEET_PROBE_INDEX["cell_shear_force"], 0] / units.SHEAR_FORCE_GF_PER_CM
top, bottom = int(np.argmax(phi)), int(np.argmin(phi))
secant = (force[top] - force[bottom]) / (phi[top] - phi[bottom])
law = scene.shear.parameters
tangent = scene.shear.rigidity_gf_per_cm_deg + law["hysteresis_d1_gf_per_cm"] * law["hysteresis_alpha_per_deg"]
print(f"probed cell: φ from {phi.min():.4f}° to {phi.max():.4f}°")
print(
    f"secant slope of the loop {secant:.3f} gf/(cm·°); at a reversal G + D1·α = {tangent:.3f}, "
    f"G alone {scene.shear.rigidity_gf_per_cm_deg} gf/(cm·°)"
)

# %%
# The sheet's shape
# -----------------
# :func:`~warpcloth.viz.figures.sheet.sheet_shapes_figure`: the nodes at six frames from the
# side (x, out of the plane: the sheet barely leaves it) and from the front (z, y: the
# sideways push and the shear). ``warpcloth render RUN_DIR`` draws the same frames in 3D,
# and ``warpcloth export-usd RUN_DIR -o sheet.usda`` writes the mesh for a USD viewer.
sheet_shapes_figure(samples, setting)
shutil.rmtree(workdir)
plt.show()
