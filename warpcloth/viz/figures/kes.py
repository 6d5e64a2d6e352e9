"""The figures of bending and KES data: a run's material loop as a KES-FB2 charts it and
its hinge's path (the paper's Figs. 3b, 8b), a KES fit against its data, and bending laws
compared on one loop.

The results they draw come from :mod:`warpcloth.calibrate.kes`, a layer above this one:
they are typed by the :class:`~typing.Protocol` of the fields each figure reads
(:class:`KesValues`, :class:`KesFitResult`, :class:`LawComparisonResult`), which the
calibration's dataclasses meet without either importing the other.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Protocol

import numpy as np

from warpcloth import units
from warpcloth.io.atomic import write_atomically
from warpcloth.io.recording import Recording
from warpcloth.scene import to_si
from warpcloth.strip import moment_along_path

from . import common
from .common import DPI, plt, variant_label


class KesValues(Protocol):
    """A loop's KES-FB2 values, None where it does not reach the curvatures they need
    (:class:`warpcloth.calibrate.kes.BendingSummary`)."""

    @property
    def b_gf_cm2_per_cm(self) -> float | None: ...
    @property
    def hb2_gf_cm_per_cm(self) -> float | None: ...


class TensileValues(Protocol):
    """A loop's KES-FB1 values (:class:`warpcloth.calibrate.kes.TensileSummary`)."""

    @property
    def emt_percent(self) -> float: ...
    @property
    def lt(self) -> float: ...
    @property
    def wt_gf_cm_per_cm2(self) -> float: ...
    @property
    def rt_percent(self) -> float | None: ...


class TensileData(Protocol):
    """A measured KES-FB1 loop (:class:`warpcloth.calibrate.kes.TensileLoop`): strain as
    a fraction, force per width in gf/cm."""

    @property
    def strain(self) -> np.ndarray: ...
    @property
    def force(self) -> np.ndarray: ...


class TensileCurve(Protocol):
    """The quartic T(ε) fitted to a loading branch (:class:`warpcloth.calibrate.kes.TensileFit`)."""

    @property
    def coefficients(self) -> list[float]: ...
    @property
    def rms_gf_per_cm(self) -> float: ...
    @property
    def rms_relative(self) -> float: ...
    @property
    def constrained(self) -> bool: ...
    def __call__(self, strain: np.ndarray) -> np.ndarray: ...


class BendingData(Protocol):
    """A measured KES-FB2 loop (:class:`warpcloth.calibrate.kes.BendingLoop`): curvature
    in 1/cm, moment per width in gf·cm/cm."""

    @property
    def curvature(self) -> np.ndarray: ...
    @property
    def moment(self) -> np.ndarray: ...
    @property
    def source(self) -> str: ...
    def legs(self) -> list[slice]: ...


class BendingCurve(Protocol):
    """A bending law fitted to a loop (:class:`warpcloth.calibrate.kes.BendingFit`): its
    moment along the measured path (gf·cm/cm), how well, and its number of free parameters."""

    @property
    def moment(self) -> np.ndarray: ...
    @property
    def rms_gf_cm_per_cm(self) -> float: ...
    @property
    def rms_relative(self) -> float: ...
    @property
    def free_parameters(self) -> int: ...


class Tagawa2003Curve(BendingCurve, Protocol):
    """The paper's law fitted to a loop, with its four parameters in KES units."""

    @property
    def rigidity_gf_cm2_per_cm(self) -> float: ...
    @property
    def d1_gf_cm_per_cm(self) -> float: ...
    @property
    def alpha_cm(self) -> float: ...
    @property
    def k0_per_cm(self) -> float: ...


class KesFitResult(Protocol):
    """A KES fit of the paper's law (:class:`warpcloth.calibrate.kes.KesFit`): both loops,
    both fits, both loops' KES values."""

    @property
    def tensile_loop(self) -> TensileData: ...
    @property
    def tensile(self) -> TensileCurve: ...
    @property
    def tensile_kes(self) -> TensileValues: ...
    @property
    def bending_loop(self) -> BendingData: ...
    @property
    def bending(self) -> Tagawa2003Curve: ...
    @property
    def bending_kes(self) -> KesValues: ...


class LawComparisonResult(Protocol):
    """Bending laws fitted to one loop (:class:`warpcloth.calibrate.kes.LawComparison`)."""

    @property
    def loop(self) -> BendingData: ...
    @property
    def fits(self) -> Mapping[str, BendingCurve]: ...
    @property
    def measured(self) -> KesValues: ...
    @property
    def recommended(self) -> str: ...
    def delta_aic(self) -> dict[str, float]: ...


