"""2D figures of a run (the paper's Figs. 3b/8b, 9/11, 10, 12 and the energy budget), of
a sweep (a metric against one or two parameters) and of fits (the motion, the clamp
angle, a KES material), as PNG files, headless.

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
from warpcloth.errors import DataFileError, OptionError  # noqa: E402
from warpcloth.io.atomic import write_atomically  # noqa: E402
from warpcloth.io.measured import LaserTrace, TrackedShapes, read_laser_trace  # noqa: E402
from warpcloth.io.recording import Recording  # noqa: E402
from warpcloth.scene import to_si  # noqa: E402
from warpcloth.sim import moment_along_path  # noqa: E402

MM = 1 / units.LENGTH_MM
DPI = 120


def _label(recording: Recording, j: int) -> str:
    varying = [c for c in recording.parameters.columns
               if c != "variant" and recording.parameters[c].nunique() > 1][:2]
    parts = [f"{c.split('.')[-1]}={recording.parameters[c].iloc[j]:.3g}" for c in varying]
    return f"variant {recording.variants[j]}" + (f" ({', '.join(parts)})" if parts else "")


FIELD_LABELS = {
    "damping.gamma_per_s": ("γ", "s⁻¹"),
    "material.bending_rigidity_gf_cm2_per_cm": ("B = D", "gf·cm²/cm"),
    "material.hysteresis_d1_gf_cm_per_cm": ("D1", "gf·cm/cm"),
    "material.hysteresis_alpha_cm": ("α", "cm"),
    "material.hysteresis_k0_per_cm": ("K0", "cm⁻¹"),
    "material.density_g_per_cm2": ("ρ_A", "g/cm²"),
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


def _save(fig: plt.Figure, path: Path) -> Path:
    fig.tight_layout()
    write_atomically(path, lambda tmp: fig.savefig(tmp, dpi=DPI))
    plt.close(fig)
    return path


def plot_amplitude(recording: Recording, path: Path, measured: LaserTrace | None = None) -> Path:
    """Laser-line displacement (and free-end x) against time, as in the paper's Fig. 10."""
    fig, ax = plt.subplots(figsize=(8, 4))
    laser_mm = recording.scenes[0].output.laser_height_mm
    for j in range(len(recording.variants)):
        t, laser = recording.probe("laser_x", j)
        line, = ax.plot(t, laser * MM, lw=1.2, label=f"{_label(recording, j)}: laser line")
        if len(recording.variants) == 1:
            t, tip = recording.probe("tip_x", j)
            ax.plot(t, tip * MM, lw=0.8, ls="--", color=line.get_color(), alpha=0.6, label="free end x")
    if measured is not None:
        ax.plot(measured.t, measured.x * MM, "k.", ms=2.5, label="measured")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.set(xlabel="time after release t (s)", ylabel="x (mm)",
           title=f"Displacement at the laser line ({laser_mm:g} mm below the clamp)")
    ax.legend(fontsize=7, loc="upper right")
    return _save(fig, path)


def plot_clamp_angle(recording: Recording, path: Path) -> Path:
    """Clamp rotation angle against time, as in the paper's Fig. 12."""
    fig, ax = plt.subplots(figsize=(6, 4))
    for j in range(len(recording.variants)):
        t, theta = recording.probe("clamp_angle", j)
        ax.plot(t, np.degrees(theta), lw=1.2, label=_label(recording, j))
    ax.set(xlabel="t (s)", ylabel="clamp angle θ (deg)", title="Clamp rotation")
    ax.legend(fontsize=7)
    return _save(fig, path)


def default_shape_times(recording: Recording, count: int = 10) -> np.ndarray:
    """``count`` frame times spread evenly over the run."""
    return np.linspace(recording.frame_times[0], recording.frame_times[-1], count)


