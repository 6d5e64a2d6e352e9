"""2D figures of a run (the paper's Figs. 3b/8b, 9/11, 10, 12 and the energy budget), of
a sweep (a metric against one or two parameters) and of fits (the motion, the clamp
angle, a KES material), headless, as PNG (or PDF, SVG: :data:`warpcloth.viz.FORMATS`).

Axes are in the units a textile lab reads: mm, degrees, and KES units for the bending
loop (curvature in 1/cm, moment per width in gf·cm/cm), converted via ``units``.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed, on CI or a cluster node

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from warpcloth import units  # noqa: E402
from warpcloth.errors import ArgumentError, DataFileError  # noqa: E402
from warpcloth.io.atomic import write_atomically  # noqa: E402
from warpcloth.io.measured import ClampAngleTrace, LaserTrace, TrackedShapes, read_measurement  # noqa: E402
from warpcloth.io.recording import Recording  # noqa: E402
from warpcloth.metrics import comparison_window, extrema  # noqa: E402
from warpcloth.scene import to_si  # noqa: E402
from warpcloth.scene.schema import PAPER_LAW_SHAPE  # noqa: E402
from warpcloth.sim import moment_along_path  # noqa: E402
from warpcloth.viz import DPI, FORMATS  # noqa: E402
from warpcloth.viz.geometry import colour_values  # noqa: E402

MM = 1 / units.LENGTH_MM

X_LABEL = "x from the clamp edge (mm)"
Y_LABEL = "y from the clamp edge (mm)"
"""The axes of every figure of the strip's shape (positions from the clamp edge at rest)."""


def time_label(recording: Recording, unit: bool = True) -> str:
    """The time axis' name: "t after release" when every scene releases its strip at
    t = 0, else plain "t" (a driven clamp, as in the impulsive rotation, has no release:
    its t = 0 is the start of the motion); ``unit`` adds " (s)"."""
    name = "t after release" if all(s.release.enabled for s in recording.scenes) else "t"
    return f"{name} (s)" if unit else name


def _label(recording: Recording, j: int) -> str:
    varying = recording.varying[:2]
    values = [recording.parameters[c].iloc[j] for c in varying]
    parts = [f"{c.split('.')[-1]}={v:.3g}" if isinstance(v, float) else f"{c.split('.')[-1]}={v}"
             for c, v in zip(varying, values, strict=True)]
    return f"variant {recording.variants[j]}" + (f" ({', '.join(parts)})" if parts else "")


LEGEND_VARIANTS = 8
"""Up to this many variants get a legend entry each; more are coloured by a parameter."""


def _variant_colours(recording: Recording, fig: plt.Figure, ax: plt.Axes) -> list[tuple[object, str | None]]:
    """A colour and a legend label per variant: its own entry for a few variants; for
    many, viridis keyed to the first parameter that varies, with a colourbar, and no
    legend entries (a 100-entry legend would cover the axes)."""
    n = len(recording.variants)
    if n <= LEGEND_VARIANTS:
        return [(f"C{j}", _label(recording, j)) for j in range(n)]
    key = recording.varying[0] if recording.varying else "variant"
    values = colour_values(recording)  # as renders and USD colour them (a choice by its values' order)
    norm = matplotlib.colors.Normalize(values.min(), values.max() if values.max() > values.min() else None)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm, "viridis"), ax=ax, label=field_label(key))
    return [(plt.cm.viridis(norm(v)), None) for v in values]


def _legend(ax: plt.Axes, **style: object) -> None:
    if ax.get_legend_handles_labels()[0]:  # many variants are labelled by a colourbar instead
        ax.legend(**style)


FIELD_LABELS = {
    "damping.gamma_per_s": ("γ", "s⁻¹"),
    "material.bending_rigidity_gf_cm2_per_cm": ("B = D", "gf·cm²/cm"),
    "material.hysteresis_d1_gf_cm_per_cm": ("D1", "gf·cm/cm"),
    "material.hysteresis_alpha_cm": ("α", "cm"),
    "material.hysteresis_k0_per_cm": ("K0", "cm⁻¹"),
    "material.density_g_per_cm2": ("ρ_A", "g/cm²"),
    "material.bending_law": ("bending law", ""),
    "material.dahl_moment_gf_cm_per_cm": ("M_s", "gf·cm/cm"),
    "material.dahl_curvature_per_cm": ("K_s", "cm⁻¹"),
    "material.dahl_exponent": ("Dahl exponent n", ""),
    "material.friction_moment_gf_cm_per_cm": ("M_f", "gf·cm/cm"),
    "material.friction_width_per_cm": ("K_w", "cm⁻¹"),
    "clamp.rotation_centre_dx_mm": ("rotation centre dx", "mm"),
    "clamp.rotation_centre_dy_mm": ("rotation centre dy", "mm"),
    "release.hold_x_mm": ("hold x", "mm"),
    "release.hold_y_mm": ("hold y", "mm"),
    "time_shift_s": ("clock offset δ", "s"),
    "first_period_s": ("first period", "s"),
    "first_amplitude_m": ("first amplitude", "m"),
    "mean_log_decrement": ("mean log decrement per half-cycle", ""),
    "n_half_cycles": ("half-cycles", ""),
    "peak_tip_speed_m_per_s": ("peak tip speed", "m/s"),
    "hysteresis_work_J": ("hysteresis work", "J"),
    "damping_work_J": ("damping work", "J"),
}
"""Symbols and units for the fields figures name; anything else shows its own name."""


