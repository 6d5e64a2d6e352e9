"""Least squares under linear inequality constraints, for the tensile fit (docs/model.md
§13.2): least squares subject to ``g x ≥ h`` through the least-distance problem (Lawson &
Hanson, *Solving Least Squares Problems*, ch. 23), whose non-negative least squares is
:func:`scipy.optimize.nnls`."""

from __future__ import annotations

import numpy as np
from scipy.optimize import nnls

from warpcloth.errors import ArgumentError


def least_squares_above(a: np.ndarray, b: np.ndarray, g: np.ndarray, h: np.ndarray) -> np.ndarray:
    """min ‖a x − b‖ subject to g x ≥ h (a of full column rank).

    Via the least-distance problem and :func:`scipy.optimize.nnls`; raises an
    ArgumentError naming ``h`` (a ValueError) if the constraints are infeasible. SciPy has
    no solver for this problem itself: :func:`scipy.optimize.lsq_linear` takes bounds on x
    only, not general rows g x ≥ h, and ``minimize(method="SLSQP")`` or ``"trust-constr"``
    are iterative nonlinear solvers that stop at a tolerance, where this reduction is exact
    to rounding in one NNLS solve.
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
    u, _ = nnls(e, f)
    residual = e @ u - f
    if np.linalg.norm(residual) < 1e-12:
        raise ArgumentError("h", "the constraints g x ≥ h are infeasible")
    z = -residual[:-1] / residual[-1]
    return rinv @ (z + y0)