def plot_shapes(recording: Recording, path: Path, times: np.ndarray, variant: int = 0) -> Path:
    """Stroboscopic overlay of the strip's shape at ``times`` (Figs. 9, 11)."""
    fig, ax = plt.subplots(figsize=(6.5, 6))
    frames = np.unique(recording.nearest_frames(times))
    colours = plt.cm.viridis(np.linspace(0, 1, len(frames)))
    nc = recording.n_clamped
    for colour, f in zip(colours, frames, strict=True):
        xy = recording.frames[f, variant] * MM
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=colour, lw=1.4, label=f"{recording.frame_times[f]:.3f} s")
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.25", lw=4, solid_capstyle="butt")
    ax.set_aspect("equal")
    ax.set(xlabel="x (mm)", ylabel="y (mm)", title=f"Strip shapes, {_label(recording, variant)}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1), title="t after release", title_fontsize=7)
    return _save(fig, path)


def kes_loop(recording: Recording, variant: int = 0, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """The material's KES-FB2 loop (0 → K0 → −K0 → K0): curvature (1/m), moment (N·m/m)."""
    material = to_si(recording.scenes[variant].material)
    k0 = material.hysteresis_k0
    path = np.concatenate([np.linspace(0, k0, samples), np.linspace(k0, -k0, 2 * samples)[1:],
                           np.linspace(-k0, k0, 2 * samples)[1:]])
    moment, _ = moment_along_path(material, path)
    return path, moment


def plot_bending_loop(recording: Recording, path: Path, variant: int = 0) -> Path:
    """Moment–curvature path of the probed hinge over the run, over the material's KES
    loop (Figs. 3b, 8b), in KES units."""
    fig, ax = plt.subplots(figsize=(6, 5))
    k, m = kes_loop(recording, variant)
    ax.plot(k / units.CURVATURE_PER_CM, m / units.MOMENT_GF_CM_PER_CM, color="0.7", lw=3,
            label="material (KES-FB2 loop, ±K0)")
    _, curvature = recording.probe("loop_curvature", variant)
    _, moment = recording.probe("loop_moment", variant)
    ax.plot(curvature / units.CURVATURE_PER_CM, moment / units.MOMENT_GF_CM_PER_CM, lw=0.8, color="C3",
            label="hinge over the run")
    hinge = recording.scenes[variant].output.loop_hinge_mm
    ax.axhline(0, color="0.8", lw=0.5)
    ax.axvline(0, color="0.8", lw=0.5)
    ax.set(xlabel="curvature K (1/cm)", ylabel="moment M (gf·cm/cm)",
           title=f"Bending loop, hinge {hinge:g} mm below the clamp, {_label(recording, variant)}")
    ax.legend(fontsize=7)
    return _save(fig, path)


ENERGY_TERMS = (("kinetic", "kinetic"), ("gravitational", "gravitational (rel. to t=0)"), ("tensile", "tensile"),
                ("bending_elastic_work", "bending, elastic"), ("hysteresis_work", "dissipated by hysteresis"),
                ("damping_work", "dissipated by damping"), ("drive_work", "done by the clamp (−)"))


def plot_energy(recording: Recording, path: Path, variant: int = 0) -> Path:
    """Energy budget against time: each term and their sum, which should stay constant."""
    fig, ax = plt.subplots(figsize=(9.5, 4.5))
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
    ax.set(xlabel="t (s)", ylabel="energy (µJ)", title=f"Energy budget, {_label(recording, variant)}")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1))
    return _save(fig, path)


