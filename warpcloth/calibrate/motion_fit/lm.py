"""The batched speculative Levenberg–Marquardt of the motion fit, in NumPy alone.

Every launch of the strip kernel is one batch, so each iteration proposes several points
at once: the Levenberg–Marquardt step from the current Jacobian, the central-difference
:func:`stencil` around it (so if it is accepted its Jacobian comes with it), and two more
cautious steps (10× and 100× the damping) in case it is not. These functions hold the
algorithm and nothing else; the caller evaluates the points, all in one batch
(:func:`warpcloth.calibrate.motion_fit.fit_motion` runs them as one launch; the tests an
analytic model)::

    state = start(q, cost, residual)
    while not state.converged:
        points = proposals(state, lower, upper)     # plus stencil(points[0]), one batch
        state, stage = step(state, points, their_residuals, jacobian_at_points_0)

Not :func:`scipy.optimize.least_squares`: it asks for one residual vector (or one
Jacobian) per call, each a launch of its own.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

STENCIL_STEP = 2e-3  # central-difference step, as a fraction of each parameter's range
INITIAL_LAMBDA = 1e-2
MIN_LAMBDA = 1e-7
MAX_LAMBDA = 1e8  # a damping this large means no step lowers the cost: the search has stopped
CAUTION = (1, 10, 100)
"""The damping factors of the speculative steps: the step itself and two fallbacks."""
CONVERGED_IMPROVEMENT = 1e-4
"""An accepted step that lowers the cost by at most this fraction of it ends the search."""


@dataclass(frozen=True)
class State:
    """Where the search stands: the point ``q``, its cost (mean squared residual) and
    residuals, the Jacobian there (None before the first launch), the damping λ."""

    q: np.ndarray
    cost: float
    residual: np.ndarray
    jac: np.ndarray | None
    lam: float
    converged: bool = False


def start(q: np.ndarray, cost: float, residual: np.ndarray) -> State:
    """The search's state at a starting point (whose Jacobian the first launch takes)."""
    return State(q, cost, residual, None, INITIAL_LAMBDA)


def lm_step(
    q: np.ndarray, jac: np.ndarray, residual: np.ndarray, lam: float, lower: np.ndarray, upper: np.ndarray
) -> np.ndarray:
    """The damped Gauss–Newton step (JᵀJ + λ diag JᵀJ) Δ = −Jᵀr from ``q``, clipped into
    the box [``lower``, ``upper``]."""
    normal = jac.T @ jac
    scale = np.diag(normal).copy()
    scale[scale <= 0] = 1.0
    point = q + np.linalg.solve(normal + lam * np.diag(scale), -jac.T @ residual)
    return np.clip(point, lower, upper)


def proposals(state: State, lower: np.ndarray, upper: np.ndarray) -> list[np.ndarray]:
    """The points the next batch evaluates: the current one alone on the first launch (for
    its Jacobian), then the step at each damping of :data:`CAUTION`."""
    if state.jac is None:
        return [state.q]
    return [lm_step(state.q, state.jac, state.residual, state.lam * f, lower, upper) for f in CAUTION]


def stencil(point: np.ndarray) -> tuple[list[np.ndarray], list[tuple[int, int, float]]]:
    """The central-difference rows around a unit-box ``point`` (+h and −h along each
    coordinate, kept inside [0, 1]) and, for each coordinate, (plus row, minus row, Δ) with
    rows counted from 1 (row 0 of the batch is the point itself)."""
    rows, pairs = [], []
    for i in range(len(point)):
        plus, minus = point.copy(), point.copy()
        plus[i] = min(point[i] + STENCIL_STEP, 1.0)
        minus[i] = max(point[i] - STENCIL_STEP, 0.0)
        pairs.append((1 + 2 * i, 2 + 2 * i, plus[i] - minus[i]))
        rows += [plus, minus]
    return rows, pairs


def step(
    state: State, points: Sequence[np.ndarray], residuals: Sequence[np.ndarray], jacobian: Callable[[], np.ndarray]
) -> tuple[State, str]:
    """The state after a batch evaluated :func:`proposals` ``points`` (their ``residuals``;
    ``jacobian()`` gives the Jacobian at ``points[0]``), and what happened: ``"step"`` (the
    full step is taken, with its Jacobian; λ falls), ``"cautious step"`` (a fallback is
    taken, the Jacobian kept; λ × 10) or ``"rejected"`` (λ × 100)."""
    costs = [float(np.mean(r**2)) for r in residuals]
    if state.jac is None or costs[0] < state.cost:
        improvement = state.cost - costs[0] if state.jac is not None else math.inf
        return State(
            points[0],
            costs[0],
            residuals[0],
            jacobian(),
            max(state.lam / 3, MIN_LAMBDA),
            0 <= improvement <= CONVERGED_IMPROVEMENT * costs[0],
        ), "step"
    if min(costs[1:]) < state.cost:
        k = 1 + int(np.argmin(costs[1:]))
        return replace(state, q=points[k], cost=costs[k], residual=residuals[k], lam=state.lam * 10), "cautious step"
    lam = state.lam * 100
    return replace(state, lam=lam, converged=lam > MAX_LAMBDA), "rejected"


def covariance(jac: np.ndarray, residual: np.ndarray | None = None) -> np.ndarray:
    """The Gauss–Newton covariance (JᵀJ)⁻¹, times the residual variance s² = rᵀr / (n − p)
    when ``residual`` is given; NaN throughout for a singular JᵀJ."""
    p = jac.shape[1]
    try:
        inverse = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return np.full((p, p), np.nan)
    if residual is None:
        return inverse
    return float(residual @ residual) / max(len(residual) - p, 1) * inverse


def clustered_covariance(jac: np.ndarray, residual: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, int]:
    """The covariance of the least-squares parameters robust to errors correlated within
    each group (the residuals of one tracked frame share its free end's error; Liang and
    Zeger's sandwich, with the small-sample factor G/(G−1)·(n−1)/(n−p)): (JᵀJ)⁻¹ (Σ_g
    J_gᵀ r_g r_gᵀ J_g) (JᵀJ)⁻¹. Consecutive groups whose scores J_gᵀ r_g stay correlated
    (a slow error: the tip's along a swing) are merged into blocks of the scores'
    correlation length, as the block bootstrap does (:func:`~warpcloth.calibrate.bootstrap.correlation_length`).
    Returns it and the groups per block; NaN throughout for a singular JᵀJ."""
    from warpcloth.calibrate.bootstrap import correlation_length

    n, p = jac.shape
    bread = covariance(jac)
    if np.isnan(bread).any():
        return bread, 1
    labels, index = np.unique(groups, return_inverse=True)
    scores = np.zeros((len(labels), p))
    np.add.at(scores, index, jac * residual[:, None])
    block = max(correlation_length(scores[:, k]) for k in range(p)) if len(labels) > 2 else 1
    block = min(block, max(1, len(labels) // 4))  # at least four blocks: a sandwich of fewer says nothing
    blocks = np.add.reduceat(scores, np.arange(0, len(labels), block), axis=0)
    g = len(blocks)
    meat = blocks.T @ blocks * (g / max(g - 1, 1)) * ((n - 1) / max(n - p, 1))
    return bread @ meat @ bread, block


def sigma_and_correlation(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The standard deviations and the correlation matrix of a covariance matrix."""
    sigma = np.sqrt(np.clip(np.diag(cov), 0, None))
    return sigma, cov / np.outer(sigma, sigma)
