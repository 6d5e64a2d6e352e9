"""2D figures of a run (the paper's Figs. 3b/8b, 9/11, 10, 12 and the energy budget), of
a sweep (a metric against one or two parameters) and of fits (the motion, the clamp
angle, a KES material), headless, as PNG (or PDF, SVG: :data:`warpcloth.viz.FORMATS`).

Axes are in the units a textile lab reads: mm, degrees, and KES units for the bending
loop (curvature in 1/cm, moment per width in gf·cm/cm), converted via ``units``.

This is the public import path; the figures live in :mod:`warpcloth.viz.figures`, one
module per subject. Fit and KES results are typed by the protocols there
(:class:`MotionFit`, :class:`ClampFit`, :class:`KesFitResult`, ...): the fields each
figure reads.
"""

from __future__ import annotations

from warpcloth.viz.figures.common import (
    DPI,
    FIELD_LABELS,
    FORMATS,
    LEGEND_VARIANTS,
    MM,
    X_LABEL,
    Y_LABEL,
    field_label,
    field_unit,
    time_label,
)
from warpcloth.viz.figures.fits import (
    SIGMA_STYLES,
    ClampFit,
    FitResiduals,
    MotionFit,
    fit_search_figure,
    plot_clamp_fit,
    plot_fit_overlay,
)
from warpcloth.viz.figures.kes import (
    KES_B_RANGE_PER_CM,
    KES_K0_PER_CM,
    RESIDUAL_MEAN_POINTS,
    KesFitResult,
    KesValues,
    LawComparisonResult,
    bending_law_comparison_figure,
    kes_loop,
    plot_bending_law_comparison,
    plot_bending_loop,
    plot_kes_fit,
)
from warpcloth.viz.figures.sweeps import HEAT_MAP_TICKS, plot_sweep, read_sweep_summary, sweep_figure
from warpcloth.viz.figures.traces import (
    ENERGY_TERMS,
    default_shape_times,
    plot_amplitude,
    plot_clamp_angle,
    plot_energy,
    plot_run,
    plot_shapes,
)

__all__ = [
    "DPI",
    "ENERGY_TERMS",
    "FIELD_LABELS",
    "FORMATS",
    "HEAT_MAP_TICKS",
    "KES_B_RANGE_PER_CM",
    "KES_K0_PER_CM",
    "LEGEND_VARIANTS",
    "MM",
    "RESIDUAL_MEAN_POINTS",
    "SIGMA_STYLES",
    "X_LABEL",
    "Y_LABEL",
    "ClampFit",
    "FitResiduals",
    "KesFitResult",
    "KesValues",
    "LawComparisonResult",
    "MotionFit",
    "bending_law_comparison_figure",
    "default_shape_times",
    "field_label",
    "field_unit",
    "fit_search_figure",
    "kes_loop",
    "plot_amplitude",
    "plot_bending_law_comparison",
    "plot_bending_loop",
    "plot_clamp_angle",
    "plot_clamp_fit",
    "plot_energy",
    "plot_fit_overlay",
    "plot_kes_fit",
    "plot_run",
    "plot_shapes",
    "plot_sweep",
    "read_sweep_summary",
    "sweep_figure",
    "time_label",
]
