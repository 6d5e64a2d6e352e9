"""Figures of a sheet run (stage 3, docs/model.md §17): what a lab would look at — the
tracked markers' motion seen from the clamp, the probed cell's shear loop and the probed
hinge's bending loop in KES units, the energy budget — and the sheet's shape at a few
times, one small panel per time.

They read a :class:`SheetRun`: the arrays a :class:`warpcloth.sheet.SheetResult` holds (or
a sheet run directory gives back), SI; and a :class:`SheetSetting`: what the run was (its
name, material, clamp motion and rest shape), which titles and the clamp's frame need.
Axes are in mm, degrees and KES units, as a textile lab reads them.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import matplotlib
import numpy as np

from warpcloth import units
from warpcloth.errors import ArgumentError
from warpcloth.kernels.sheet import SHEET_PROBE_INDEX
from warpcloth.scene.sheet import SheetScene
from warpcloth.sheet.model import SheetClampMotion

from .common import DPI, MM, plt, save

DEGREE = 1 / units.ANGLE_DEGREE

ROUND_OFF_SHEAR_RAD = 1e-9
"""A probed cell whose shear angle never exceeds this (rad) does not shear: far above the
round-off of float64 positions (≈1e-14 rad over a 5 mm cell), far below what any camera or
KES tester resolves."""
ROUND_OFF_CURVATURE_PER_M = 1e-6
"""A probed hinge whose curvature never exceeds this (1/m, a radius of 1000 km) does not
bend: round-off gives ≈1e-12 1/m at a 5 mm spacing; the bundled scenes bend theirs by 0.1
to 100 1/m."""
QUIET_COMPONENT = 0.02
"""A coordinate of the markers' motion whose peak stays under this part of the largest is
named in the panel's title, not drawn (a flat line per marker adds legend, not data)."""


@dataclass(frozen=True)
class SheetSetting:
    """What the figures say of a run besides its arrays (SI): its ``name`` (the scene or run
    directory), its ``material``, the ``clamp``'s rigid motion (undone to see the sheet from
    the clamp), the sheet's ``rest_positions`` ``[node, xyz]`` (its rows and columns of
    nodes), and where the probed cell and hinge are (a phrase for the panels' titles)."""

    name: str
    material: str
    clamp: SheetClampMotion
    rest_positions: np.ndarray
    probed_cell: str = "probed cell"
    probed_hinge: str = "probed hinge"

    @classmethod
    def of_scene(cls, scene: SheetScene, name: str, rest_positions: np.ndarray) -> SheetSetting:
        """The setting of a run of ``scene`` called ``name`` (e.g. its run directory's name)."""
        from warpcloth.scene.sheet_build import sheet_clamp

        out = scene.output
        return cls(
            name=name,
            material=scene.material.name.split(" (")[0],
            clamp=sheet_clamp(scene),
            rest_positions=np.asarray(rest_positions, dtype=float),
            probed_cell=f"probed cell at (y, z) = ({out.probe_cell_mm[0]:g}, {out.probe_cell_mm[1]:g}) mm",
            probed_hinge=(
                f"probed {out.probe_hinge_family} hinge at (y, z) = "
                f"({out.probe_hinge_mm[0]:g}, {out.probe_hinge_mm[1]:g}) mm"
            ),
        )

    def title(self, shown: str) -> str:
        """A figure's title: the run, its material and what the figure shows."""
        return f"{self.name} ({self.material}): {shown}"


class SheetRun(Protocol):
    """What the sheet figures read of a run (SI): probes ``[sample, field, sheet]`` and
    markers ``[sample, sheet, marker, xyz]`` at ``t``, frames ``[frame, sheet, node, xyz]``
    at ``frame_times`` (None if not kept)."""

    t: np.ndarray
    probes: np.ndarray
    markers: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None

    def energy_total(self) -> np.ndarray:
        """The budget, ``[sample, sheet]``."""


def _turned(v: np.ndarray, angle: np.ndarray, axis: np.ndarray) -> np.ndarray:
    # v [time, ..., xyz] turned by angle[time] about the unit axis (Rodrigues' formula)
    shape = (-1,) + (1,) * (v.ndim - 1)
    cos, sin = np.cos(angle).reshape(shape), np.sin(angle).reshape(shape)
    return v * cos + np.cross(axis, v) * sin + (v @ axis)[..., None] * axis * (1 - cos)


