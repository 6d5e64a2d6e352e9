"""The paper's loop with return-point memory (masing, docs/model.md §4.10) fitted to a
KES-FB2 loop (docs/model.md §13.5), by the machinery of :mod:`.bending_fit`.

Its parameters are the paper's (D, D1, α, K0 = the loop's largest ``|K|``) and its
hysteretic moment is proportional to D1 at fixed α (the reversal points depend only on
the curvature path), so it is fitted exactly as tagawa2003 is: (D, D1) by non-negative
least squares for each α of the same grid, α refined by golden-section search. On a
major loop the two laws coincide once the first loading is past (it starts on the
virgin curve here, on a shifted branch there); inner loops — partial cycles — tell them
apart (:func:`~warpcloth.calibrate.kes.compare_laws`).
"""

from __future__ import annotations

from .bending_fit import LawFitter
from .bending_tagawa2003 import TAGAWA2003, Tagawa2003Fit
from .readers import BendingLoop

MASING = LawFitter(
    law="masing", amplitude=TAGAWA2003.amplitude, shape=TAGAWA2003.shape, k0=TAGAWA2003.k0, result=Tagawa2003Fit
)
"""The masing law: the paper's parameters and search, the law's own hinge logic."""


def fit_masing(loop: BendingLoop, device: str | None = "cpu") -> Tagawa2003Fit:
    """Fit D, D1 and α of M = D K + H (masing) to the whole loop (K0 = the loop's largest ``|K|``)."""
    return MASING.fit(loop, device)
