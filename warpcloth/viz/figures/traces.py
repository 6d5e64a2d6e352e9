"""The figures of a run: the laser-line displacement (the paper's Fig. 10), the clamp
angle (Fig. 12), the strip's shapes (Figs. 9, 11), the energy budget, and :func:`plot_run`,
which writes them all with the bending loop (:mod:`.kes`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from warpcloth.errors import ArgumentError
from warpcloth.io.measured import ClampAngleTrace, LaserTrace, TrackedShapes, read_measurement
from warpcloth.io.recording import Recording
from warpcloth.metrics import comparison_window, extrema

from . import common
from .common import (
    DPI,
    FORMATS,
    MM,
    X_LABEL,
    Y_LABEL,
    colours_and_labels,
    inside,
    legend,
    plt,
    time_label,
    variant_label,
    window_note,
)
from .kes import KesValues, plot_bending_loop


def plot_amplitude(
    recording: Recording,
    path: Path,
    measured: LaserTrace | None = None,
    *,
    dpi: float = DPI,
    window: tuple[float, float] | None = None,
) -> Path:
    """Laser-line displacement (and free-end x) against time, as in the paper's Fig. 10;
    with ``window`` (s) only that span of the run and of ``measured`` (same footing)."""
    fig, ax = plt.subplots(figsize=(8, 4))
    laser_mm = recording.scenes[0].output.laser_height_mm
    for j, (colour, label) in enumerate(colours_and_labels(recording, fig, ax)):
        t, laser = recording.probe("laser_x", j)
        keep = inside(t, window)
        ax.plot(t[keep], laser[keep] * MM, lw=1.2, color=colour, label=label and f"{label}: laser line")
        if len(recording.variants) == 1:
            t, tip = recording.probe("tip_x", j)
            ax.plot(t[keep], tip[keep] * MM, lw=0.8, ls="--", color=colour, alpha=0.6, label="free end x")
    if measured is not None:
        keep = inside(measured.t, window)
        ax.plot(measured.t[keep], measured.x[keep] * MM, "k.", ms=2.5, label="measured")
    ax.axhline(0, color="0.6", lw=0.6)
    height = f"{laser_mm:g}".replace("-", "−")  # a minus sign, as the tick labels write it
    ax.set(
        xlabel=time_label(recording),
        ylabel="x (mm)",
        title=f"Displacement at the laser line (y = {height} mm from the clamp edge){window_note(window)}",
    )
    legend(ax, fontsize=7, loc="best")
    return common.save(fig, path, dpi)


def plot_clamp_angle(
    recording: Recording,
    path: Path,
    measured: ClampAngleTrace | None = None,
    *,
    dpi: float = DPI,
    window: tuple[float, float] | None = None,
) -> Path:
    """Clamp rotation angle against time, as in the paper's Fig. 12, over an encoder's;
    with ``window`` (s) only that span of both."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for j, (colour, label) in enumerate(colours_and_labels(recording, fig, ax)):
        t, theta = recording.probe("clamp_angle", j)
        keep = inside(t, window)
        ax.plot(t[keep], np.degrees(theta[keep]), lw=1.2, color=colour, label=label)
    if measured is not None:
        keep = inside(measured.t, window)
        ax.plot(measured.t[keep], np.degrees(measured.theta[keep]), "k.", ms=2.5, label="encoder (measured)")
    ax.set(xlabel=time_label(recording), ylabel="clamp angle θ (deg)", title=f"Clamp rotation{window_note(window)}")
    legend(ax, fontsize=7)
    return common.save(fig, path, dpi)


def default_shape_times(recording: Recording, count: int = 9, variant: int = 0) -> np.ndarray:
    """``count`` times evenly over the first half swing: from the release to the free end's
    first turning point after it (the far side for a released swing, the end's largest
    excursion for a driven clamp), so a stroboscopic figure shows one phase of the motion,
    as the paper's Figs. 9 and 11 do; turning points as :func:`warpcloth.metrics.extrema`
    finds them, ripples below 10 % of the swing ignored. The whole run when the end never
    turns back."""
    t, x = recording.probe("tip_x", variant)
    after = t >= 0
    times, _ = extrema(t[after], x[after], starts_at_rest=True, prominence=0.1)
    if len(times) < 2:
        return np.linspace(recording.frame_times[0], recording.frame_times[-1], count)
    return np.linspace(times[0], times[1], count)


def plot_shapes(
    recording: Recording,
    path: Path,
    times: np.ndarray,
    variant: int = 0,
    measured: TrackedShapes | None = None,
    *,
    dpi: float = DPI,
) -> Path:
    """Stroboscopic overlay of the strip's shape at ``times`` (Figs. 9, 11), the laser line
    dashed; with ``measured`` markers, the shapes at the measured frames (up to eight)
    with the markers over them."""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    if measured is not None:
        frames = np.unique(measured.frame)
        chosen = frames[np.linspace(0, len(frames) - 1, min(8, len(frames))).round().astype(int)]
        times = np.array([measured.t[measured.frame == f][0] for f in chosen])
    frames = np.unique(recording.nearest_frames(times))
    colours = plt.cm.viridis(np.linspace(0, 1, len(frames)))
    nc = recording.n_clamped
    for colour, f in zip(colours, frames, strict=True):
        xy = recording.frames[f, variant] * MM
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=colour, lw=1.4, label=f"{recording.frame_times[f]:.3f} s")
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.25", lw=4, solid_capstyle="butt")
        if measured is not None:
            rows = measured.frame == measured.frame[np.abs(measured.t - recording.frame_times[f]).argmin()]
            ax.plot(measured.x[rows] * MM, measured.y[rows] * MM, "o", color=colour, ms=3.5, mfc="none")
    laser_mm = recording.scenes[variant].output.laser_height_mm
    ax.axhline(laser_mm, color="C3", lw=0.8, ls="--", label=f"laser line, y = {laser_mm:g} mm")
    ax.set_aspect("equal")
    ax.set(
        xlabel=X_LABEL,
        ylabel=Y_LABEL,
        title=f"Strip shapes{' and measured markers (o)' if measured is not None else ''}, "
        f"{variant_label(recording, variant)}",
    )
    ax.legend(
        fontsize=7,
        loc="upper left",
        bbox_to_anchor=(1.02, 1),
        title=time_label(recording, unit=False),
        title_fontsize=7,
    )
    return common.save(fig, path, dpi)