def _clamp_axes(clamp: SheetClampMotion) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # the rotation's unit axis and centre and the translation's unit direction
    axis = np.asarray(clamp.axis, float) / np.linalg.norm(clamp.axis)
    direction = np.asarray(clamp.direction, float) / np.linalg.norm(clamp.direction)
    return axis, np.asarray(clamp.centre, float), direction


def seen_from_clamp(
    points: np.ndarray, clamp_angle: np.ndarray, clamp_displacement: np.ndarray, clamp: SheetClampMotion
) -> np.ndarray:
    """``points`` ``[time, ..., xyz]`` (m) as a camera riding on the clamp sees them: the clamp's
    translation d(t) along its direction and rotation θ(t) about its axis through its centre
    undone (the clamp's motion is the rotation, then the translation). A point the clamp
    carries rigidly stays where it was at t = 0."""
    axis, centre, direction = _clamp_axes(clamp)
    travel = clamp_displacement.reshape((-1,) + (1,) * (points.ndim - 1)) * direction
    return _turned(points - travel - centre, -clamp_angle, axis) + centre


def carried_by_clamp(
    start: np.ndarray, clamp_angle: np.ndarray, clamp_displacement: np.ndarray, clamp: SheetClampMotion
) -> np.ndarray:
    """Where the clamp's rigid motion alone carries points at ``start`` ``[..., xyz]`` (m, at
    t = 0): ``[time, ..., xyz]``; a point's motion less this is its motion against the clamp."""
    axis, centre, direction = _clamp_axes(clamp)
    travel = clamp_displacement.reshape((-1,) + (1,) * start.ndim) * direction
    around_centre = np.broadcast_to(start - centre, (len(clamp_angle), *start.shape))
    return _turned(around_centre, clamp_angle, axis) + centre + travel


def _probe(run: SheetRun, name: str, sheet: int) -> np.ndarray:
    return run.probes[:, SHEET_PROBE_INDEX[name], sheet]


def _clamp_frame(run: SheetRun, setting: SheetSetting, sheet: int, points: np.ndarray, at: np.ndarray) -> np.ndarray:
    # points at times `at` seen from the clamp, its angle and travel interpolated from the probes
    angle = np.interp(at, run.t, _probe(run, "clamp_angle", sheet))
    travel = np.interp(at, run.t, _probe(run, "clamp_displacement", sheet))
    return seen_from_clamp(points, angle, travel, setting.clamp)


def _markers_panel(ax: plt.Axes, run: SheetRun, setting: SheetSetting, sheet: int) -> None:
    # each marker's motion seen from the clamp: a colour per marker, a line style per
    # coordinate, coordinates that barely move named in the title instead of drawn
    seen = _clamp_frame(run, setting, sheet, run.markers[:, sheet], run.t)
    motion = (seen - seen[:1]) * MM
    peaks = np.nanmax(np.abs(motion), axis=(0, 1)) if motion.size else np.zeros(3)
    drawn = [a for a in range(3) if peaks[a] >= QUIET_COMPONENT * peaks.max() and peaks.max() > 0]
    names = {0: "x, out of plane", 1: "y, vertical", 2: "z, sideways"}
    styles = dict(zip(drawn, ("-", "--", ":"), strict=False))
    for m in range(motion.shape[1]):
        for a in drawn:
            ax.plot(run.t, motion[:, m, a], styles[a], color=f"C{m}", lw=1)
    ax.axhline(0, color="0.6", lw=0.6)
    quiet = [f"{'xyz'[a]} under {peaks[a]:.2g} mm" for a in range(3) if a not in drawn]
    ax.set(
        xlabel="t (s)",
        ylabel="displacement against the clamp (mm)",
        title="tracked markers, seen from the clamp" + (f" ({', '.join(quiet)})" if quiet else ""),
    )
    start = run.markers[0, sheet] * MM
    who = [
        matplotlib.lines.Line2D([], [], color=f"C{m}", label=f"({round(start[m, 1])}, {round(start[m, 2])})")
        for m in range(motion.shape[1])
    ]
    what = [matplotlib.lines.Line2D([], [], ls=styles[a], color="0.3", label=names[a]) for a in drawn]
    if who:
        markers = ax.legend(handles=who, title="marker at (y, z) mm", fontsize=6, title_fontsize=6, loc="upper left")
        ax.add_artist(markers)
    if what:
        ax.legend(handles=what, fontsize=6, loc="upper right")


