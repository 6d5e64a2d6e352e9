"""The Dahl bending law (dahl, docs/model.md §4.8) fitted to a KES-FB2 loop
(docs/model.md §13.5), by the machinery of :mod:`.bending_fit`.

At fixed (K_s, n) the hysteretic moment is proportional to M_s (h = M_s g with
dg/dK = (1 − s g)^n / K_s, which does not involve M_s), so (D, M_s) is a linear
least-squares problem with D, M_s ≥ 0. (K_s, n) are searched on a 2-D logarithmic grid,
K_s / K0 in [1/60, 20] (the range of tagawa2003's α K0, inverted) by n in [0.1, 5], every
grid point in one kernel launch, then refined by Nelder–Mead on (ln K_s, ln n) inside the
grid's box. Free parameters: D, M_s, K_s, n. With n = 1 the law is tagawa2003
(M_s = M0, K_s = 1/α), so a dahl fit is never worse than the tagawa2003 fit of the same
loop; n → 0 tends to the frictional couple.
"""

from __future__ import annotations

from .bending_fit import BendingFit, LawFitter, Parameter, ShapeParameter
from .readers import BendingLoop

SCALE_K0_GRID = (1 / 60, 20.0, 32)
"""K_s / K0: log-spaced from a near step to nearly linear branches, n points."""

EXPONENT_GRID = (0.1, 5.0, 24)
"""n: log-spaced from nearly a frictional couple to slow saturation, n points."""

DAHL = LawFitter(
    law="dahl",
    amplitude=Parameter("dahl_moment_gf_cm_per_cm", "M_s", "gf·cm/cm"),
    shape=(
        ShapeParameter("dahl_curvature_per_cm", "K_s", "1/cm", *SCALE_K0_GRID, k0_power=1, scaled="K_s/K0"),
        ShapeParameter("dahl_exponent", "n", "", *EXPONENT_GRID, k0_power=0, scaled="n"),
    ),
)
"""Dahl's law: amplitude M_s, shape (K_s, n)."""


def fit_dahl(loop: BendingLoop, device: str | None = "cpu") -> BendingFit:
    """Fit D, M_s, K_s and n of M = D K + h (Dahl) to the whole loop."""
    return DAHL.fit(loop, device)
