"""The standard KES summary values of a loop, computed from the data, not from a fit
(docs/model.md §13.4):

- EMT (%): the strain where loading ends (the maximum strain; KES-FB1 reverses at the
  preset maximum load Fm, 500 gf/cm as standard); Fm is the force there.
- WT (gf·cm/cm²): tensile energy ∫ T dε along the loading branch (ε a fraction; trapezoids).
- LT: linearity WT / (½ Fm εm) (1 for a straight line).
- RT (%): resilience, 100 × (∫ T dε along the unloading branch) / WT; only with unloading data.
- B (gf·cm²/cm): mean of the least-squares slopes dM/dK for 0.5 ≤ |K| ≤ 1.5 1/cm on both
  branches (rising and falling K) on both sides (K > 0 and K < 0).
- 2HB (gf·cm/cm): mean over K = +1 and K = −1 1/cm of the hysteresis width
  M(rising) − M(falling), each read off a straight line through the branch's points
  within ±0.1 1/cm (linear interpolation where fewer than 3 points lie there).
- G (gf/(cm·°)): as B, the mean slope dFs/dφ for 0.5 ≤ ``|φ|`` ≤ 5° of a KES-FB1 shear loop.
- 2HG, 2HG5 (gf/cm): as 2HB, the hysteresis width Fs(rising) − Fs(falling) at φ = ±0.5°
  and ±5°, each branch read off a line through its points within ±0.1° (docs/model.md §17.1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .readers import PERCENT, BendingLoop, ShearLoop, TensileLoop

B_RANGE_PER_CM = (0.5, 1.5)
"""KES B: the |K| range (1/cm) of the slopes that are averaged."""

HB_CURVATURE_PER_CM = 1.0
"""KES 2HB: the hysteresis width is read at K = ± this (1/cm)."""

HB_WINDOW_PER_CM = 0.1
"""2HB: a branch's moment at ±1 1/cm is a line through its points within ± this (1/cm)."""

G_RANGE_DEG = (0.5, 5.0)
"""KES G: the ``|φ|`` range (degree) of the slopes that are averaged."""

HG_ANGLES_DEG = (0.5, 5.0)
"""KES 2HG and 2HG5: the hysteresis width is read at φ = ± these (degree)."""

HG_WINDOW_DEG = 0.1
"""2HG, 2HG5: a branch's force at ±φ is a line through its points within ± this (degree)."""


@dataclass(frozen=True)
class TensileSummary:
    """KES-FB1 values of a loop (definitions in the module docstring)."""

    emt_percent: float
    fm_gf_per_cm: float
    wt_gf_cm_per_cm2: float
    lt: float
    rt_percent: float | None  # None without an unloading branch


@dataclass(frozen=True)
class BendingSummary:
    """KES-FB2 values of a loop; None where the loop does not reach the curvatures used."""

    b_gf_cm2_per_cm: float | None
    hb2_gf_cm_per_cm: float | None


def _area(y: np.ndarray, x: np.ndarray) -> float:
    # trapezoid rule (np.trapezoid needs NumPy 2; warpcloth supports 1.24)
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def tensile_summary(loop: TensileLoop) -> TensileSummary:
    """EMT, Fm, WT, LT and (with unloading data) RT of a tensile loop."""
    e, t = loop.strain, loop.force
    load, unload = loop.loading, loop.unloading
    em, fm = float(e[loop.turn]), float(t[loop.turn])
    wt = _area(t[load], e[load])
    lt = wt / (0.5 * fm * em)
    rt = None
    if len(e[unload]) > 1:
        rt = 100.0 * _area(t[unload][::-1], e[unload][::-1]) / wt
    return TensileSummary(em / PERCENT, fm, wt, lt, rt)


@dataclass(frozen=True)
class ShearSummary:
    """KES-FB1 shear values of a loop; None where the loop does not reach the angles used."""

    g_gf_per_cm_deg: float | None
    hg2_gf_per_cm: float | None
    hg2_5_gf_per_cm: float | None


