"""Least squares under inequality constraints, for the KES fits (docs/model.md §13.2,
§13.3): non-negative least squares, and least squares subject to ``g x ≥ h`` through the
least-distance problem (Lawson & Hanson, *Solving Least Squares Problems*, ch. 23)."""

from __future__ import annotations

import numpy as np


def nnls(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """min ‖a x − b‖ subject to x ≥ 0, by Lawson & Hanson's active-set algorithm."""
    m, n = a.shape
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    tol = 10 * np.finfo(float).eps * np.linalg.norm(a, 1) * max(m, n)
    for _ in range(3 * n + 10):
        w = np.where(passive, -np.inf, a.T @ (b - a @ x))
        if passive.all() or np.max(w) <= tol:
            break
        passive[int(np.argmax(w))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(a[:, passive], b, rcond=None)[0]
            if np.all(z[passive] > 0):
                x = z
                break
            # step back towards x until the first variable reaches 0, and free it
            blocking = np.nonzero(passive & (z <= 0))[0]
            ratios = x[blocking] / (x[blocking] - z[blocking])
            x = x + np.min(ratios) * (z - x)
            x[blocking[np.argmin(ratios)]] = 0.0
            passive &= x > 0
            x[~passive] = 0.0
    return x


def least_squares_above(a: np.ndarray, b: np.ndarray, g: np.ndarray, h: np.ndarray) -> np.ndarray:
    """min ‖a x − b‖ subject to g x ≥ h (a of full column rank).

    Via the least-distance problem and :func:`nnls`; raises ValueError if the
    constraints are infeasible.
    """
    q, r = np.linalg.qr(a)
    rinv = np.linalg.inv(r)
    y0 = q.T @ b  # x = rinv (z + y0); minimise ‖z‖ subject to (g rinv) z ≥ h − g rinv y0
    gz = g @ rinv
    hz = h - gz @ y0
    norms = np.linalg.norm(gz, axis=1, keepdims=True)  # same constraints, comparable scales
    gz, hz = gz / norms, hz / norms[:, 0]
    e = np.vstack([gz.T, hz[None, :]])
    f = np.zeros(e.shape[0])
    f[-1] = 1.0
    u = nnls(e, f)
    residual = e @ u - f
    if np.linalg.norm(residual) < 1e-12:
        raise ValueError("the constraints are infeasible")
    z = -residual[:-1] / residual[-1]
    return rinv @ (z + y0)
