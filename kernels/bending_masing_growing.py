"""Masing's rules with a friction that grows with the angle, ``"masing_growing"``: woven
fabrics' shear loops, which widen toward the turning point (2HG5 > 2HG; docs/model.md §17.1).

Why. In an Iwan model (a continuum of Jenkins elements: a spring in series with a friction
slider) every element slips at the same force however far the fabric is sheared, so its
KES loop is widest at φ = 0 and narrows toward ±φ0 (2HG5 ≤ 2HG). In a woven fabric the
friction acts at the yarn crossovers, and shearing presses the yarns together toward
jamming: the normal force there, and with it the friction, grows with the shear. Here
every element's slip threshold grows by one factor of the distance from the hinge's
origin K_o (the state it was fresh in: the woven rest state of a sheet's cell),

    g(K) = √(1 + (β (K − K_o))²),   β ≥ 0 (β = 0: masing, bit for bit),

an element of yield y (its elastic range |e| ≤ y without growth) sliding once
|e| = y g(K). With the masing law's yield density (its virgin curve F(u) = ½ D1 (1 − e^{−2αu}))
the branches follow in closed form (derived in docs/model.md §4.11):

- virgin curve from K_o:  H = g(K) F(|K − K_o| / g(K)) sgn(K − K_o);
- the branch after a reversal at (K_r, H_r), direction s:  H = H_r + s G F(s (K − K_r) / G),
  G = g(K) + g(K_r) (Masing's rule is G = 2);
- return-point memory as for masing: an inner loop closes where it began, and the first
  branch meets the virgin curve on the other side where K_m − K_o = s y_r g(K_m),
  y_r = |K_r − K_o| / g(K_r): g depends on |K − K_o| alone, so that is the mirror point
  2 K_o − K_r, as for masing.

The formulas hold because the elements that have slid on a branch are exactly those of
yield y ≤ s (K − K_r) / G, a number that grows along every branch for this g (g(K) + g(K_r)
> β |K − K_r| ≥ |K − K_r| g'(K)), and each sliding element dissipates q dp ≥ 0: no closed
cycle makes energy. The tests compare with a discrete Iwan model of many elements
integrated along the path (an independent implementation), check return-point memory,
sup-norm continuity and nonnegative dissipation, and that β = 0 is masing.

Parameters: D, D1, α, K0 as masing (K0 only where the KES loop closes), and β (per
curvature, 1/cm; per degree in shear).
"""

import functools
from typing import Any

from .bending_masing import masing_functions
from .bending_masing import packed_parameters as masing_parameters
from .bending_tagawa2003 import LOOP_PARAMETERS
from .law import BendingLaw, LawFunctions, LawParameter

GROWTH = LawParameter(
    "hysteresis_growth",
    "hysteresis_growth_cm",
    "inverse_curvature",
    "beta",
    "β",
    "β, growth of the friction with the curvature from the fresh state: yield × √(1 + (β ΔK)²) (0 = masing)",
    default=0.0,
    ge=0,
)
"""β: how fast the friction grows with the distance from the hinge's (cell's) fresh state."""


def packed_parameters(bending_rigidity: float, d1: float, alpha: float, k0: float, growth: float) -> tuple[float, ...]:
    """The per-strip parameter vector (D, D1, α, K0, β) from D (N·m), D1 (N), α (m), K0 (1/m), β (m) in SI."""
    return (*masing_parameters(bending_rigidity, d1, alpha, k0), growth)


@functools.cache
def build(scalar: Any) -> LawFunctions:
    """The law's Warp functions for ``scalar`` (masing's, with the growth)."""
    return masing_functions(scalar, growing=True)


LAW = BendingLaw(
    name="masing_growing",
    summary="masing with friction that grows with the angle: woven fabrics' loops, widest at the turning point",
    parameters=(*LOOP_PARAMETERS, GROWTH),
    pack=packed_parameters,
    memory=("hysteretic_moment", "direction_depth", "previous_curvature"),
    build=build,
    fitter="warpcloth.calibrate.kes.bending_masing_growing:MASING_GROWING",
    mesh_independent=True,  # return-point memory, continuous in the path: converges in h and dt
    uses_reversal_memory=True,
    loop_closure="hysteresis_k0",
)
"""Masing's rules with growing friction, described once (kernels/law.py)."""
