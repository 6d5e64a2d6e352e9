"""Figures of a sheet run (stage 3, docs/model.md §17): what a lab would look at — the
tracked markers' displacement, the probed cell's shear loop and the probed hinge's
bending loop in KES units, the energy budget — and the sheet's shape seen from the side
and from the front.

They read a :class:`SheetRun`: the arrays a :class:`warpcloth.sheet.SheetResult` holds (or
a sheet run directory gives back), SI.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import numpy as np

from warpcloth import units
from warpcloth.errors import ArgumentError
from warpcloth.kernels.sheet import SHEET_PROBE_INDEX

from .common import DPI, MM, plt, save

DEGREE = 1 / units.ANGLE_DEGREE


class SheetRun(Protocol):
    """What the sheet figures read of a run (SI): probes ``[sample, field, sheet]`` and
    markers ``[sample, sheet, marker, xyz]`` at ``t``, frames ``[frame, sheet, node, xyz]``
    at ``frame_times`` (None if not kept), and the cut's cells ``[cell, 4]`` (via ``geometry``)."""

    t: np.ndarray
    probes: np.ndarray
    markers: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None

    def energy_total(self) -> np.ndarray:
        """The budget, ``[sample, sheet]``."""


def sheet_run_figure(run: SheetRun, sheet: int = 0) -> plt.Figure:
    """Four panels of sheet ``sheet``: marker displacements, shear loop, bending loop, budget."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    markers, displacement = axes[0, 0], run.markers[:, sheet] - run.markers[:1, sheet]
    for m in range(displacement.shape[1]):
        for axis, style in zip("xyz", ("-", "--", ":"), strict=True):
            markers.plot(run.t, displacement[:, m, "xyz".index(axis)] * MM, style, lw=1, label=f"marker {m} {axis}")
    markers.set(xlabel="t (s)", ylabel="displacement from t = 0 (mm)", title="tracked markers")
    if displacement.shape[1]:
        markers.legend(fontsize=7, ncol=2)

    def probe(name: str) -> np.ndarray:
        return run.probes[:, SHEET_PROBE_INDEX[name], sheet]

    shear = axes[0, 1]
    shear.plot(probe("cell_shear_angle") * DEGREE, probe("cell_shear_force") / units.SHEAR_FORCE_GF_PER_CM, lw=1)
    shear.set(xlabel="shear angle φ (°)", ylabel="shear force Fs (gf/cm)", title="probed cell: shear loop")
    bending = axes[1, 0]
    bending.plot(
        probe("hinge_curvature") / units.CURVATURE_PER_CM, probe("hinge_moment") / units.MOMENT_GF_CM_PER_CM, lw=1
    )
    bending.set(xlabel="curvature K (1/cm)", ylabel="moment M (gf·cm/cm)", title="probed hinge: bending loop")
    budget = axes[1, 1]
    total = run.energy_total()[:, sheet]
    kinetic = probe("kinetic")
    scale = np.nanmax(kinetic) if np.isfinite(kinetic).any() and np.nanmax(kinetic) > 0 else 1.0
    budget.plot(run.t, (total - total[0]) / scale, lw=1)
    budget.set(
        xlabel="t (s)",
        ylabel="budget − its start (per peak kinetic energy)",
        title="energy budget (constant to O(dt))",
    )
    fig.suptitle(f"sheet {sheet}")
    return fig


def sheet_shapes_figure(run: SheetRun, sheet: int = 0, count: int = 6) -> plt.Figure:
    """The sheet's nodes at ``count`` frames, from the side (x, y) and from the front (z, y)."""
    if run.frames is None or not len(run.frame_times):
        raise ArgumentError("run", "the run kept no frames: run it with keep_frames=True")
    fig, (side, front) = plt.subplots(1, 2, figsize=(10, 5), sharey=True)
    picks = np.unique(np.linspace(0, len(run.frame_times) - 1, count).round().astype(int))
    colours = plt.cm.viridis(np.linspace(0, 1, len(picks)))
    for colour, f in zip(colours, picks, strict=True):
        x = run.frames[f, sheet] * MM
        label = f"t = {run.frame_times[f]:.3f} s"
        side.plot(x[:, 0], x[:, 1], ".", ms=2, color=colour, label=label)
        front.plot(x[:, 2], x[:, 1], ".", ms=2, color=colour)
    side.set(xlabel="x, out of the sheet's plane (mm)", ylabel="y from the clamp edge (mm)", title="from the side")
    front.set(xlabel="z, across the sheet (mm)", title="from the front")
    for ax in (side, front):
        ax.set_aspect("equal", adjustable="datalim")
    side.legend(fontsize=7)
    return fig


def plot_sheet_run(
    run: SheetRun, out_dir: str | Path, sheet: int = 0, fmt: str = "png", dpi: float = DPI
) -> list[Path]:
    """Write ``sheet_run`` and (if frames were kept) ``sheet_shapes`` of one sheet into
    ``out_dir``; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [save(sheet_run_figure(run, sheet), out / f"sheet_run.{fmt}", dpi)]
    if run.frames is not None and len(run.frame_times):
        paths.append(save(sheet_shapes_figure(run, sheet), out / f"sheet_shapes.{fmt}", dpi))
    return paths
