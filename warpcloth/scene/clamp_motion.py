"""Clamp motion θ(t) as piecewise polynomials, the single form the kernels evaluate.

A piecewise polynomial from the scene is used as given; a sampled encoder table becomes
one linear or natural-cubic piece per sample interval. Before the first piece and after
the last, θ is held at the end value (the clamp stands still).
"""

from __future__ import annotations

import numpy as np

from warpcloth.kernels import MAX_DEGREE

from .schema import ClampSection


def clamp_pieces(clamp: ClampSection) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start [S], end [S], coefficients [S, 5]) of θ(t) = Σ c_k (t − start)^k, SI."""
    if clamp.motion == "fixed":
        return np.zeros(0), np.zeros(0), np.zeros((0, MAX_DEGREE + 1))
    if clamp.motion == "piecewise":
        return segment_pieces(clamp.segments, "theta_coefficients_si")
    t = np.asarray(clamp.table_t_s, dtype=float)
    theta = np.asarray(clamp.table_theta_rad, dtype=float)
    h = np.diff(t)
    coefficients = np.zeros((len(h), MAX_DEGREE + 1))
    coefficients[:, 0] = theta[:-1]
    if clamp.interpolation == "linear":
        coefficients[:, 1] = np.diff(theta) / h
    else:
        m = natural_spline_second_derivatives(t, theta)
        coefficients[:, 1] = np.diff(theta) / h - h * (2 * m[:-1] + m[1:]) / 6
        coefficients[:, 2] = m[:-1] / 2
        coefficients[:, 3] = np.diff(m) / (6 * h)
    return t[:-1], t[1:], coefficients


def segment_pieces(segments: list, coefficients: str, scale: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start [S], end [S], coefficients [S, 5]) of scene segments whose attribute
    ``coefficients`` holds c_0..c_k, times ``scale`` (to SI)."""
    start = np.array([s.t_start_s for s in segments], dtype=float)
    end = np.array([s.t_end_s for s in segments], dtype=float)
    out = np.zeros((len(segments), MAX_DEGREE + 1))
    for i, seg in enumerate(segments):
        values = getattr(seg, coefficients)
        out[i, : len(values)] = np.asarray(values, dtype=float) * scale
    return start, end, out


def natural_spline_second_derivatives(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Second derivatives at the knots of the natural cubic spline through (t, y)."""
    n = len(t)
    m = np.zeros(n)
    if n < 3:
        return m
    h = np.diff(t)
    # Thomas algorithm on the tridiagonal system for the interior knots.
    diag = 2 * (h[:-1] + h[1:])
    rhs = 6 * (np.diff(y[1:]) / h[1:] - np.diff(y[:-1]) / h[:-1])
    lower = h[1:-1].copy()
    for i in range(1, n - 2):
        w = lower[i - 1] / diag[i - 1]
        diag[i] -= w * lower[i - 1]
        rhs[i] -= w * rhs[i - 1]
    x = np.zeros(n - 2)
    x[-1] = rhs[-1] / diag[-1]
    for i in range(n - 4, -1, -1):
        x[i] = (rhs[i] - lower[i] * x[i + 1]) / diag[i]
    m[1:-1] = x
    return m


def evaluate(start: np.ndarray, end: np.ndarray, coefficients: np.ndarray, t: np.ndarray) -> np.ndarray:
    """θ at times ``t`` (host-side reference of the kernel's clamp_angle)."""
    t = np.asarray(t, dtype=float)
    if len(start) == 0:
        return np.zeros_like(t)
    i = np.clip(np.searchsorted(start, t, side="right") - 1, 0, len(start) - 1)
    tau = np.clip(t, start[i], end[i]) - start[i]
    return sum(coefficients[i, k] * tau**k for k in range(MAX_DEGREE + 1))
