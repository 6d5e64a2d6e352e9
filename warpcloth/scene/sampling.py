"""Seeded space-filling samples of the unit box: the one Latin hypercube, shared by a
sweep's ``[sweep.random]`` block (``method = "latin_hypercube"``) and the motion fit's
space-filling start (:mod:`warpcloth.calibrate.motion_fit`)."""

from __future__ import annotations

import numpy as np


def latin_hypercube(n: int, d: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points in [0, 1)^d, ``[point, coordinate]``: one sample per stratum
    [i/n, (i+1)/n) in every coordinate, the strata of the coordinates paired at random.

    The draws, in this order, are part of the result (a sweep's variants are fixed by its
    seed, bit for bit): ``rng.random((d, n))``, whose ranks along each coordinate pair
    the strata, then ``rng.random((n, d))``, each point's place inside its stratum.
    """
    return (np.argsort(rng.random((d, n)), axis=1).T + rng.random((n, d))) / n
