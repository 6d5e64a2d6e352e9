"""
USD export: the motion for Omniverse, Blender or usdview
========================================================

A run or a sweep exports to a USD stage: the strips as animated ``BasisCurves``, the
clamp as an animated box, optionally each strip as a ribbon of its real width, and every
per-strip scene parameter as a primvar, so a viewer can colour or filter the variants by
them. This example exports the impulsive rotation and opens the stage again with
``pxr`` (``usd-core``, installed with warpcloth) to show what it contains.

What to read off: the stage metadata a viewer needs to show the motion at the right
size and speed (Y up, metres, 60 time codes per second = the frame rate), the prim
layout, and that the points on the stage are the recorded frames.
"""

# %%
# Run, then export
# ----------------
# :func:`warpcloth.export_usd` takes a :class:`warpcloth.Recording`, the view of a run
# or sweep directory that :func:`warpcloth.load_recording` opens (``--variants`` and
# ``--where`` selections included). ``WARPCLOTH_EXAMPLES_QUICK=1`` records 0.25 s instead
# of 0.5 s.
import os
import shutil
import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from pxr import Usd, UsdGeom

import warpcloth as wc

QUICK = os.environ.get("WARPCLOTH_EXAMPLES_QUICK") == "1"
workdir = Path(tempfile.mkdtemp(prefix="warpcloth-usd-"))

wc.run("impulsive_rotation", {"run.duration_s": 0.25} if QUICK else {}, out=workdir / "rotation")
recording = wc.load_recording(workdir / "rotation")
stage_file = wc.export_usd(recording, workdir / "rotation.usda", ribbon=True)
print(f"{stage_file.name}: {stage_file.stat().st_size / 1e3:.0f} kB for {len(recording.frame_times)} frames")

# %%
# What the stage says
# -------------------
# Positions are metres (``metersPerUnit = 1``; left unwritten a viewer would read
# centimetres and open the strip 100× too small), Y is up, and a time code is a frame
# index from the release at ``timeCodesPerSecond`` = the frame rate. The root layer also
# records where the numbers come from (warpcloth, Warp and NumPy versions, the command,
# the date, the device).
stage = Usd.Stage.Open(str(stage_file))
print(
    f"upAxis {UsdGeom.GetStageUpAxis(stage)}, metersPerUnit {UsdGeom.GetStageMetersPerUnit(stage)}, "
    f"timeCodesPerSecond {stage.GetTimeCodesPerSecond()}, time codes {stage.GetStartTimeCode():g} to "
    f"{stage.GetEndTimeCode():g}, defaultPrim {stage.GetDefaultPrim().GetPath()}"
)
for prim in stage.Traverse():
    print(f"  {prim.GetPath()!s:32} {prim.GetTypeName() or '(group)'}")
print("layer metadata:", sorted(stage.GetRootLayer().customLayerData))

# %%
# The strip prim: points and parameters
# -------------------------------------
# ``points`` are time-sampled, one sample per frame; the scene's per-strip fields are
# primvars named ``warpcloth:<section>:<field>``. The points read back equal the
# recorded frames to single precision (USD points are float32; z = 0, as the model is
# 2D; the ribbon adds the width in z).
curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/Strips/variant_0000"))
samples = curves.GetPointsAttr().GetTimeSamples()
print(f"points: {len(samples)} time samples of {len(curves.GetPointsAttr().Get(0))} nodes")
primvars = UsdGeom.PrimvarsAPI(curves.GetPrim())
for name in ("damping:gamma_per_s", "clamp:rotation_centre_dy_mm", "material:hysteresis_d1_gf_cm_per_cm"):
    value = np.atleast_1d(primvars.GetPrimvar(f"warpcloth:{name}").Get())  # constant: one value per prim
    print(f"  primvars:warpcloth:{name} = {value[0]:g}")
deviation = max(
    np.abs(np.array(curves.GetPointsAttr().Get(code))[:, :2] - recording.frames[int(code), 0]).max() for code in samples
)
print(f"largest difference from the recorded frames: {deviation:.2g} m")

# %%
# A few frames, read from the stage
# ---------------------------------
# Left: the strip's curve and the clamp box (its mesh moved by its time-sampled
# transform) at six time codes, in the plane of the motion. Right: the ribbons of every
# other one of those frames in 3D, the strip's 50 mm width along z.
codes = np.linspace(samples[0], samples[-1], 6).round()
clamp = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Clamps/variant_0000"))
ribbon = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Ribbons/variant_0000"))
box = np.array(clamp.GetPointsAttr().Get())
counts = np.array(ribbon.GetFaceVertexCountsAttr().Get())
indices = np.split(np.array(ribbon.GetFaceVertexIndicesAttr().Get()), np.cumsum(counts)[:-1])
fig = plt.figure(figsize=(12, 5.2))
flat = fig.add_subplot(1, 2, 1)
space = fig.add_subplot(1, 2, 2, projection="3d")
for colour, code in zip(plt.cm.viridis(np.linspace(0, 1, len(codes))), codes, strict=True):
    label = f"time code {code:g} ({code / stage.GetTimeCodesPerSecond():.3f} s)"
    points = np.array(curves.GetPointsAttr().Get(code)) * 1e3
    flat.plot(points[:, 0], points[:, 1], color=colour, lw=1.3, label=label)
    matrix = np.array(UsdGeom.Xformable(clamp.GetPrim()).ComputeLocalToWorldTransform(code))
    corners = (np.c_[box, np.ones(len(box))] @ matrix)[:, :2] * 1e3
    outline = corners[[0, 2, 6, 4, 0]]  # the box's four corners at z = -W/2, in order
    flat.fill(outline[:, 0], outline[:, 1], color=colour, alpha=0.35)
    if code in codes[::2]:  # every other frame, so the ribbons do not hide each other
        vertices = np.array(ribbon.GetPointsAttr().Get(code)) * 1e3
        space.add_collection3d(
            Poly3DCollection([vertices[face][:, [0, 2, 1]] for face in indices], color=colour, alpha=0.6, lw=0)
        )
flat.set(xlabel="x (mm)", ylabel="y (mm)", aspect="equal", title="curves and clamp from the stage")
flat.legend(fontsize=6, loc="upper left", bbox_to_anchor=(1.02, 1))
space.set(
    xlim=(-60, 60),
    ylim=(-30, 30),
    zlim=(-110, 25),
    xlabel="x (mm)",
    ylabel="z (mm)",
    zlabel="y (mm)",
    title="ribbons from the stage",
)
space.set_box_aspect((120, 60, 135))
fig.tight_layout()

shutil.rmtree(workdir)
plt.show()