def field_unit(name: str) -> str:
    """The unit a figure writes for ``name`` ("" if none is known)."""
    return FIELD_LABELS.get(name, (name, ""))[1]


def field_label(name: str, units: bool = True) -> str:
    """An axis label: the field's symbol and unit (``γ (s⁻¹)``), else its dotted name."""
    symbol, unit = FIELD_LABELS.get(name, (name, ""))
    return f"{symbol} ({unit})" if units and unit else symbol


def _save(fig: plt.Figure, path: Path, dpi: float = DPI) -> Path:
    fig.tight_layout()
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png"))
    plt.close(fig)
    return path


def _inside(t: np.ndarray, window: tuple[float, float] | None) -> np.ndarray:
    # samples within a comparison window (all of them without one)
    if window is None:
        return np.ones(len(t), bool)
    return (t >= window[0] - 1e-9) & (t <= window[1] + 1e-9)


def _window_note(window: tuple[float, float] | None) -> str:
    return "" if window is None else f"; compared on t = {window[0]:g} … {window[1]:g} s"


def plot_amplitude(recording: Recording, path: Path, measured: LaserTrace | None = None, *,
                   dpi: float = DPI, window: tuple[float, float] | None = None) -> Path:
    """Laser-line displacement (and free-end x) against time, as in the paper's Fig. 10;
    with ``window`` (s) only that span of the run and of ``measured`` (same footing)."""
    fig, ax = plt.subplots(figsize=(8, 4))
    laser_mm = recording.scenes[0].output.laser_height_mm
    for j, (colour, label) in enumerate(_variant_colours(recording, fig, ax)):
        t, laser = recording.probe("laser_x", j)
        keep = _inside(t, window)
        ax.plot(t[keep], laser[keep] * MM, lw=1.2, color=colour, label=label and f"{label}: laser line")
        if len(recording.variants) == 1:
            t, tip = recording.probe("tip_x", j)
            ax.plot(t[keep], tip[keep] * MM, lw=0.8, ls="--", color=colour, alpha=0.6, label="free end x")
    if measured is not None:
        keep = _inside(measured.t, window)
        ax.plot(measured.t[keep], measured.x[keep] * MM, "k.", ms=2.5, label="measured")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.set(xlabel=time_label(recording), ylabel="x (mm)",
           title=f"Displacement at the laser line (y = {laser_mm:g} mm from the clamp edge){_window_note(window)}")
    _legend(ax, fontsize=7, loc="upper right")
    return _save(fig, path, dpi)


def plot_clamp_angle(recording: Recording, path: Path, measured: ClampAngleTrace | None = None, *,
                     dpi: float = DPI, window: tuple[float, float] | None = None) -> Path:
    """Clamp rotation angle against time, as in the paper's Fig. 12, over an encoder's;
    with ``window`` (s) only that span of both."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for j, (colour, label) in enumerate(_variant_colours(recording, fig, ax)):
        t, theta = recording.probe("clamp_angle", j)
        keep = _inside(t, window)
        ax.plot(t[keep], np.degrees(theta[keep]), lw=1.2, color=colour, label=label)
    if measured is not None:
        keep = _inside(measured.t, window)
        ax.plot(measured.t[keep], np.degrees(measured.theta[keep]), "k.", ms=2.5, label="encoder (measured)")
    ax.set(xlabel=time_label(recording), ylabel="clamp angle θ (deg)", title=f"Clamp rotation{_window_note(window)}")
    _legend(ax, fontsize=7)
    return _save(fig, path, dpi)


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


def plot_shapes(recording: Recording, path: Path, times: np.ndarray, variant: int = 0,
                measured: TrackedShapes | None = None, *, dpi: float = DPI) -> Path:
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
    ax.set(xlabel=X_LABEL, ylabel=Y_LABEL,
           title=f"Strip shapes{' and measured markers (o)' if measured is not None else ''}, "
                 f"{_label(recording, variant)}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1), title=time_label(recording, unit=False),
              title_fontsize=7)
    return _save(fig, path, dpi)


def kes_loop(recording: Recording, variant: int = 0, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """The material's KES-FB2 loop (0 → K0 → −K0 → K0): curvature (1/m), moment (N·m/m)."""
    material = to_si(recording.scenes[variant].material)
    # the paper's law closes its loop at its K0; the others are charted on the standard cycle
    k0 = material.hysteresis_k0 if material.bending_law in PAPER_LAW_SHAPE else KES_K0_PER_CM * units.CURVATURE_PER_CM
    path = np.concatenate([np.linspace(0, k0, samples), np.linspace(k0, -k0, 2 * samples)[1:],
                           np.linspace(-k0, k0, 2 * samples)[1:]])
    moment, _ = moment_along_path(material, path)
    return path, moment


