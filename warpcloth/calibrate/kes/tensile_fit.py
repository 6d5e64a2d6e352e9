"""The tensile law's quartic fitted to a KES-FB1 loading branch (docs/model.md §13.2).

The quartic T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴ (ε a fraction, no constant term) is the
least-squares fit to the loading branch, solved in the scaled powers (ε/εm)^k for
conditioning; when it would not increase on [0, max(ε_max, divergence strain)], as a
scene requires, the fit is constrained to dT/dε ≥ 10⁻³ Fm/εm there instead (and says
so). Residuals are RMS(fit − data) in gf/cm and that RMS relative to the data's range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from warpcloth.errors import DataFileError
from warpcloth.scene import IntegratorSection, tensile_slope_minimum

from ..motion_fit.lm import covariance
from ..uncertainty import FittedValue, judge
from .least_squares import least_squares_above
from .readers import TensileLoop

DIVERGENCE_STRAIN = IntegratorSection().divergence_strain
"""Strain up to which a fitted T(ε) must increase (the scene default)."""

SLOPE_FLOOR = 1e-3
"""Constrained tensile fit: dT/dε ≥ SLOPE_FLOOR × Fm / εm (so T strictly increases)."""


@dataclass(frozen=True)
class TensileFit:
    """The quartic T(ε) fitted to the loading branch."""

    coefficients: list[float]  # a1..a4, gf/cm (ε a fraction)
    rms_gf_per_cm: float
    rms_relative: float  # RMS / range of the loading branch's force
    constrained: bool
    note: str  # why the fit was constrained; "" when it was not
    covariance: tuple[tuple[float, ...], ...] = ()  # of a1..a4, (gf/cm)²: s² (XᵀX)⁻¹

    def values(self) -> list[FittedValue]:
        """a1…a4 with their 1σ, each marked where the data do not determine it
        (:func:`~warpcloth.calibrate.uncertainty.judge`): over a loading branch a few %
        long the quartic's coefficients trade against each other while T(ε) is fixed."""
        return judge(
            [f"a{k}" for k in range(1, 5)], ["gf/cm"] * 4, np.array(self.coefficients), np.array(self.covariance)
        )

    def __call__(self, strain: np.ndarray) -> np.ndarray:
        """T(ε) in gf/cm."""
        a1, a2, a3, a4 = self.coefficients
        e = np.asarray(strain, dtype=np.float64)
        return e * (a1 + e * (a2 + e * (a3 + e * a4)))


def fit_tensile(loop: TensileLoop, max_strain: float = DIVERGENCE_STRAIN) -> TensileFit:
    """Least-squares quartic T(ε) = a1 ε + … + a4 ε⁴ through the loading branch.

    If it does not increase on [0, max(ε_max, max_strain)] (a scene needs it to, up to
    its divergence strain), the fit is redone with dT/dε ≥ 10⁻³ Fm/εm on 257 points of
    that range, and ``note`` says where the unconstrained fit failed.
    """
    e = loop.strain[loop.loading]
    t = loop.force[loop.loading]
    scale = float(e.max())
    powers = np.arange(1, 5)
    design = (e[:, None] / scale) ** powers
    unscale = scale ** -powers.astype(float)
    coefficients = np.linalg.lstsq(design, t, rcond=None)[0] * unscale
    upper = max(scale, max_strain)
    slope, where = tensile_slope_minimum(list(coefficients), upper)
    constrained, note = False, ""
    if not slope > 0:
        inside = "inside the data" if where <= scale else "beyond the data"
        free_rms = float(np.sqrt(np.mean((design @ (coefficients / unscale) - t) ** 2)))
        note = (
            f"the unconstrained quartic (RMS {free_rms:.3g} gf/cm) decreases at ε = {where:.4g} ({inside}, "
            f"which end at {scale:.4g}; dT/dε = {slope:.4g} gf/cm); refitted with dT/dε ≥ {SLOPE_FLOOR:g} "
            f"Fm/εm on [0, {upper:g}] (a smaller divergence strain constrains less)"
        )
        grid = np.linspace(0.0, upper, 257) / scale
        # dT/dε = Σ k b_k (ε/s)^(k−1) / s for the scaled coefficients b_k
        gradient = powers * grid[:, None] ** (powers - 1) / scale
        floor = SLOPE_FLOOR * abs(loop.force[loop.turn]) / scale
        try:
            coefficients = least_squares_above(design, t, gradient, np.full(len(grid), floor)) * unscale
        except ValueError:  # numerically infeasible: forces far outside a fabric's (overflowing squares)
            raise DataFileError(
                loop.source,
                f"no quartic T(ε) rising on [0, {upper:g}] fits this loop (largest "
                f"|force| {float(np.max(np.abs(loop.force))):.3g} gf/cm): are the forces in gf/cm?",
            ) from None
        constrained = True
        slope, where = tensile_slope_minimum(list(coefficients), upper)
        if not slope > 0:  # pragma: no cover - the grid constraint holds between its points
            raise DataFileError(loop.source, f"no increasing quartic fits the loading branch ({note})")
    residual = design @ (coefficients / unscale) - t
    rms = float(np.sqrt(np.mean(residual**2)))
    # the linear fit's covariance (at an active slope constraint the spread along it is
    # smaller, so this is an upper bound there); in a's units through the column scaling
    cov = covariance(design, residual) * np.outer(unscale, unscale)
    return TensileFit(
        [float(a) for a in coefficients],
        rms,
        rms / (float(np.ptp(t)) or 1.0),
        constrained,
        note,
        tuple(tuple(float(c) for c in row) for row in cov),
    )
