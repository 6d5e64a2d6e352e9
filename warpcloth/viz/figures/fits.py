"""The figures of motion and clamp-motion fits: measured against the best fit, and where
a two-parameter search went with its uncertainty ellipses.

The fits come from :mod:`warpcloth.calibrate`, a layer above this one: they are typed by
the :class:`~typing.Protocol` of the fields each figure reads (:class:`MotionFit`,
:class:`FitResiduals`, :class:`ClampFit`), which the calibration's classes meet without
either importing the other.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, cast

import numpy as np

from warpcloth.errors import ArgumentError
from warpcloth.io.measured import LaserTrace, SheetMarkers, TrackedShapes
from warpcloth.scene import Scene

if TYPE_CHECKING:
    from warpcloth.scene.sheet import SheetScene

from . import common
from .common import MM, X_LABEL, Y_LABEL, field_label, field_unit, inside, plt


class MotionFit(Protocol):
    """A motion fit's result (:class:`warpcloth.calibrate.motion_fit.FitResult`): each
    fitted field's value and 1σ, their correlation, the RMS (m), the clock offset (s) and
    one history row per launch (stage, RMS and every field's value)."""

    @property
    def parameters(self) -> dict[str, float]: ...
    @property
    def sigma(self) -> dict[str, float]: ...
    @property
    def correlation(self) -> list[list[float]]: ...
    @property
    def rms(self) -> float: ...
    @property
    def shift_s(self) -> float: ...
    @property
    def history(self) -> list[dict]: ...


class FitResiduals(Protocol):
    """What a motion fit compares (:class:`warpcloth.calibrate.motion_fit.Objective`): its
    scene and the residuals of variant ``j`` of a run at clock offset ``shift``."""

    @property
    def scene(self) -> Scene: ...
    def residuals(self, result: Any, j: int, shift: float, penalise: bool = True) -> np.ndarray: ...


class ClampFit(Protocol):
    """A clamp-motion fit (:class:`warpcloth.calibrate.clamp_fit.ClampMotionFit`): θ(t),
    its form and breakpoints, how well it fits and its verdict."""

    @property
    def form(self) -> str: ...
    @property
    def breakpoints_s(self) -> tuple[float, ...]: ...
    @property
    def rms_rad(self) -> float: ...
    @property
    def noise_rad(self) -> float: ...
    @property
    def status(self) -> str: ...
    def theta(self, t: np.ndarray) -> np.ndarray: ...


def plot_fit_overlay(
    result: Any,
    objective: FitResiduals,
    measurement: LaserTrace | TrackedShapes | SheetMarkers,
    fit: MotionFit,
    path: Path,
) -> Path:
    """Measured against the best fit: the laser trace and its residual, tracked markers
    over the simulated strip at six of the measured frames, or a sheet's tracked markers
    coordinate by coordinate (on the measured clock)."""
    shift = fit.shift_s
    title = ", ".join(
        f"{field_label(k, units=False)} = {v:.4g} ± {fit.sigma[k]:.2g} {field_unit(k)}".rstrip()
        for k, v in fit.parameters.items()
    )
    if isinstance(measurement, SheetMarkers):
        return _sheet_markers_overlay(result, objective, measurement, fit, shift, title, path)
    if isinstance(measurement, LaserTrace):
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, height_ratios=[3, 1])
        top.plot(measurement.t, measurement.x * MM, "k.", ms=2.5, label="measured")
        window = (float(measurement.t[0]), float(measurement.t[-1]))  # the fit's own: the measured record
        keep = inside(result.t - shift, window)
        top.plot((result.t - shift)[keep], result.probe("laser_x", 0)[keep] * MM, "C3", lw=1.2, label="best fit")
        top.set(ylabel="x at the laser line (mm)")
        top.legend(fontsize=7)
        residual = objective.residuals(result, 0, shift, penalise=False)
        bottom.plot(measurement.t, residual * MM, "C0.", ms=2)
        bottom.axhline(0, color="0.6", lw=0.6)
        bottom.set(xlabel="measured time (s)", ylabel="residual (mm)")
        top.set_title(
            f"RMS {fit.rms * MM:.3g} mm on t = {window[0]:g} … {window[1]:g} s (the measured record)\n{title}",
            fontsize=9,
        )
        return common.save(fig, path)
    if result.frames is None:
        raise ArgumentError("result", "tracked markers are drawn over the run's frames: run it with keep_frames=True")
    return _tracked_shapes_overlay(result, objective, measurement, fit, title, path)


