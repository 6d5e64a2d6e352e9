"""The paper's hysteretic bending law (tagawa2003, docs/model.md §4) fitted to a
KES-FB2 loop (docs/model.md §13.3).

The model M = D K + h (the hinge starts fresh at the first sample: rising branch, no
offset) is run along the measured curvature path by the kernel's own hinge logic. K0 is
the loop's largest ``|K|``. For a fixed α the hysteretic offset is proportional to D1 (the
branch functions are, and the loop centre after a reversal depends on the offset only
through (M0 ∓ H)/D1), so M = D K + D1 h₁(α; path) with h₁ the offset for D1 = 1 gf·cm/cm:
for each α, (D, D1) is a linear least-squares problem (with D, D1 ≥ 0). α is searched on
a logarithmic grid of α K0 in [0.05, 60] (all in one kernel launch), then refined by
golden-section search between the best grid point's neighbours. Residuals are
RMS(fit − data) in gf·cm/cm and that RMS relative to the data's range.

Another bending law would be fitted by a module like this one, beside it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from warpcloth import units
from warpcloth.sim import MaterialSI, moment_along_path

from .least_squares import nnls
from .readers import BendingLoop

ALPHA_K0_GRID = (0.05, 60.0, 64)
"""Coarse α search: α K0 from nearly linear branches to a step, log-spaced, n points."""


@dataclass(frozen=True)
class BendingFit:
    """D, D1, α (K0 from the data) of the hysteretic bending law, and the fitted path."""

    rigidity_gf_cm2_per_cm: float  # D
    d1_gf_cm_per_cm: float
    alpha_cm: float
    k0_per_cm: float
    rms_gf_cm_per_cm: float
    rms_relative: float  # RMS / range of the measured moment
    moment: np.ndarray  # the model's moment along the measured path, gf·cm/cm
    note: str  # e.g. α at the edge of its search range; "" otherwise


def hysteretic_offsets(curvature_per_cm: np.ndarray, alphas_cm: Sequence[float] | np.ndarray, k0_per_cm: float,
                       device: str | None = "cpu") -> np.ndarray:
    """Offset h(α; path) per gf·cm/cm of D1 along a curvature path, one column per α.

    All α run in one kernel launch (warpcloth.sim.moment_along_path, the strip
    kernel's hinge logic) with D = 0 and D1 = 1 gf·cm/cm; the hinge starts fresh at the
    path's first sample. Returns ``[sample, alpha]``, in gf·cm/cm per gf·cm/cm of D1.
    """
    materials = [MaterialSI(density=1.0, tensile=(0.0, 0.0, 0.0, 0.0), bending_rigidity=0.0,
                            hysteresis_d1=units.MOMENT_GF_CM_PER_CM, hysteresis_alpha=float(a) * units.LENGTH_CM,
                            hysteresis_k0=k0_per_cm * units.CURVATURE_PER_CM) for a in np.atleast_1d(alphas_cm)]
    k = np.asarray(curvature_per_cm, dtype=np.float64) * units.CURVATURE_PER_CM
    moment, _ = moment_along_path(materials, k[:, None], device=device)
    return moment / units.MOMENT_GF_CM_PER_CM


def _linear_part(curvature: np.ndarray, moment: np.ndarray, offset: np.ndarray) -> tuple[float, float, float]:
    # D, D1 ≥ 0 of M = D K + D1 h for one α, and the sum of squared residuals.
    d, d1 = nnls(np.column_stack([curvature, offset]), moment)
    return float(d), float(d1), float(np.sum((d * curvature + d1 * offset - moment) ** 2))


def fit_bending(loop: BendingLoop, device: str | None = "cpu") -> BendingFit:
    """Fit D, D1 and α of M = D K + h to the whole loop (K0 = the loop's largest ``|K|``).

    For each α, (D, D1) is a linear least-squares problem; α comes from a log grid of
    α K0 (one kernel launch) refined by golden-section search on log α.
    """
    k, m, k0 = loop.curvature, loop.moment, loop.k0
    low, high, n = ALPHA_K0_GRID
    grid = np.geomspace(low, high, n) / k0
    offsets = hysteretic_offsets(k, grid, k0, device)
    sse = np.array([_linear_part(k, m, offsets[:, i])[2] for i in range(n)])
    best = int(np.argmin(sse))
    note = ""
    if best in (0, n - 1):
        note = (f"α at the edge of its search range (α K0 = {grid[best] * k0:g}); the loop may not have the "
                "model's shape")

    def objective(log_alpha: float) -> float:
        return _linear_part(k, m, hysteretic_offsets(k, [math.exp(log_alpha)], k0, device)[:, 0])[2]

    # golden section on log α between the best grid point's neighbours
    a, b = math.log(grid[max(best - 1, 0)]), math.log(grid[min(best + 1, n - 1)])
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = b - ratio * (b - a), a + ratio * (b - a)
    fc, fd = objective(c), objective(d)
    while b - a > 1e-10:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - ratio * (b - a)
            fc = objective(c)
        else:
            a, c, fc = c, d, fd
            d = a + ratio * (b - a)
            fd = objective(d)
    alpha = math.exp(0.5 * (a + b))
    if sse[best] < min(fc, fd):  # a flat objective (no hysteresis): keep the grid's point
        alpha = float(grid[best])
    offset = hysteretic_offsets(k, [alpha], k0, device)[:, 0]
    d_fit, d1_fit, total = _linear_part(k, m, offset)
    if d1_fit == 0.0:
        note = "the loop shows no hysteresis (D1 = 0): α has no effect"
    rms = math.sqrt(total / len(k))
    return BendingFit(d_fit, d1_fit, alpha, k0, rms, rms / (float(np.ptp(m)) or 1.0),
                      d_fit * k + d1_fit * offset, note)