def _loop_panel(
    ax: plt.Axes, x: np.ndarray, y: np.ndarray, still: bool, labels: tuple[str, str], title: str, why: str
) -> None:
    # a probed element's loop, or — where it stays at round-off — a sentence saying so
    ax.set(xlabel=labels[0], ylabel=labels[1], title=title)
    if still:
        ax.text(0.5, 0.5, why, ha="center", va="center", wrap=True, fontsize=8, transform=ax.transAxes)
        ax.set_xticks([])
        ax.set_yticks([])
        return
    ax.plot(x, y, lw=1)


def _peak(series: np.ndarray) -> float:
    return float(np.nanmax(np.abs(series))) if np.isfinite(series).any() else 0.0


def sheet_run_figure(run: SheetRun, setting: SheetSetting, sheet: int = 0) -> plt.Figure:
    """Four panels of sheet ``sheet``: the markers' motion against the clamp, the probed
    cell's shear loop, the probed hinge's bending loop (either a sentence where it stays at
    round-off), and the energy budget."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    _markers_panel(axes[0, 0], run, setting, sheet)
    phi, force = _probe(run, "cell_shear_angle", sheet), _probe(run, "cell_shear_force", sheet)
    _loop_panel(
        axes[0, 1],
        phi * DEGREE,
        force / units.SHEAR_FORCE_GF_PER_CM,
        _peak(phi) < ROUND_OFF_SHEAR_RAD,
        ("shear angle φ (°)", "shear force Fs (gf/cm)"),
        f"{setting.probed_cell}: shear loop",
        f"this cell's shear angle stays at round-off (peak |φ| = {_peak(phi) * DEGREE:.2g}°): it does not shear.\n"
        "Probe a cell that does with output.probe_cell_mm.",
    )
    curvature, moment = _probe(run, "hinge_curvature", sheet), _probe(run, "hinge_moment", sheet)
    _loop_panel(
        axes[1, 0],
        curvature / units.CURVATURE_PER_CM,
        moment / units.MOMENT_GF_CM_PER_CM,
        _peak(curvature) < ROUND_OFF_CURVATURE_PER_M,
        ("curvature K (1/cm)", "moment M (gf·cm/cm)"),
        f"{setting.probed_hinge}: bending loop",
        f"this hinge's curvature stays at round-off (peak |K| = {_peak(curvature) / units.CURVATURE_PER_CM:.2g} "
        "1/cm): it does not bend.\nProbe a hinge that does with output.probe_hinge_mm and output.probe_hinge_family.",
    )
    budget = axes[1, 1]
    total = run.energy_total()[:, sheet]
    kinetic = _probe(run, "kinetic", sheet)
    scale = np.nanmax(kinetic) if np.isfinite(kinetic).any() and np.nanmax(kinetic) > 0 else 1.0
    budget.plot(run.t, (total - total[0]) / scale, lw=1)
    budget.set(
        xlabel="t (s)",
        ylabel="budget − its start (per peak kinetic energy)",
        title="energy budget (constant to O(dt))",
    )
    fig.suptitle(setting.title("markers, shear, bending and energy"))
    return fig


def _lines(rest: np.ndarray, along: int, across: int) -> list[np.ndarray]:
    # the nodes of each line of the sheet, one line per rest value of coordinate `across`
    # (a row: equal y; a column: equal z), ordered along coordinate `along`; at 1 µm, so a
    # bias cut's rows, whose y are sums of h/√2, group exactly. A cut at another angle has
    # no two nodes at one y or z: there a line is a band of `across` as wide as the lattice
    # spacing (the nearest neighbours' median distance), its nodes ordered along
    keys = np.round(rest[:, across] * 1e6).astype(np.int64)
    if len(np.unique(keys)) > len(keys) / 2:
        from scipy.spatial import cKDTree

        spacing = float(np.median(cKDTree(rest).query(rest, k=2)[0][:, 1]))
        keys = np.floor((rest[:, across] - rest[:, across].min()) / spacing + 0.5).astype(np.int64)
    return [
        np.flatnonzero(keys == k)[np.argsort(rest[keys == k, along])] for k in np.unique(keys) if (keys == k).sum() > 1
    ]


def sheet_shapes_figure(run: SheetRun, setting: SheetSetting, sheet: int = 0, count: int = 6) -> plt.Figure:
    """The sheet's shape seen from the clamp at ``count`` frames, a column of small panels
    per frame: from the side (each column of nodes, x against y, coloured by its z) and from
    below (each row of nodes, x against z, coloured by its depth y). Out-of-plane x is drawn
    on its own scale (stated on the axis), shared by every panel so frames compare."""
    if run.frames is None or not len(run.frame_times):
        raise ArgumentError("run", "the run kept no frames: run it with keep_frames=True")
    if count < 1:
        raise ArgumentError("count", f"must be at least 1, got {count}")
    picks = np.unique(np.linspace(0, len(run.frame_times) - 1, count).round().astype(int))
    times = run.frame_times[picks]
    shapes = _clamp_frame(run, setting, sheet, run.frames[picks, sheet], times) * MM
    rest = setting.rest_positions * MM
    # a narrow last column holds each row's colourbar, so no panel is squeezed for it
    fig, axes = plt.subplots(
        2, len(picks) + 1, figsize=(2.0 * len(picks) + 1.6, 6.6), width_ratios=[1] * len(picks) + [0.08]
    )
    views = (
        (_lines(rest, 1, 2), 2, (0, 1), "from the side", "y from the clamp edge (mm)", "z across (mm)"),
        (_lines(rest, 2, 1), 1, (2, 0), "from below", "x out of the plane (mm)", "y from the clamp edge (mm)"),
    )
    reach = max(float(np.nanmax(np.abs(shapes[..., 0]))), 1e-3)
    for row, (lines, key, (h, v), view, ylabel, colour_label) in zip(axes, views, strict=True):
        row, bar = row[:-1], row[-1]
        norm = matplotlib.colors.Normalize(rest[:, key].min(), rest[:, key].max())
        for ax, shape, t in zip(row, shapes, times, strict=True):
            if ax is not row[0]:
                ax.sharey(row[0])
                ax.tick_params(labelleft=False)
            for nodes in lines:
                ax.plot(shape[nodes, h], shape[nodes, v], color=plt.cm.viridis(norm(rest[nodes[0], key])), lw=0.8)
            ax.set_title(f"t = {t:.3f} s", fontsize=8)
            ax.tick_params(labelsize=7)
            if view == "from the side":
                ax.set_xlim(-1.1 * reach, 1.1 * reach)
                ax.set_xlabel("x out of the plane (mm)", fontsize=7)
            else:
                ax.set_ylim(-1.1 * reach, 1.1 * reach)
                ax.set_xlabel("z across (mm)", fontsize=7)
        row[0].set_ylabel(f"{view}\n{ylabel}", fontsize=8)
        fig.colorbar(matplotlib.cm.ScalarMappable(norm, "viridis"), cax=bar, label=colour_label)
    fig.suptitle(setting.title("the sheet's shape seen from the clamp (x on its own scale)"), fontsize=10)
    return fig


def plot_sheet_run(
    run: SheetRun, setting: SheetSetting, out_dir: str | Path, sheet: int = 0, fmt: str = "png", dpi: float = DPI
) -> list[Path]:
    """Write ``sheet_run`` and (if frames were kept) ``sheet_shapes`` of one sheet into
    ``out_dir``; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [save(sheet_run_figure(run, setting, sheet), out / f"sheet_run.{fmt}", dpi)]
    if run.frames is not None and len(run.frame_times):
        paths.append(save(sheet_shapes_figure(run, setting, sheet), out / f"sheet_shapes.{fmt}", dpi))
    return paths