def _tracked_shapes_overlay(
    result: Any, objective: FitResiduals, measurement: TrackedShapes, fit: MotionFit, title: str, path: Path
) -> Path:
    # Left: the simulated strip at six measured frames with their markers over it (what
    # was fitted, at the scale of the motion). Right: every marker's x and y residual
    # against measured time, at the scale of the noise, which the left panel cannot show
    # (a systematic misfit is a drift or a wave there, noise a band around 0).
    shift = fit.shift_s
    fig = plt.figure(figsize=(11, 6))
    grid = fig.add_gridspec(2, 3, width_ratios=(0.85, 1, 0.04))  # the last: the residuals' colourbar
    ax = fig.add_subplot(grid[:, 0])
    frames = np.unique(measurement.frame)
    chosen = frames[np.linspace(0, len(frames) - 1, min(6, len(frames))).round().astype(int)]
    for colour, f in zip(plt.cm.viridis(np.linspace(0, 1, len(chosen))), chosen, strict=True):
        rows = measurement.frame == f
        t = measurement.t[rows][0]
        k = int(np.abs(result.frame_times - (t + shift)).argmin())
        xy = result.frames[k, 0] * MM
        nc = objective.scene.n_clamped
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=colour, lw=1.2, label=f"{t:.3f} s")
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.25", lw=3)
        ax.plot(measurement.x[rows] * MM, measurement.y[rows] * MM, "o", color=colour, ms=3.5, mfc="none")
    ax.set_aspect("equal")
    curve = getattr(measurement, "u_along", None) is not None  # a curve's points (io.measured.ALONG_COLUMN)
    what = "curve points" if curve else "markers"
    ax.set(xlabel=X_LABEL, ylabel=Y_LABEL, title=f"{what} (o) over the best fit (lines)")
    ax.legend(fontsize=7, loc="best", title="measured t", title_fontsize=7)
    residual = objective.residuals(result, 0, shift, penalise=False).reshape(-1, 2) * MM
    top = fig.add_subplot(grid[0, 1])
    bottom = fig.add_subplot(grid[1, 1], sharex=top)
    # a curve's points are compared across the strip and along it less the frame's mean
    axes = ("across", "along, less the frame's mean") if curve else ("x", "y")
    for panel, axis, column in ((top, axes[0], 0), (bottom, axes[1], 1)):
        drawn = panel.scatter(
            measurement.t, residual[:, column], c=measurement.s * MM, cmap="cividis", s=4, linewidths=0
        )
        panel.axhline(0, color="0.6", lw=0.6)
        panel.set(ylabel=f"residual {axis} (mm)")
    bottom.set(xlabel="measured time (s)")
    fig.colorbar(drawn, cax=fig.add_subplot(grid[:, 2]), label=f"{what[:-1]}'s arc length s (mm)")
    fig.suptitle(
        f"RMS {fit.rms * MM:.3g} mm on t = {measurement.t.min():g} … {measurement.t.max():g} s "
        f"(the measured record)\n{title}",
        fontsize=9,
    )
    return common.save(fig, path)


def _sheet_markers_overlay(
    result: Any,
    objective: FitResiduals,
    measurement: SheetMarkers,
    fit: MotionFit,
    shift: float,
    title: str,
    path: Path,
) -> Path:
    # a row per measured coordinate: every marker's measured points over its simulated
    # track, both less where the clamp alone carries the marker (the clamp's 20 mm would
    # hide the swing of a few tenths of a mm that sets G), and beside it their residuals,
    # simulated − measured: what the fit minimises
    from warpcloth.scene.sheet_build import sheet_clamp

    from .sheet import carried_by_clamp

    rows = len(measurement.axes)
    fig, axes = plt.subplots(rows, 2, figsize=(11, 2.6 * rows + 0.6), sharex=True, squeeze=False)
    window = (float(measurement.t[0]), float(measurement.t[-1]))
    keep = inside(result.t - shift, window)
    residual = objective.residuals(result, 0, shift, penalise=False).reshape(-1, rows)
    clamp = sheet_clamp(cast("SheetScene", objective.scene))  # a sheet fit's objective holds a sheet scene
    angle, travel = result.probe("clamp_angle", 0), result.probe("clamp_displacement", 0)
    carried = carried_by_clamp(result.markers[0, 0], angle, travel, clamp)  # [sample, marker, xyz]
    for a, axis in enumerate(measurement.axes):
        track, misfit = axes[a]
        c = "xyz".index(axis)
        for colour, marker in zip(plt.get_cmap("tab10")(np.arange(10)), np.unique(measurement.marker), strict=False):
            mine = measurement.marker == marker
            against = result.markers[:, 0, marker, c] - carried[:, marker, c]
            measured = measurement.position[mine, a] - np.interp(
                measurement.t[mine] + shift, result.t, carried[:, marker, c]
            )
            track.plot((result.t - shift)[keep], against[keep] * MM, color=colour, lw=1.2, label=f"marker {marker}")
            track.plot(measurement.t[mine], measured * MM, ".", color=colour, ms=2.5)
            misfit.plot(measurement.t[mine], residual[mine, a] * MM, ".", color=colour, ms=2.5)
        track.axhline(0, color="0.6", lw=0.6)
        track.set(ylabel=f"{axis} against the clamp (mm)")
        misfit.axhline(0, color="0.6", lw=0.6)
        misfit.set(ylabel=f"simulated − measured {axis} (mm)")
    axes[0, 0].legend(fontsize=7, ncol=4, loc="lower right")
    axes[0, 0].set_title("measured (dots) and best fit (lines), less the clamp's own motion", fontsize=8)
    axes[0, 1].set_title(f"residuals: RMS {fit.rms * MM:.3g} mm", fontsize=8)
    for ax in axes[-1]:
        ax.set(xlabel="measured time (s)")
    material = objective.scene.material.name.split(" (")[0]
    fig.suptitle(f"sheet markers fit ({material}): {title}", fontsize=9)
    return common.save(fig, path)


