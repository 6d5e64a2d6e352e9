"""How noisy a measurement is, estimated from the measurement itself.

A fit is judged against the noise of what it fits: an RMS near it means the model
explains the data; many times it means the model (or its inputs) does not. The noise is
estimated without a model from high-order differences of each sampled series: for white
noise of σ the fourth difference has variance 70 σ², while a smooth signal sampled well
above its frequencies contributes (ω Δt)⁴ of its amplitude, negligible. The median
absolute deviation makes the estimate ignore the few samples where the signal changes
abruptly (an impulsive start, a clamp that stops).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

FOURTH_DIFFERENCE_VARIANCE = 70.0  # Σ binomial(4, k)² = 70
MAD_TO_SIGMA = 1.482602218505602  # 1 / Φ⁻¹(3/4)


def quantisation_floor(series: Iterable[np.ndarray]) -> float:
    """σ of rounding to the data's resolution (the smallest step between samples) / √12:
    an instrument that reads in counts is never quieter than its count (0 if unresolved)."""
    steps = [np.abs(np.diff(np.asarray(s, dtype=float))) for s in series if len(s) >= 2]
    steps = np.concatenate(steps) if steps else np.zeros(0)
    steps = steps[np.isfinite(steps) & (steps > 0)]
    return float(steps.min() / math.sqrt(12.0)) if len(steps) else 0.0


def difference_noise(series: Iterable[np.ndarray]) -> float:
    """σ of white noise on smooth, evenly sampled ``series`` (NaN when too short), never
    below the data's :func:`quantisation_floor` (a quantised flat record has MAD 0)."""
    series = list(series)
    parts = [np.diff(np.asarray(s, dtype=float), 4) for s in series if len(s) >= 5]
    if not parts:
        return float("nan")
    d = np.concatenate(parts)
    d = d[np.isfinite(d)]
    if not len(d):
        return float("nan")
    estimate = MAD_TO_SIGMA * np.median(np.abs(d - np.median(d))) / math.sqrt(FOURTH_DIFFERENCE_VARIANCE)
    return float(max(estimate, quantisation_floor(series)))


POOR_FIT_FACTOR = 1.5
"""The one verdict rule of every fit (clamp motion, motion, KES): an RMS above this many
times the noise of the data is not explained by the model. Measured (benchmarks/RESULTS.md,
issue 22): over 20 noise seeds every right model stays at or below 1.15×, and the
estimator's own spread (≈ 1.46/√n) passes 1.5 in none of 5000 draws at n ≥ 200; models
wrong enough to move a fitted value beyond its tolerance leave 2.0× and more."""


def poor_fit_ratio(rms: float, noise: float) -> float | None:
    """RMS / noise when it exceeds :data:`POOR_FIT_FACTOR` (the model does not explain the
    data: the fit is ``poor_fit``); None when it does not, or the noise is unknown (not
    finite or zero: nothing to judge against)."""
    if not (math.isfinite(noise) and noise > 0):
        return None
    ratio = rms / noise
    return ratio if ratio > POOR_FIT_FACTOR else None
