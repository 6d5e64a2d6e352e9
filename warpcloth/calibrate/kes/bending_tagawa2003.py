"""The paper's hysteretic bending law (tagawa2003, docs/model.md §4) fitted to a
KES-FB2 loop (docs/model.md §13.3), by the machinery of :mod:`.bending_fit`.

K0 is the loop's largest ``|K|`` (fixed by the data, not a free parameter). For a fixed α
the hysteretic offset is proportional to D1 (the branch functions are, and a reversal
maps the gap to the asymptote g = M0 − s H, which is proportional to D1, onto 2 M0 − g), so
M = D K + D1 h₁(α; path) with h₁ the offset for D1 = 1 gf·cm/cm: for each α, (D, D1) is a
linear least-squares problem (with D, D1 ≥ 0). α is searched on a logarithmic grid of
α K0 in [0.05, 60] (all in one kernel launch), then refined by Nelder–Mead inside the
grid's range. Free parameters: D, D1, α.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .bending_fit import BendingFit, LawFitter, Parameter, ShapeParameter
from .readers import BendingLoop

ALPHA_K0_GRID = (0.05, 60.0, 64)
"""Coarse α search: α K0 from nearly linear branches to a step, log-spaced, n points."""


@dataclass(frozen=True)
class Tagawa2003Fit(BendingFit):
    """A tagawa2003 fit, with its parameters also by name."""

    @property
    def d1_gf_cm_per_cm(self) -> float:
        """D1, the hysteresis amplitude."""
        return self.parameters["hysteresis_d1_gf_cm_per_cm"]

    @property
    def alpha_cm(self) -> float:
        """α, the steepness of the branches."""
        return self.parameters["hysteresis_alpha_cm"]

    @property
    def k0_per_cm(self) -> float:
        """K0, the loop's largest ``|K|``."""
        return self.parameters["hysteresis_k0_per_cm"]


TAGAWA2003 = LawFitter(
    law="tagawa2003",
    amplitude=Parameter("hysteresis_d1_gf_cm_per_cm", "D1", "gf·cm/cm"),
    shape=(ShapeParameter("hysteresis_alpha_cm", "α", "cm", *ALPHA_K0_GRID, k0_power=-1, scaled="α K0"),),
    k0=Parameter("hysteresis_k0_per_cm", "K0", "1/cm"),
    result=Tagawa2003Fit,
)
"""The paper's law: amplitude D1, shape α (α K0 on the grid), K0 from the data."""


def hysteretic_offsets(
    curvature_per_cm: np.ndarray, alphas_cm: Sequence[float] | np.ndarray, k0_per_cm: float, device: str | None = "cpu"
) -> np.ndarray:
    """Offset h(α; path) per gf·cm/cm of D1 along a curvature path, one column per α.

    All α run in one kernel launch (warpcloth.strip.moment_along_path, the strip
    kernel's hinge logic) with D = 0 and D1 = 1 gf·cm/cm; the hinge starts fresh at the
    path's first sample. Returns ``[sample, alpha]``, in gf·cm/cm per gf·cm/cm of D1.
    """
    alphas = np.atleast_1d(np.asarray(alphas_cm, dtype=np.float64))
    return TAGAWA2003.unit_offsets(curvature_per_cm, alphas[:, None], k0_per_cm, device)


def fit_bending(loop: BendingLoop, device: str | None = "cpu") -> Tagawa2003Fit:
    """Fit D, D1 and α of M = D K + h to the whole loop (K0 = the loop's largest ``|K|``)."""
    return TAGAWA2003.fit(loop, device)