def _branch_value(k: np.ndarray, m: np.ndarray, at: float, window: float) -> float | None:
    # M of one leg at curvature ``at``: a line through its points within the window, or
    # linear interpolation; None when the leg does not reach ``at``.
    if not k.min() <= at <= k.max():
        return None
    near = np.abs(k - at) <= window
    if np.count_nonzero(near) >= 3 and np.ptp(k[near]) > 0:
        slope, intercept = np.polyfit(k[near], m[near], 1)
        return float(slope * at + intercept)
    order = np.argsort(k, kind="stable")
    return float(np.interp(at, k[order], m[order]))


def _legs(loop: BendingLoop) -> list[tuple[np.ndarray, np.ndarray, float]]:
    k, m = loop.curvature, loop.moment
    return [(k[leg], m[leg], float(np.sign(k[leg][-1] - k[leg][0]))) for leg in loop.legs()]


def _mean_slope(legs: list[tuple[np.ndarray, np.ndarray, float]], span: tuple[float, float]) -> float | None:
    # The mean least-squares slope over |x| in ``span`` on both branches on both sides;
    # None unless all four are there.
    slopes = {}
    for kl, ml, direction in legs:
        for side in (1.0, -1.0):
            inside = (side * kl >= span[0]) & (side * kl <= span[1])
            spans = np.min(side * kl) <= span[0] and np.max(side * kl) >= span[1]
            if spans and np.count_nonzero(inside) >= 3:
                slopes.setdefault((direction, side), []).append(np.polyfit(kl[inside], ml[inside], 1)[0])
    return float(np.mean([s for v in slopes.values() for s in v])) if len(slopes) == 4 else None


def _mean_width(legs: list[tuple[np.ndarray, np.ndarray, float]], at: float, window: float) -> float | None:
    # The hysteresis width (rising − falling) averaged over x = ±at; None unless both are there.
    widths = []
    for x in (at, -at):
        values = {1.0: [], -1.0: []}
        for kl, ml, direction in legs:
            value = _branch_value(kl, ml, x, window)
            if value is not None and direction in values:
                values[direction].append(value)
        if values[1.0] and values[-1.0]:
            widths.append(np.mean(values[1.0]) - np.mean(values[-1.0]))
    return float(np.mean(widths)) if len(widths) == 2 else None


def bending_summary(loop: BendingLoop) -> BendingSummary:
    """B and 2HB of a bending loop (None where the loop does not reach the curvatures used)."""
    legs = _legs(loop)
    return BendingSummary(_mean_slope(legs, B_RANGE_PER_CM), _mean_width(legs, HB_CURVATURE_PER_CM, HB_WINDOW_PER_CM))


def shear_summary(loop: ShearLoop) -> ShearSummary:
    """G, 2HG and 2HG5 of a shear loop (None where the loop does not reach the angles used)."""
    legs = _legs(loop.as_law_loop())
    return ShearSummary(_mean_slope(legs, G_RANGE_DEG), *(_mean_width(legs, at, HG_WINDOW_DEG) for at in HG_ANGLES_DEG))


KES_CYCLE_STEP_PER_CM = 0.02
"""Curvature step of :func:`standard_cycle` (the bundled KES-FB2 example's)."""


KES_SHEAR_STEP_DEG = 0.05
"""Angle step of the standard shear cycle (:func:`standard_cycle` with it; the bundled
KES-FB1 shear example's)."""


def standard_cycle(k0_per_cm: float, step_per_cm: float = KES_CYCLE_STEP_PER_CM) -> np.ndarray:
    """The KES-FB2 curvature cycle 0 → +K0 → −K0 → 0 (1/cm), in steps of about ``step_per_cm``."""
    n = max(round(k0_per_cm / step_per_cm), 2)
    return np.concatenate(
        [
            np.linspace(0.0, k0_per_cm, n, endpoint=False),
            np.linspace(k0_per_cm, -k0_per_cm, 2 * n, endpoint=False),
            np.linspace(-k0_per_cm, 0.0, n + 1),
        ]
    )
