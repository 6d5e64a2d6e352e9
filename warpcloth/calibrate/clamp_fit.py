"""Fitting the paper's clamp motion, a quartic then a straight line, to an encoder series.

The model (paper Fig. 12, with its onset and stop found by the fit)::

    θ(t) = θ0                                   t < t0
         = θ0 + c (t − t0)⁴                     t0 ≤ t < t1     (the impulsive start)
         = θ0 + c (t1 − t0)⁴ + ω (t − t1)       t1 ≤ t < t2     (constant angular speed)
         = θ(t2)                                t ≥ t2          (the clamp stops)

For given breakpoints (t0, t1, t2) the model is linear in (θ0, c, ω), so each candidate
is a 3-unknown least-squares solve; the breakpoints are chosen by a grid search over
the data's time range refined around the best cell. The slope is left free at t1 (the
paper's fit is two pieces, not a spline); the fit reports the slope jump so a user can
see whether the data support a smooth join.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from warpcloth.errors import OptionError

GRID = 24  # breakpoint candidates per axis and refinement round
ROUNDS = 5
MIN_SAMPLES = 12


@dataclass(frozen=True)
class ClampMotionFit:
    """A fitted quartic-then-line clamp motion (SI: s, rad, rad/s)."""

    onset_s: float
    break_s: float
    stop_s: float
    theta0_rad: float
    quartic_rad_per_s4: float
    speed_rad_per_s: float
    rms_rad: float
    n_samples: int

    @property
    def slope_jump_rad_per_s(self) -> float:
        """ω minus the quartic's slope at the break (0 for a smooth join)."""
        return self.speed_rad_per_s - 4 * self.quartic_rad_per_s4 * (self.break_s - self.onset_s) ** 3

    def theta(self, t: np.ndarray) -> np.ndarray:
        """The fitted θ(t)."""
        t = np.asarray(t, dtype=float)
        quartic = np.clip(np.minimum(t, self.break_s) - self.onset_s, 0, None) ** 4
        line = np.clip(np.minimum(t, self.stop_s) - self.break_s, 0, None)
        return self.theta0_rad + self.quartic_rad_per_s4 * quartic + self.speed_rad_per_s * line

    def segments(self) -> list[dict]:
        """The motion as scene ``clamp.segments`` (θ = Σ c_k (t − t_start)^k), measured
        from the encoder's reading at rest θ0: a scene's θ turns the clamp away from the
        hanging rest shape, so an encoder zero offset must not become a jump at t = 0."""
        theta_break = self.quartic_rad_per_s4 * (self.break_s - self.onset_s) ** 4
        return [
            {"t_start_s": self.onset_s, "t_end_s": self.break_s,
             "theta_coefficients_si": [0.0, 0.0, 0.0, 0.0, self.quartic_rad_per_s4]},
            {"t_start_s": self.break_s, "t_end_s": self.stop_s,
             "theta_coefficients_si": [theta_break, self.speed_rad_per_s]},
        ]


def _costs(t: np.ndarray, theta: np.ndarray, t0: float, t1: np.ndarray,
           t2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # Squared residual and coefficients for one onset and many (t1, t2) pairs at once,
    # through the 3×3 normal equations. Times are in units of the data's span, so the
    # columns are O(1) and a tiny ridge only matters for an empty column.
    quartic = np.clip(np.minimum(t[None], t1[:, None]) - t0, 0, None) ** 4
    line = np.clip(np.minimum(t[None], t2[:, None]) - t1[:, None], 0, None)
    a = np.stack([np.ones_like(quartic), quartic, line], axis=-1)  # [pair, sample, 3]
    normal = np.einsum("psi,psj->pij", a, a)
    normal += 1e-12 * np.trace(normal, axis1=1, axis2=2)[:, None, None] * np.eye(3)
    rhs = np.einsum("psi,s->pi", a, theta)
    coefficients = np.linalg.solve(normal, rhs[..., None])[..., 0]
    residual = np.einsum("psi,pi->ps", a, coefficients) - theta[None]
    return np.sum(residual**2, axis=1), coefficients


def fit_clamp_motion(t: np.ndarray, theta: np.ndarray) -> ClampMotionFit:
    """Least-squares quartic-then-line fit of an encoder series (s, rad)."""
    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    start = t[0]
    if len(t) < MIN_SAMPLES:
        raise OptionError("ENCODER", f"{len(t)} samples are too few to place three breakpoints; "
                          f"give at least {MIN_SAMPLES}")
    if np.ptp(theta) <= 0:
        raise OptionError("ENCODER", "the angle never changes: there is no clamp motion to fit")
    scale = t[-1] - t[0]
    t = (t - t[0]) / scale
    lo, hi = 0.0, 1.0
    best = (np.inf, None, None)
    span = hi - lo
    centre = None
    for _ in range(ROUNDS):
        if centre is None:
            axes = [np.linspace(lo, hi, GRID)] * 3
        else:
            axes = [np.clip(np.linspace(c - span, c + span, GRID), lo, hi) for c in centre]
        for t0 in axes[0]:
            t1, t2 = (g.ravel() for g in np.meshgrid(axes[1], axes[2], indexing="ij"))
            valid = (t1 > t0) & (t2 > t1)
            if not valid.any():
                continue
            costs, coefficients = _costs(t, theta, t0, t1[valid], t2[valid])
            k = int(np.argmin(costs))
            if costs[k] < best[0]:
                best = (costs[k], (t0, t1[valid][k], t2[valid][k]), coefficients[k])
        centre = best[1]
        span = 2 * span / GRID
    cost, breaks, (theta0, quartic, speed) = best
    t0, t1, t2 = (start + b * scale for b in breaks)
    return ClampMotionFit(float(t0), float(t1), float(t2), float(theta0), float(quartic / scale**4),
                          float(speed / scale), float(np.sqrt(cost / len(t))), len(t))


def scene_with_clamp_motion(raw_scene: dict, fit: ClampMotionFit) -> dict:
    """A copy of raw scene data whose clamp follows ``fit`` (motion = "piecewise")."""
    data = copy.deepcopy(raw_scene)
    clamp = data.setdefault("clamp", {})
    clamp["motion"] = "piecewise"
    clamp["segments"] = fit.segments()
    for key in ("table_t_s", "table_theta_rad"):
        clamp.pop(key, None)
    return data