ENERGY_TERMS = (
    ("kinetic", "kinetic"),
    ("gravitational", "gravitational (rel. to t=0)"),
    ("tensile", "tensile"),
    ("bending_elastic_work", "bending, elastic"),
    ("hysteresis_work", "dissipated by hysteresis"),
    ("damping_work", "dissipated by damping"),
    ("drive_work", "done by the clamp (−)"),
)


def plot_energy(recording: Recording, path: Path, variant: int = 0, *, dpi: float = DPI) -> Path:
    """Energy budget against time: each term and their sum (top), and the sum's drift
    from its start in % of the peak kinetic energy (bottom), which shows how well the
    step conserves it."""
    fig, (ax, drift) = plt.subplots(2, 1, figsize=(9.5, 6), sharex=True, height_ratios=[3, 1])
    total = np.zeros(())  # the sum of the terms, as they are added
    for name, label in ENERGY_TERMS:
        t, value = recording.probe(name, variant)
        if name == "gravitational":
            value = value - value[0]
        if name == "drive_work":
            value = -value
        total = total + value
        ax.plot(t, value * 1e6, lw=1, label=label)
    ax.plot(t, total * 1e6, "k", lw=1.8, label="sum (conserved)")
    ax.set(ylabel="energy (µJ)", title=f"Energy budget, {variant_label(recording, variant)}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1))
    peak = float(np.nanmax(recording.probe("kinetic", variant)[1]))
    if peak > 0:
        drift.plot(t, 100 * (total - total[0]) / peak, "k", lw=1)
    drift.axhline(0, color="0.6", lw=0.6)
    drift.set(xlabel=time_label(recording), ylabel="sum − start\n(% of peak kinetic)")
    return common.save(fig, path, dpi)


def plot_run(
    recording: Recording,
    out_dir: str | Path,
    *,
    measured: str | Path | None = None,
    times: np.ndarray | None = None,
    variant: int = 0,
    kes: KesValues | None = None,
    fmt: str = "png",
    dpi: float = DPI,
    t_from: float | None = None,
    t_to: float | None = None,
) -> list[Path]:
    """Write every run figure into ``out_dir`` as ``fmt`` (png, pdf or svg); returns the
    paths. A ``measured`` file goes onto the figure of its kind: a laser trace onto the
    amplitude, a clamp encoder onto the clamp angle, tracked markers onto the shapes
    (:func:`warpcloth.io.measured.read_measurement`); a trace or encoder and the run are
    drawn on one window, their overlap unless ``t_from``/``t_to`` choose it
    (:func:`warpcloth.metrics.comparison_window`), which the title states; the figures
    that do not draw the measured record show the whole run, or ``t_from``/``t_to``.
    The clamp angle is left out when every variant's clamp is fixed (θ = 0 throughout)
    and no encoder is drawn.
    ``kes`` marks B and 2HB on the bending loop (:func:`plot_bending_loop`)."""

    if fmt not in FORMATS:
        raise ArgumentError("fmt", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if not (np.isfinite(dpi) and 10 <= dpi <= 2400):
        raise ArgumentError("dpi", f"must be between 10 and 2400, got {dpi!r}")
    if times is not None:
        recording.nearest_frames(times)  # an out-of-range time is refused before any figure is written
    data = read_measurement(measured, argument="measured", encoder=True) if measured else None
    # Each time series is drawn on its own window: the overlap with the measured record
    # only on the figure that draws that record (a short laser trace must not cut the
    # clamp angle), else --from/--to on the run, else all of it. Both are checked before
    # any figure is written.
    run_span = {"the run": (float(recording.probes["t"].min()), float(recording.probes["t"].max()))}
    overlap = None
    if isinstance(data, (LaserTrace, ClampAngleTrace)):  # first: a window outside names the shorter record
        overlap = comparison_window(run_span | {str(measured): (float(data.t[0]), float(data.t[-1]))}, t_from, t_to)
    chosen = comparison_window(run_span, t_from, t_to) if t_from is not None or t_to is not None else None
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    shapes = data if isinstance(data, TrackedShapes) else None
    laser = data if isinstance(data, LaserTrace) else None
    encoder = data if isinstance(data, ClampAngleTrace) else None
    paths = [plot_amplitude(recording, out / f"amplitude.{fmt}", laser, dpi=dpi, window=overlap if laser else chosen)]
    # a fixed clamp's angle is 0 throughout: a figure of it would be an empty axis
    if encoder is not None or any(scene.clamp.motion != "fixed" for scene in recording.scenes):
        paths.append(
            plot_clamp_angle(
                recording, out / f"clamp_angle.{fmt}", encoder, dpi=dpi, window=overlap if encoder else chosen
            )
        )
    return [
        *paths,
        plot_shapes(
            recording,
            out / f"shapes.{fmt}",
            default_shape_times(recording, variant=variant) if times is None else times,
            variant,
            shapes,
            dpi=dpi,
        ),
        plot_bending_loop(recording, out / f"bending_loop.{fmt}", variant, kes, dpi=dpi),
        plot_energy(recording, out / f"energy.{fmt}", variant, dpi=dpi),
    ]