KES_K0_PER_CM = 2.5
"""The standard KES-FB2 cycle's largest curvature (1/cm)."""

KES_B_RANGE_PER_CM = (0.5, 1.5)
"""Where KES-FB2 reads B (the slope) and 2HB (the loop's width, at the middle: K = ±1 1/cm)."""


def _mark_kes_values(ax: plt.Axes, k: np.ndarray, m: np.ndarray, kes: object) -> None:
    # B as a line of its slope through the loop's centre line over 0.5–1.5 1/cm, 2HB as
    # the width at K = 1 1/cm between the branches, as a KES-FB2 chart is read
    lo, hi = KES_B_RANGE_PER_CM
    k1 = 0.5 * (lo + hi)
    rising, falling = np.gradient(k) > 0, np.gradient(k) < 0
    at_k1 = [float(np.interp(k1, *_sorted(k[leg], m[leg]))) for leg in (rising & (k > 0), falling & (k > 0))]
    centre = 0.5 * sum(at_k1)
    b, hb2 = kes.b_gf_cm2_per_cm, kes.hb2_gf_cm_per_cm
    if b is not None:
        span = np.array([lo, hi])
        ax.plot(span, centre + b * (span - k1), color="C0", lw=2, label=f"B = {b:.4g} gf·cm²/cm (slope, 0.5–1.5)")
    if hb2 is not None:
        ax.annotate("", xy=(k1, max(at_k1)), xytext=(k1, min(at_k1)),
                    arrowprops={"arrowstyle": "<->", "color": "C1", "lw": 1.5})
        ax.plot([], [], color="C1", lw=1.5, label=f"2HB = {hb2:.4g} gf·cm/cm (width at K = 1)")


