"""Measurements on recorded signals (periods, crossings) shared by tests and tools."""

from __future__ import annotations

import numpy as np


def crossing_times(t: np.ndarray, x: np.ndarray, level: float = 0.0) -> np.ndarray:
    """Times where ``x`` crosses ``level`` (either direction), linearly interpolated."""
    t = np.asarray(t, dtype=float)
    d = np.asarray(x, dtype=float) - level
    ok = np.isfinite(d)
    t, d = t[ok], d[ok]
    i = np.nonzero((d[:-1] * d[1:] < 0) | ((d[:-1] == 0) & (d[1:] != 0)))[0]
    return t[i] - d[i] * (t[i + 1] - t[i]) / (d[i + 1] - d[i])


def first_period(t: np.ndarray, x: np.ndarray, level: float | None = None) -> float:
    """First full period of an oscillation about ``level`` (default: the signal's mean).

    Measured between the first and third crossings, so a start at rest or in motion
    gives the same answer; NaN if the signal crosses fewer than three times.
    """
    x = np.asarray(x, dtype=float)
    if level is None:
        level = float(np.nanmean(x))
    c = crossing_times(t, x, level)
    return float(c[2] - c[0]) if len(c) >= 3 else float("nan")