def plot_run(recording: Recording, out_dir: str | Path, *, measured: str | Path | None = None,
             times: np.ndarray | None = None, variant: int = 0) -> list[Path]:
    """Write every run figure into ``out_dir``; returns the PNG paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    series = read_laser_trace(measured) if measured else None
    return [
        plot_amplitude(recording, out / "amplitude.png", series),
        plot_clamp_angle(recording, out / "clamp_angle.png"),
        plot_shapes(recording, out / "shapes.png", default_shape_times(recording) if times is None else times,
                    variant),
        plot_bending_loop(recording, out / "bending_loop.png", variant),
        plot_energy(recording, out / "energy.png", variant),
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


def plot_sweep(summary: pd.DataFrame, path: str | Path, metric: str, x: str, y: str | None = None) -> Path:
    """PNG of :func:`sweep_figure`."""
    return _save(sweep_figure(summary, metric, x, y), Path(path))


def sweep_figure(summary: pd.DataFrame, metric: str, x: str, y: str | None = None) -> plt.Figure:
    """A metric against one swept parameter (a line for a 1-D sweep; points coloured by
    another swept field for a sampled one; points and their mean when others are gridded)
    or two (heat map on a grid, coloured points otherwise)."""
    for name, flag in ((metric, "--metric"), (x, "--x"), (y, "--y")):
        if name is not None and name not in summary:
            raise OptionError(flag, f"{name!r} is not a column of the sweep summary; "
                             f"known: {', '.join(c for c in summary.columns if c not in ('variant', 'batch'))}")
    if y is not None and y == x:
        raise OptionError("--y", f"{y!r} is already on the x axis; a heat map needs two different parameters")
    if summary[metric].map(lambda v: isinstance(v, (list, np.ndarray))).any():
        raise OptionError("--metric", f"{metric!r} holds a list per variant (one value per half-cycle); plot one "
                          "number per variant, e.g. mean_log_decrement or first_amplitude_m")
    data = summary[~summary["diverged"]] if "diverged" in summary else summary
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
            points = ax.scatter(data[x], data[metric], c=data[others[0]], s=12, cmap="viridis")
            fig.colorbar(points, ax=ax, label=field_label(others[0]))
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
            mesh = ax.pcolormesh(table.columns, table.index, table.to_numpy(), shading="nearest", **scale)
        else:
            mesh = ax.scatter(data[x], data[y], c=data[metric], s=14, **scale)
        fig.colorbar(mesh, ax=ax, label=field_label(metric), extend="both")
        ax.set(xlabel=field_label(x), ylabel=field_label(y))
    ax.set_title(f"{metric} over {len(data)} variants" + (f" ({len(summary) - len(data)} diverged)"
                                                           if len(data) < len(summary) else ""))
    return fig



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
        top.plot(result.t - shift, result.probe("laser_x", 0) * MM, "C3", lw=1.2, label="best fit")
        top.set(ylabel="x at the laser line (mm)")
        top.legend(fontsize=7)
        residual = objective.residuals(result, 0, shift, penalise=False)
        bottom.plot(measurement.t, residual * MM, "C0.", ms=2)
        bottom.axhline(0, color="0.6", lw=0.6)
        bottom.set(xlabel="measured time (s)", ylabel="residual (mm)")
        top.set_title(f"RMS {fit.rms * MM:.3g} mm; {title}", fontsize=8)
        return _save(fig, path)
    fig, ax = plt.subplots(figsize=(6.5, 6))
    frames = np.unique(measurement.frame)
    chosen = frames[np.linspace(0, len(frames) - 1, min(6, len(frames))).round().astype(int)]
    edge = objective.edge
    for colour, f in zip(plt.cm.viridis(np.linspace(0, 1, len(chosen))), chosen, strict=True):
        rows = measurement.frame == f
        t = measurement.t[rows][0]
        k = int(np.abs(result.frame_times - (t + shift)).argmin())
        xy = (result.frames[k, 0] - edge) * MM
        nc = objective.scene.n_clamped
        ax.plot(xy[nc - 1 :, 0], xy[nc - 1 :, 1], color=colour, lw=1.2, label=f"{t:.3f} s")
        ax.plot(xy[:nc, 0], xy[:nc, 1], color="0.25", lw=3)
        ax.plot(measurement.x[rows] * MM, measurement.y[rows] * MM, "o", color=colour, ms=3.5, mfc="none")
    ax.set_aspect("equal")
    ax.set(xlabel="x from the clamp's lowest point (mm)", ylabel="y (mm)")
    ax.set_title(f"markers (o) vs best fit (lines); RMS {fit.rms * MM:.3g} mm\n{title}", fontsize=8)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1), title="measured t", title_fontsize=7)
    return _save(fig, path)


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
