"""Uncertainty that survives correlated errors: a moving-block bootstrap of the residuals.

The Gauss–Newton σ assumes independent residuals. A measured swing's errors are
correlated in time (unmodelled motion, a camera's smoothing), and then that σ is too
small. Here blocks of consecutive residuals at the optimum are resampled with
replacement (keeping their correlation inside each block), mapped through the
linearised estimator Δp = −(JᵀJ)⁻¹ Jᵀ r*, and the spread of Δp is the σ. The block
length is four times the residuals' correlation length (the first lag whose
autocorrelation falls below 1/e), at least n^(1/3). Linearised, it needs no new simulation: the
Jacobian at the optimum is already there.

Measured on a linear model with AR(1) noise (tests/test_calibration_path.py): for
white noise its 95 % intervals cover the truth in 93–94 % of trials (Gauss–Newton's in
94–95 %); for φ = 0.9 in 82–87 %, where Gauss–Newton's cover in 37–42 %: residuals
lack the part of the noise that looks like the model's own response, so any
residual-based σ stays somewhat low when the noise is strongly correlated.
"""

from __future__ import annotations

import math

import numpy as np


def correlation_length(residual: np.ndarray) -> int:
    """First lag at which the residuals' autocorrelation falls below 1/e (≥ 1)."""
    r = np.asarray(residual, dtype=float) - np.mean(residual)
    n = len(r)
    spectrum = np.fft.rfft(r, 2 * n)
    acf = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    if acf[0] <= 0:
        return 1
    below = np.flatnonzero(acf / acf[0] < math.exp(-1))
    return int(below[0]) if len(below) else n


def block_bootstrap_sigma(
    jacobian: np.ndarray, residual: np.ndarray, replicates: int, rng: np.random.Generator, block: int | None = None
) -> tuple[np.ndarray, int]:
    """σ of the least-squares parameters (columns of ``jacobian``, ∂r/∂p) from ``replicates``
    moving-block resamples of ``residual``; returns (σ, block length)."""
    n, _ = jacobian.shape
    if block is None:
        block = max(4 * correlation_length(residual), math.ceil(n ** (1 / 3)))
    # at most a third of the record, so resamples still differ (σ from one block is 0)
    block = int(min(max(block, 1), max(1, n // 3)))
    estimator = np.linalg.pinv(jacobian)  # (JᵀJ)⁻¹ Jᵀ, and defined for a singular Jacobian
    centred = residual - residual.mean()
    n_blocks = math.ceil(n / block)
    starts = rng.integers(0, n - block + 1, size=(replicates, n_blocks))
    index = (starts[:, :, None] + np.arange(block)[None, None, :]).reshape(replicates, -1)[:, :n]
    shifts = -(estimator @ centred[index].T).T  # [replicate, parameter]
    return shifts.std(axis=0, ddof=1), block
