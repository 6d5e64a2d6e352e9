"""Seeded space-filling samples of the unit box: the one Latin hypercube, shared by a
sweep's ``[sweep.random]`` block (``method = "latin_hypercube"``) and the motion fit's
space-filling start (:mod:`warpcloth.calibrate.motion_fit`), and how evenly a sample
fills the box."""

from __future__ import annotations

import numpy as np

DISCREPANCY_SAMPLES = 10_000
"""Samples up to which :func:`discrepancy` is computed: its cost grows as n², about 1 s
for 10⁴ points in 4 dimensions."""


def latin_hypercube(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points in [0, 1)^d, ``[point, coordinate]``: one sample per stratum
    [i/n, (i+1)/n) in every coordinate, the strata of the coordinates paired at random,
    each point at a random place inside its stratum: :class:`scipy.stats.qmc.LatinHypercube`
    drawing from ``rng`` (a sweep's variants are fixed by its seed, bit for bit, for a
    given SciPy).
    """
    from scipy.stats import qmc  # here: scipy.stats is ~40 % of every command's start-up

    return qmc.LatinHypercube(d, rng=rng).random(n)


def discrepancy(unit: np.ndarray) -> float | None:
    """The centred L2 discrepancy of points in the unit box (:func:`scipy.stats.qmc.discrepancy`;
    lower is more even: a Latin hypercube's is below a uniform sample's of the same size);
    None for more than :data:`DISCREPANCY_SAMPLES` points, or none."""
    if not 0 < len(unit) <= DISCREPANCY_SAMPLES or unit.shape[1] == 0:
        return None
    from scipy.stats import qmc

    return float(qmc.discrepancy(unit))