def kes_loop(recording: Recording, variant: int = 0, samples: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """The material's KES-FB2 loop (0 → K0 → −K0 → K0): curvature (1/m), moment (N·m/m)."""
    material = to_si(recording.scenes[variant].material)
    # a law whose loop closes at a curvature of its own (the paper's K0) is charted there, the
    # others on the standard cycle
    closure = material.bending.description.loop_closure
    k0 = material.bending[closure] if closure else KES_K0_PER_CM * units.CURVATURE_PER_CM
    path = np.concatenate(
        [np.linspace(0, k0, samples), np.linspace(k0, -k0, 2 * samples)[1:], np.linspace(-k0, k0, 2 * samples)[1:]]
    )
    moment, _ = moment_along_path(material, path)
    return path, moment


KES_K0_PER_CM = 2.5
"""The standard KES-FB2 cycle's largest curvature (1/cm)."""

KES_B_RANGE_PER_CM = (0.5, 1.5)
"""Where KES-FB2 reads B (the slope) and 2HB (the loop's width, at the middle: K = ±1 1/cm)."""


def _mark_kes_values(ax: plt.Axes, k: np.ndarray, m: np.ndarray, kes: KesValues) -> None:
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
        ax.annotate(
            "", xy=(k1, max(at_k1)), xytext=(k1, min(at_k1)), arrowprops={"arrowstyle": "<->", "color": "C1", "lw": 1.5}
        )
        ax.plot([], [], color="C1", lw=1.5, label=f"2HB = {hb2:.4g} gf·cm/cm (width at K = 1)")


def _sorted(k: np.ndarray, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    order = np.argsort(k, kind="stable")
    return k[order], m[order]


def plot_bending_loop(
    recording: Recording, path: Path, variant: int = 0, kes: KesValues | None = None, *, dpi: float = DPI
) -> Path:
    """The material's KES-FB2 loop ±K0 as the instrument charts it, B and 2HB marked when
    ``kes`` (:class:`KesValues`, e.g. a :class:`warpcloth.calibrate.kes.BendingSummary`) is given (left), and the probed
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
    zoom.set_title(
        f"Hinge {hinge:g} mm below the clamp edge, {variant_label(recording, variant)} (zoomed to its path)", fontsize=9
    )
    zoom.legend(fontsize=7)
    return common.save(fig, path, dpi)


def plot_kes_fit(fit: KesFitResult, path: str | Path) -> Path:
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
    left.set_title(
        f"KES-FB1: EMT {tk.emt_percent:.2f} %, LT {tk.lt:.3f}, WT {tk.wt_gf_cm_per_cm2:.3g} gf·cm/cm²{rt}", fontsize=9
    )
    left.set_xlabel("strain (%)")
    left.set_ylabel("force per width T (gf/cm)")
    a = ", ".join(f"{c:.4g}" for c in tf.coefficients)
    left.text(
        0.03,
        0.97,
        f"a = ({a}) gf/cm\nRMS {tf.rms_gf_per_cm:.3g} gf/cm ({tf.rms_relative:.2%} of range)"
        + ("\nconstrained to increase" if tf.constrained else ""),
        transform=left.transAxes,
        va="top",
        fontsize=8,
        bbox={"fc": "white", "alpha": 0.8},
    )
    left.legend(loc="lower right", fontsize=8)
    bl, bk, bf = fit.bending_loop, fit.bending_kes, fit.bending
    right.plot(bl.curvature, bl.moment, ".", ms=3, color="0.4", label="data")
    right.plot(bl.curvature, bf.moment, "-", color="C3", label="model fit")
    b = f"{bk.b_gf_cm2_per_cm:.4g}" if bk.b_gf_cm2_per_cm is not None else "n/a"
    hb = f"{bk.hb2_gf_cm_per_cm:.4g}" if bk.hb2_gf_cm_per_cm is not None else "n/a"
    right.set_title(f"KES-FB2: B {b} gf·cm²/cm, 2HB {hb} gf·cm/cm", fontsize=9)
    right.set_xlabel("curvature K (1/cm)")
    right.set_ylabel("moment per width M (gf·cm/cm)")
    right.text(
        0.03,
        0.97,
        f"D {bf.rigidity_gf_cm2_per_cm:.4g} gf·cm²/cm, D1 {bf.d1_gf_cm_per_cm:.4g} gf·cm/cm\n"
        f"α {bf.alpha_cm:.4g} cm, K0 {bf.k0_per_cm:.4g} 1/cm\n"
        f"RMS {bf.rms_gf_cm_per_cm:.3g} gf·cm/cm ({bf.rms_relative:.2%} of range)",
        transform=right.transAxes,
        va="top",
        fontsize=8,
        bbox={"fc": "white", "alpha": 0.8},
    )
    right.legend(loc="lower right", fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_atomically(path, figure.savefig)
    return path


RESIDUAL_MEAN_POINTS = 15
"""The bending-law comparison's residual panel: running mean over this many points."""


def bending_law_comparison_figure(comparison: LawComparisonResult) -> plt.Figure:
    """Each bending law fitted to one KES-FB2 loop (a
    :class:`warpcloth.calibrate.kes.LawComparison`): the fits over the measured loop (top
    left; the legend gives each law's RMS and ΔAIC), the same with the data's centre line
    B K taken away so the loops' shapes show (top right), and the residuals along the
    cycle (bottom: each point thin, a running mean thick, so a law's systematic misfit
    stands out of the noise); the title gives the recommendation and the data's B and 2HB."""
    loop, delta, measured = comparison.loop, comparison.delta_aic(), comparison.measured
    fig, axes = plt.subplot_mosaic(
        [["loop", "shape"], ["residual", "residual"]], figsize=(11.0, 7.6), height_ratios=(1.6, 1.0)
    )
    slope = measured.b_gf_cm2_per_cm if measured.b_gf_cm2_per_cm is not None else 0.0
    k, index = loop.curvature, np.arange(len(loop.curvature))
    window = np.ones(min(RESIDUAL_MEAN_POINTS, len(index)))
    counts = np.convolve(np.ones(len(index)), window, mode="same")  # fewer points near the ends
    for name, centre in (("loop", 0.0), ("shape", slope)):
        axes[name].plot(k, loop.moment - centre * k, ".", ms=2.5, color="0.6", label="KES-FB2 data", zorder=1)
    for j, (law, fit) in enumerate(comparison.fits.items()):
        axes["loop"].plot(
            k,
            fit.moment,
            color=f"C{j}",
            lw=1.2,
            zorder=2,
            label=f"{law} (k = {fit.free_parameters}): RMS {fit.rms_gf_cm_per_cm:.3g} gf·cm/cm, ΔAIC {delta[law]:.1f}",
        )
        axes["shape"].plot(k, fit.moment - slope * k, color=f"C{j}", lw=1.2, zorder=2, label=law)
        residual = fit.moment - loop.moment
        axes["residual"].plot(index, residual, color=f"C{j}", lw=0.5, alpha=0.2)
        axes["residual"].plot(
            index, np.convolve(residual, window, mode="same") / counts, color=f"C{j}", lw=1.5, label=law
        )
    for leg in loop.legs()[1:]:
        axes["residual"].axvline(leg.start, color="0.7", lw=0.6, ls=":")
    for ax in axes.values():
        ax.axhline(0.0, color="0.8", lw=0.5)
    kes = ", ".join(
        f"{name} {value:.4g} {unit}"
        for name, value, unit in (
            ("B", measured.b_gf_cm2_per_cm, "gf·cm²/cm"),
            ("2HB", measured.hb2_gf_cm_per_cm, "gf·cm/cm"),
        )
        if value is not None
    )
    axes["loop"].set(
        xlabel="curvature K (1/cm)",
        ylabel="moment per width M (gf·cm/cm)",
        title=f"{Path(loop.source).name}: "
        + (
            f"AIC recommends {comparison.recommended}"
            if len(comparison.fits) > 1
            else f"{comparison.recommended} fitted (one law: no comparison)"
        )
        + (f"\ndata: {kes}" if kes else ""),
    )
    axes["loop"].legend(fontsize=7, loc="lower right")
    axes["shape"].set(
        xlabel="curvature K (1/cm)",
        ylabel=f"M − {slope:.4g} K (gf·cm/cm)",
        title="the loops without the data's centre line B K",
    )
    axes["shape"].legend(fontsize=7, loc="center", bbox_to_anchor=(0.27, 0.5))
    axes["residual"].set(
        xlabel="point along the cycle (dotted: the turns at +K0 and −K0)",
        ylabel="model − data (gf·cm/cm)",
        title=f"residuals (thin: each point; thick: running mean over {len(window)} points)",
    )
    axes["residual"].legend(fontsize=7, ncols=len(comparison.fits))
    for ax in axes.values():
        ax.title.set_fontsize(9)
    fig.tight_layout()
    return fig


def plot_bending_law_comparison(comparison: LawComparisonResult, path: str | Path, *, dpi: float = DPI) -> Path:
    """:func:`bending_law_comparison_figure` written to ``path`` (its suffix chooses the format)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return common.save(bending_law_comparison_figure(comparison), path, dpi)
