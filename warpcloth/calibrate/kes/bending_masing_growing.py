"""Masing's rules with growing friction (masing_growing, kernels/bending_masing_growing.py)
fitted to a KES loop by the machinery of :mod:`.bending_fit`: its hysteretic part is
proportional to D1 at fixed (α, β), so (D, D1) come from non-negative least squares for
each (α, β) of a grid, refined by Nelder–Mead, as for masing; K0 is the loop's largest |K|."""

from __future__ import annotations

from .bending_fit import LawFitter, ShapeParameter
from .bending_tagawa2003 import TAGAWA2003, Tagawa2003Fit

GROWTH = ShapeParameter("hysteresis_growth_cm", "β", "cm", low=0.02, high=20.0, count=9, k0_power=-1, scaled="β K0")
"""β on a grid of β K0 from 0.02 (hardly growing over the loop) to 20 (twenty-fold)."""

MASING_GROWING = LawFitter(
    law="masing_growing",
    amplitude=TAGAWA2003.amplitude,
    shape=(*TAGAWA2003.shape, GROWTH),
    k0=TAGAWA2003.k0,
    result=Tagawa2003Fit,
)
"""The masing_growing law: the paper's parameters with β, the law's own hinge logic."""
