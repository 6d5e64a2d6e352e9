"""Grosberg's frictional couple (frictional_couple, docs/model.md §4.9) fitted to a
KES-FB2 loop (docs/model.md §13.5), by the machinery of :mod:`.bending_fit`.

At fixed K_w the regularised couple h = clamp(h + (M_f / K_w) ΔK, −M_f, M_f) is
proportional to M_f, so (D, M_f) is a linear least-squares problem with D, M_f ≥ 0. K_w
is searched on a logarithmic grid of K_w / K0 in [0.001, 2] (one kernel launch), then
refined by Nelder–Mead inside the grid's range. Free parameters: D, M_f, K_w.
"""

from __future__ import annotations

from .bending_fit import BendingFit, LawFitter, Parameter, ShapeParameter
from .readers import BendingLoop

WIDTH_K0_GRID = (1e-3, 2.0, 64)
"""K_w / K0: log-spaced from a sharp reversal to one the loop never completes, n points."""

FRICTIONAL_COUPLE = LawFitter(
    law="frictional_couple",
    amplitude=Parameter("friction_moment_gf_cm_per_cm", "M_f", "gf·cm/cm"),
    shape=(ShapeParameter("friction_width_per_cm", "K_w", "1/cm", *WIDTH_K0_GRID, k0_power=1, scaled="K_w/K0"),),
)
"""The frictional couple: amplitude M_f, shape K_w."""


def fit_frictional_couple(loop: BendingLoop, device: str | None = "cpu") -> BendingFit:
    """Fit D, M_f and K_w of M = D K + h (frictional couple) to the whole loop."""
    return FRICTIONAL_COUPLE.fit(loop, device)