SIGMA_STYLES = {1: "-", 2: "--"}
"""Each uncertainty ellipse of :func:`fit_search_figure` (k σ) and its line style, so the
legend tells the 1σ and the 2σ region apart."""


def fit_search_figure(fit: MotionFit, truth: dict[str, float] | None = None) -> plt.Figure:
    """Where a two-parameter motion fit (a :class:`warpcloth.calibrate.motion_fit.FitResult`)
    went: one point per launch from the space-filling start to the optimum, and the 1σ
    and 2σ ellipses of its Gauss–Newton covariance (their tilt is the correlation), also
    in an inset at their own scale; ``truth`` (field → value) is marked when known."""
    names = list(fit.parameters)
    if len(names) != 2:
        raise ArgumentError("fit", f"the search figure shows two parameters; this fit has {len(names)}")
    path = np.array([[h[n] for n in names] for h in fit.history])
    sigma = np.array([fit.sigma[n] for n in names])
    values, vectors = np.linalg.eigh(np.array(fit.correlation) * np.outer(sigma, sigma))
    angle = np.linspace(0, 2 * np.pi, 200)
    circle = np.stack([np.cos(angle), np.sin(angle)])
    centre = np.array([fit.parameters[n] for n in names])[:, None]
    fig, ax = plt.subplots(figsize=(6, 5))
    ax.plot(path[:, 0], path[:, 1], "o-", color="0.5", ms=4, lw=0.8, label="search (one point per launch)")
    inset = ax.inset_axes((0.1, 0.08, 0.38, 0.3))
    for k, style in SIGMA_STYLES.items():
        ellipse = centre + vectors @ (k * np.sqrt(np.clip(values, 0, None))[:, None] * circle)
        ax.plot(*ellipse, color="C3", ls=style, lw=1, label=f"{k}σ")
        inset.plot(*ellipse, color="C3", ls=style, lw=1)
    if truth is not None:
        ax.plot(*[truth[n] for n in names], "k*", ms=12, label="truth")
        inset.plot(*[truth[n] for n in names], "k*", ms=8)
    inset.tick_params(labelsize=6)
    ax.set(xlabel=field_label(names[0]), ylabel=field_label(names[1]), title="the search and the uncertainty")
    ax.legend(fontsize=7)
    return fig


def plot_clamp_fit(t: np.ndarray, theta: np.ndarray, fit: ClampFit, path: Path) -> Path:
    """Encoder angle and the fitted θ(t) (rest, quartic, lines, stop), breakpoints marked."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5), sharex=True, height_ratios=[3, 1])
    top.plot(t, np.degrees(theta), "k.", ms=2.5, label="encoder")
    top.plot(t, np.degrees(fit.theta(t)), "C3", lw=1.2, label=fit.form)
    for when in fit.breakpoints_s:
        top.axvline(when, color="0.7", lw=0.6, ls="--")
    top.set(
        ylabel="θ (deg)",
        title=f"clamp motion fit, RMS {np.degrees(fit.rms_rad):.3g}° "
        f"(noise {np.degrees(fit.noise_rad):.2g}°): {fit.status}",
    )
    top.legend(fontsize=7)
    bottom.plot(t, np.degrees(theta - fit.theta(t)), "C0.", ms=2)
    bottom.axhline(0, color="0.6", lw=0.6)
    bottom.set(xlabel="t (s)", ylabel="residual (deg)")
    return common.save(fig, path)