def _sorted(k: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(k, kind="stable")
    return k[order], m[order]


def plot_bending_loop(recording: Recording, path: Path, variant: int = 0, kes: object | None = None, *,
                      dpi: float = DPI) -> Path:
    """The material's KES-FB2 loop ±K0 as the instrument charts it, B and 2HB marked when
    ``kes`` (an object with ``b_gf_cm2_per_cm`` and ``hb2_gf_cm_per_cm``, e.g. a
    :class:`warpcloth.calibrate.kes.BendingSummary`) is given (left), and the probed
    hinge's moment–curvature path over the run, zoomed to the path (right; Figs. 3b, 8b);
    KES units."""
    fig, (chart, zoom) = plt.subplots(1, 2, figsize=(11, 4.8))
    k, m = kes_loop(recording, variant)
    k, m = k / units.CURVATURE_PER_CM, m / units.MOMENT_GF_CM_PER_CM
    _, curvature = recording.probe("loop_curvature", variant)
    _, moment = recording.probe("loop_moment", variant)
    curvature, moment = curvature / units.CURVATURE_PER_CM, moment / units.MOMENT_GF_CM_PER_CM
    for ax in (chart, zoom):
        ax.plot(k, m, color="0.7", lw=3, label="material, KES-FB2 loop (±K0)")
        ax.axhline(0, color="0.8", lw=0.5)
        ax.axvline(0, color="0.8", lw=0.5)
        ax.set(xlabel="curvature K (cm⁻¹)", ylabel="moment per width M (gf·cm/cm)")
    if kes is not None:
        _mark_kes_values(chart, k, m, kes)
    chart.set_title("Material: the loop a KES-FB2 would chart", fontsize=9)
    chart.legend(fontsize=7, loc="upper left")
    zoom.plot(curvature, moment, lw=0.8, color="C3", label="hinge over the run")
    finite = np.isfinite(curvature) & np.isfinite(moment)
    if finite.any():
        (k_lo, k_hi), (m_lo, m_hi) = ((float(np.min(v[finite])), float(np.max(v[finite]))) for v in (curvature, moment))
        pad_k, pad_m = 0.08 * (k_hi - k_lo) or 0.01, 0.08 * (m_hi - m_lo) or 0.001
        zoom.set(xlim=(k_lo - pad_k, k_hi + pad_k), ylim=(m_lo - pad_m, m_hi + pad_m))
    hinge = recording.scenes[variant].output.loop_hinge_mm
    zoom.set_title(f"Hinge {hinge:g} mm below the clamp edge, {_label(recording, variant)} (zoomed to its path)",
                   fontsize=9)
    zoom.legend(fontsize=7)
    return _save(fig, path, dpi)


ENERGY_TERMS = (("kinetic", "kinetic"), ("gravitational", "gravitational (rel. to t=0)"), ("tensile", "tensile"),
                ("bending_elastic_work", "bending, elastic"), ("hysteresis_work", "dissipated by hysteresis"),
                ("damping_work", "dissipated by damping"), ("drive_work", "done by the clamp (−)"))


def plot_energy(recording: Recording, path: Path, variant: int = 0, *, dpi: float = DPI) -> Path:
    """Energy budget against time: each term and their sum (top), and the sum's drift
    from its start in % of the peak kinetic energy (bottom), which shows how well the
    step conserves it."""
    fig, (ax, drift) = plt.subplots(2, 1, figsize=(9.5, 6), sharex=True, height_ratios=[3, 1])
    total = 0.0
    for name, label in ENERGY_TERMS:
        t, value = recording.probe(name, variant)
        if name == "gravitational":
            value = value - value[0]
        if name == "drive_work":
            value = -value
        total = total + value
        ax.plot(t, value * 1e6, lw=1, label=label)
    ax.plot(t, total * 1e6, "k", lw=1.8, label="sum (conserved)")
    ax.set(ylabel="energy (µJ)", title=f"Energy budget, {_label(recording, variant)}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1))
    peak = float(np.nanmax(recording.probe("kinetic", variant)[1]))
    if peak > 0:
        drift.plot(t, 100 * (total - total[0]) / peak, "k", lw=1)
    drift.axhline(0, color="0.6", lw=0.6)
    drift.set(xlabel=time_label(recording), ylabel="sum − start\n(% of peak kinetic)")
    return _save(fig, path, dpi)


def plot_run(recording: Recording, out_dir: str | Path, *, measured: str | Path | None = None,
             times: np.ndarray | None = None, variant: int = 0, kes: object | None = None,
             fmt: str = "png", dpi: float = DPI, t_from: float | None = None,
             t_to: float | None = None) -> list[Path]:
    """Write every run figure into ``out_dir`` as ``fmt`` (png, pdf or svg); returns the
    paths. A ``measured`` file goes onto the figure of its kind: a laser trace onto the
    amplitude, a clamp encoder onto the clamp angle, tracked markers onto the shapes
    (:func:`warpcloth.io.measured.read_measurement`); a trace or encoder and the run are
    drawn on one window, their overlap unless ``t_from``/``t_to`` choose it
    (:func:`warpcloth.metrics.comparison_window`), which the title states.
    ``kes`` marks B and 2HB on the bending loop (:func:`plot_bending_loop`)."""

    if fmt not in FORMATS:
        raise ArgumentError("fmt", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if not (np.isfinite(dpi) and 10 <= dpi <= 2400):
        raise ArgumentError("dpi", f"must be between 10 and 2400, got {dpi!r}")
    if times is not None:
        recording.nearest_frames(times)  # an out-of-range time is refused before any figure is written
    data = read_measurement(measured, argument="measured", encoder=True) if measured else None
    window = None
    if isinstance(data, (LaserTrace, ClampAngleTrace)) or t_from is not None or t_to is not None:
        spans = {"the run": (float(recording.probes["t"].min()), float(recording.probes["t"].max()))}
        if isinstance(data, (LaserTrace, ClampAngleTrace)):
            spans[str(measured)] = (float(data.t[0]), float(data.t[-1]))
        window = comparison_window(spans, t_from, t_to)  # refused before any figure is written
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    shapes = data if isinstance(data, TrackedShapes) else None
    return [
        plot_amplitude(recording, out / f"amplitude.{fmt}", data if isinstance(data, LaserTrace) else None, dpi=dpi,
                       window=window),
        plot_clamp_angle(recording, out / f"clamp_angle.{fmt}", data if isinstance(data, ClampAngleTrace) else None,
                         dpi=dpi, window=window),
        plot_shapes(recording, out / f"shapes.{fmt}",
                    default_shape_times(recording, variant=variant) if times is None else times, variant, shapes,
                    dpi=dpi),
        plot_bending_loop(recording, out / f"bending_loop.{fmt}", variant, kes, dpi=dpi),
        plot_energy(recording, out / f"energy.{fmt}", variant, dpi=dpi),
    ]


def read_sweep_summary(sweep_dir: str | Path) -> pd.DataFrame:
    """Per-variant summary of a sweep (the merged file, or the finished batches so far)."""
    from warpcloth.io.sweep_dir import read_parquet

    sweep_dir = Path(sweep_dir)
    if not (sweep_dir / "sweep.json").is_file():
        raise DataFileError(sweep_dir, "is not a sweep directory (no sweep.json); --metric and --x plot a sweep's "
                            "summary")
    merged = sweep_dir / "summary.parquet"
    if merged.is_file():
        return read_parquet(merged)
    parts = sorted((sweep_dir / "summary").glob("batch-*.parquet"))
    if not parts:
        raise DataFileError(sweep_dir, "the sweep has no finished batch yet")
    return pd.concat([read_parquet(p) for p in parts]).sort_values("variant")


def plot_sweep(summary: pd.DataFrame, path: str | Path, metric: str, x: str, y: str | None = None, *,
               dpi: float = DPI) -> Path:
    """:func:`sweep_figure` written to ``path`` (its suffix chooses the format)."""
    return _save(sweep_figure(summary, metric, x, y), Path(path), dpi)


def sweep_figure(summary: pd.DataFrame, metric: str, x: str, y: str | None = None) -> plt.Figure:
    """A metric against one swept parameter (a line for a 1-D sweep; points coloured by
    another swept field for a sampled one; a line per value of one other gridded field
    with few values, e.g. the bending law; points and their mean when more are gridded)
    or two (heat map on a grid, categories such as the law included; coloured points
    otherwise)."""
    for argument, name in (("metric", metric), ("x", x), ("y", y)):
        if name is not None and name not in summary:
            raise ArgumentError(argument, f"{name!r} is not a column of the sweep summary; "
                             f"known: {', '.join(c for c in summary.columns if c not in ('variant', 'batch'))}")
    if y is not None and y == x:
        raise ArgumentError("y", f"{y!r} is already on the x axis; a heat map needs two different parameters")
    if summary[metric].map(lambda v: isinstance(v, (list, np.ndarray))).any():
        raise ArgumentError("metric", f"{metric!r} holds a list per variant (one value per half-cycle); plot one "
                          "number per variant, e.g. mean_log_decrement or first_amplitude_m")
    if not pd.api.types.is_numeric_dtype(summary[metric]) or pd.api.types.is_bool_dtype(summary[metric]):
        raise ArgumentError("metric", f"{metric!r} is not a number per variant (it holds "
                          f"{summary[metric].dtype}); plot a numeric column, e.g. first_period_s or mean_log_decrement")
    data = summary[~summary["diverged"]] if "diverged" in summary else summary
    valued = data[np.isfinite(data[metric].to_numpy(dtype=float))]
    if valued.empty:
        raise ArgumentError("metric", f"no variant has a value of "
                          f"{metric!r} (every one is NaN: for a period or decrement, the record may be shorter "
                          "than the swing needs, or the strip does not swing); plot another metric or run longer")
    missing, data = len(data) - len(valued), valued
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    if y is None:
        grouped = data.groupby(x)[metric]
        # swept fields are dotted scene names; others that vary make this a sample, not a curve
        others = [c for c in data.columns if "." in c and c != x and data[c].nunique() > 1]
        if grouped.size().max() == 1 and not others:
            ordered = data.sort_values(x)
            ax.plot(ordered[x], ordered[metric], "o-", ms=3)
        elif grouped.size().max() == 1:
            # a sampled sweep (Latin hypercube): points coloured by another swept field,
            # never joined in x order (that draws a zigzag through unrelated variants)
            colour = data[others[0]]
            if not pd.api.types.is_numeric_dtype(colour):  # a choice: one colour per value, in a legend
                for value, part in data.groupby(others[0], sort=False):
                    ax.scatter(part[x], part[metric], s=12, label=f"{field_label(others[0], units=False)} = {value}")
                ax.legend(fontsize=7)
            else:
                points = ax.scatter(data[x], data[metric], c=colour, s=12, cmap="viridis")
                fig.colorbar(points, ax=ax, label=field_label(others[0]))
        elif len(others) == 1 and data[others[0]].nunique() <= LEGEND_VARIANTS:
            # one other gridded field with few values (e.g. the bending law): a line each
            for value, part in data.groupby(others[0], sort=False):
                ordered = part.sort_values(x)
                shown = f"{value:g}" if isinstance(value, float) else str(value)
                label = f"{field_label(others[0], units=False)} = {shown}"
                ax.plot(ordered[x], ordered[metric], "o-", ms=3, label=label)
            ax.legend(fontsize=7)
        else:
            ax.plot(data[x], data[metric], ".", ms=3, alpha=0.6, label="variants (other parameters vary)")
            ax.plot(grouped.mean().index, grouped.mean().to_numpy(), "k-", lw=1, label="mean")
            ax.legend(fontsize=7)
        ax.set(xlabel=field_label(x), ylabel=field_label(metric))
    else:
        table = data.pivot_table(index=y, columns=x, values=metric, aggfunc="mean")
        # Colours span the 2nd–98th percentile, so one outlier does not flatten the map.
        lo, hi = np.nanpercentile(data[metric], [2, 98])
        scale = {"cmap": "viridis", "vmin": lo, "vmax": hi if hi > lo else None}
        if table.size == len(data) and not table.isna().any().any():
            # one equal cell per grid value, at 0, 1, 2, ..., labelled at its centre
            mesh = ax.pcolormesh(np.arange(table.shape[1]), np.arange(table.shape[0]), table.to_numpy(),
                                 shading="nearest", **scale)
            _cell_ticks(ax.xaxis, table.columns)
            _cell_ticks(ax.yaxis, table.index)
        else:
            mesh = ax.scatter(data[x], data[y], c=data[metric], s=14, **scale)
        fig.colorbar(mesh, ax=ax, label=field_label(metric), extend="both")
        ax.set(xlabel=field_label(x), ylabel=field_label(y))
    diverged = len(summary) - len(data) - missing
    notes = [f"{diverged} diverged"] * bool(diverged) + [f"{missing} without a value"] * bool(missing)
    ax.set_title(f"{field_label(metric, units=False)} over {len(data)} variants" + (f" ({', '.join(notes)})"
                                                                                   if notes else ""))
    return fig



HEAT_MAP_TICKS = 12
"""A heat-map axis labels at most this many of its cells (every k-th beyond)."""


def _cell_ticks(axis: matplotlib.axis.Axis, values: pd.Index) -> None:
    # The grid's cells are drawn one per value at 0, 1, 2, ...: a tick at the centre of
    # each, labelled with the swept value it holds. On the values' own scale an uneven
    # grid's cells would be uneven and a value's tick off its cell's centre (the cell
    # edges lie halfway to the neighbours), and the locator's round numbers fell anywhere.
    step = -(-len(values) // HEAT_MAP_TICKS)
    shown = range(0, len(values), step)
    axis.set_ticks(list(shown), [f"{values[i]:.4g}" if isinstance(values[i], float) else str(values[i])
                                 for i in shown])


def plot_fit_overlay(result: object, objective: object, measurement: LaserTrace | TrackedShapes, fit: object,
                     path: Path) -> Path:
    """Measured against the best fit: the laser trace and its residual, or tracked
    markers over the simulated strip at six of the measured frames (on the measured clock)."""
    shift = fit.shift_s
    title = ", ".join(f"{field_label(k, units=False)} = {v:.4g} ± {fit.sigma[k]:.2g} {field_unit(k)}".rstrip()
                      for k, v in fit.parameters.items())
    if isinstance(measurement, LaserTrace):
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, height_ratios=[3, 1])
        top.plot(measurement.t, measurement.x * MM, "k.", ms=2.5, label="measured")
        window = (float(measurement.t[0]), float(measurement.t[-1]))  # the fit's own: the measured record
        keep = _inside(result.t - shift, window)
        top.plot((result.t - shift)[keep], result.probe("laser_x", 0)[keep] * MM, "C3", lw=1.2, label="best fit")
        top.set(ylabel="x at the laser line (mm)")
        top.legend(fontsize=7)
        residual = objective.residuals(result, 0, shift, penalise=False)
        bottom.plot(measurement.t, residual * MM, "C0.", ms=2)
        bottom.axhline(0, color="0.6", lw=0.6)
        bottom.set(xlabel="measured time (s)", ylabel="residual (mm)")
        top.set_title(f"RMS {fit.rms * MM:.3g} mm on t = {window[0]:g} … {window[1]:g} s (the measured record); "
                      f"{title}", fontsize=8)
        return _save(fig, path)
    fig, ax = plt.subplots(figsize=(6.5, 6))
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
    ax.set(xlabel=X_LABEL, ylabel=Y_LABEL)
    ax.set_title(f"markers (o) vs best fit (lines); RMS {fit.rms * MM:.3g} mm on t = {measurement.t.min():g} … "
                 f"{measurement.t.max():g} s (the measured record)\n{title}", fontsize=8)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1), title="measured t", title_fontsize=7)
    return _save(fig, path)


SIGMA_STYLES = {1: "-", 2: "--"}
"""Each uncertainty ellipse of :func:`fit_search_figure` (k σ) and its line style, so the
legend tells the 1σ and the 2σ region apart."""


def fit_search_figure(fit: object, truth: dict[str, float] | None = None) -> plt.Figure:
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
    inset = ax.inset_axes([0.1, 0.08, 0.38, 0.3])
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


def plot_clamp_fit(t: np.ndarray, theta: np.ndarray, fit: object, path: Path) -> Path:
    """Encoder angle and the fitted θ(t) (rest, quartic, lines, stop), breakpoints marked."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5), sharex=True, height_ratios=[3, 1])
    top.plot(t, np.degrees(theta), "k.", ms=2.5, label="encoder")
    top.plot(t, np.degrees(fit.theta(t)), "C3", lw=1.2, label=fit.form)
    for when in fit.breakpoints_s:
        top.axvline(when, color="0.7", lw=0.6, ls="--")
    top.set(ylabel="θ (deg)", title=f"clamp motion fit, RMS {np.degrees(fit.rms_rad):.3g}° "
            f"(noise {np.degrees(fit.noise_rad):.2g}°): {fit.status}")
    top.legend(fontsize=7)
    bottom.plot(t, np.degrees(theta - fit.theta(t)), "C0.", ms=2)
    bottom.axhline(0, color="0.6", lw=0.6)
    bottom.set(xlabel="t (s)", ylabel="residual (deg)")
    return _save(fig, path)


def plot_kes_fit(fit: object, path: str | Path) -> Path:
    """PNG of a KES fit (a :class:`warpcloth.calibrate.kes.KesFit`) against its data:
    tensile (left) and bending (right), the KES values in the titles."""
    from matplotlib.figure import Figure  # no pyplot: no global backend state

    path = Path(path)
    figure = Figure(figsize=(11, 4.6), dpi=120, layout="constrained")
    left, right = figure.subplots(1, 2)
    tl, tk, tf = fit.tensile_loop, fit.tensile_kes, fit.tensile
    left.plot(tl.strain / units.STRAIN_PERCENT, tl.force, ".", ms=3, color="0.4", label="data")
    e = np.linspace(0.0, float(tl.strain.max()), 200)
    left.plot(e / units.STRAIN_PERCENT, tf(e), "-", color="C0", label="quartic fit (loading)")
    rt = f", RT {tk.rt_percent:.1f} %" if tk.rt_percent is not None else ""
    left.set_title(f"KES-FB1: EMT {tk.emt_percent:.2f} %, LT {tk.lt:.3f}, WT {tk.wt_gf_cm_per_cm2:.3g} "
                   f"gf·cm/cm²{rt}", fontsize=9)
    left.set_xlabel("strain (%)")
    left.set_ylabel("force per width T (gf/cm)")
    a = ", ".join(f"{c:.4g}" for c in tf.coefficients)
    left.text(0.03, 0.97, f"a = ({a}) gf/cm\nRMS {tf.rms_gf_per_cm:.3g} gf/cm ({tf.rms_relative:.2%} of range)"
              + ("\nconstrained to increase" if tf.constrained else ""),
              transform=left.transAxes, va="top", fontsize=8, bbox={"fc": "white", "alpha": 0.8})
    left.legend(loc="lower right", fontsize=8)
    bl, bk, bf = fit.bending_loop, fit.bending_kes, fit.bending
    right.plot(bl.curvature, bl.moment, ".", ms=3, color="0.4", label="data")
    right.plot(bl.curvature, bf.moment, "-", color="C3", label="model fit")
    b = f"{bk.b_gf_cm2_per_cm:.4g}" if bk.b_gf_cm2_per_cm is not None else "n/a"
    hb = f"{bk.hb2_gf_cm_per_cm:.4g}" if bk.hb2_gf_cm_per_cm is not None else "n/a"
    right.set_title(f"KES-FB2: B {b} gf·cm²/cm, 2HB {hb} gf·cm/cm", fontsize=9)
    right.set_xlabel("curvature K (1/cm)")
    right.set_ylabel("moment per width M (gf·cm/cm)")
    right.text(0.03, 0.97, f"D {bf.rigidity_gf_cm2_per_cm:.4g} gf·cm²/cm, D1 {bf.d1_gf_cm_per_cm:.4g} gf·cm/cm\n"
               f"α {bf.alpha_cm:.4g} cm, K0 {bf.k0_per_cm:.4g} 1/cm\n"
               f"RMS {bf.rms_gf_cm_per_cm:.3g} gf·cm/cm ({bf.rms_relative:.2%} of range)",
               transform=right.transAxes, va="top", fontsize=8, bbox={"fc": "white", "alpha": 0.8})
    right.legend(loc="lower right", fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomically(path, figure.savefig)
    return path


RESIDUAL_MEAN_POINTS = 15
"""The bending-law comparison's residual panel: running mean over this many points."""


def bending_law_comparison_figure(comparison: object) -> plt.Figure:
    """Each bending law fitted to one KES-FB2 loop (a
    :class:`warpcloth.calibrate.kes.LawComparison`): the fits over the measured loop (top
    left; the legend gives each law's RMS and ΔAIC), the same with the data's centre line
    B K taken away so the loops' shapes show (top right), and the residuals along the
    cycle (bottom: each point thin, a running mean thick, so a law's systematic misfit
    stands out of the noise); the title gives the recommendation and the data's B and 2HB."""
    loop, delta, measured = comparison.loop, comparison.delta_aic(), comparison.measured
    fig, axes = plt.subplot_mosaic([["loop", "shape"], ["residual", "residual"]], figsize=(11.0, 7.6),
                                   height_ratios=(1.6, 1.0))
    slope = measured.b_gf_cm2_per_cm if measured.b_gf_cm2_per_cm is not None else 0.0
    k, index = loop.curvature, np.arange(len(loop.curvature))
    window = np.ones(min(RESIDUAL_MEAN_POINTS, len(index)))
    counts = np.convolve(np.ones(len(index)), window, mode="same")  # fewer points near the ends
    for name, centre in (("loop", 0.0), ("shape", slope)):
        axes[name].plot(k, loop.moment - centre * k, ".", ms=2.5, color="0.6", label="KES-FB2 data", zorder=1)
    for j, (law, fit) in enumerate(comparison.fits.items()):
        axes["loop"].plot(k, fit.moment, color=f"C{j}", lw=1.2, zorder=2,
                          label=f"{law} (k = {fit.free_parameters}): RMS {fit.rms_gf_cm_per_cm:.3g} gf·cm/cm, "
                          f"ΔAIC {delta[law]:.1f}")
        axes["shape"].plot(k, fit.moment - slope * k, color=f"C{j}", lw=1.2, zorder=2, label=law)
        residual = fit.moment - loop.moment
        axes["residual"].plot(index, residual, color=f"C{j}", lw=0.5, alpha=0.2)
        axes["residual"].plot(index, np.convolve(residual, window, mode="same") / counts, color=f"C{j}", lw=1.5,
                              label=law)
    for leg in loop.legs()[1:]:
        axes["residual"].axvline(leg.start, color="0.7", lw=0.6, ls=":")
    for ax in axes.values():
        ax.axhline(0.0, color="0.8", lw=0.5)
    kes = ", ".join(f"{name} {value:.4g} {unit}" for name, value, unit in
                    (("B", measured.b_gf_cm2_per_cm, "gf·cm²/cm"), ("2HB", measured.hb2_gf_cm_per_cm, "gf·cm/cm"))
                    if value is not None)
    axes["loop"].set(xlabel="curvature K (1/cm)", ylabel="moment per width M (gf·cm/cm)",
                     title=f"{Path(loop.source).name}: "
                     + (f"AIC recommends {comparison.recommended}" if len(comparison.fits) > 1
                        else f"{comparison.recommended} fitted (one law: no comparison)")
                     + (f"\ndata: {kes}" if kes else ""))
    axes["loop"].legend(fontsize=7, loc="lower right")
    axes["shape"].set(xlabel="curvature K (1/cm)", ylabel=f"M − {slope:.4g} K (gf·cm/cm)",
                      title="the loops without the data's centre line B K")
    axes["shape"].legend(fontsize=7, loc="center", bbox_to_anchor=(0.27, 0.5))
    axes["residual"].set(xlabel="point along the cycle (dotted: the turns at +K0 and −K0)",
                         ylabel="model − data (gf·cm/cm)",
                         title=f"residuals (thin: each point; thick: running mean over {len(window)} points)")
    axes["residual"].legend(fontsize=7, ncols=len(comparison.fits))
    for ax in axes.values():
        ax.title.set_fontsize(9)
    fig.tight_layout()
    return fig


def plot_bending_law_comparison(comparison: object, path: str | Path, *, dpi: float = DPI) -> Path:
    """:func:`bending_law_comparison_figure` written to ``path`` (its suffix chooses the format)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return _save(bending_law_comparison_figure(comparison), path, dpi)
