"""The motion fit's search: a space-filling launch, then the speculative
Levenberg–Marquardt of :mod:`.lm`, every step one batched launch of the strip kernel."""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np
from tqdm import tqdm

from warpcloth.core.resources import check_memory
from warpcloth.errors import ArgumentError, checked_count
from warpcloth.io.measured import LaserTrace, SheetMarkers, TrackedShapes
from warpcloth.scene.sampling import latin_hypercube
from warpcloth.strip import RunResult

from ..bootstrap import block_bootstrap_sigma
from . import lm
from .continuum import continuum_limit
from .objective import SHIFT, FitObjective, make_objective
from .parameters import FreeParameter, initial_point
from .report import FitResult, summarise
from .verdict import check_given_noise, ended_at_bound, judged_noise

MAX_SPACE_FILLING = 10_000


def fit_motion(
    base: dict,
    measurement: LaserTrace | TrackedShapes | SheetMarkers,
    free: list[FreeParameter],
    *,
    align_start_s: float = 0.0,
    space_filling: int | None = None,
    max_iterations: int = 25,
    seed: int = 0,
    device: str | None = None,
    progress: bool = True,
    noise: float | None = None,
    bootstrap: int = 0,
    continuum: bool = True,
) -> FitResult:
    """Fit ``free`` parameters of raw scene ``base`` to ``measurement`` (see the module doc).

    ``noise`` is the measurement's σ (m) the RMS is judged against; by default it is
    estimated from the measurement (:func:`measurement_noise`). ``bootstrap`` > 0 adds a
    moving-block bootstrap σ from that many resamples (:mod:`.bootstrap`).
    ``continuum`` (the default) reports the values extrapolated to h → 0 with the mesh's
    share in σ (:mod:`.continuum`); ``False`` reports them at the scene's spacing, where
    the mesh's error is unknown, so the status is at best ``spacing_limited``."""
    started = time.perf_counter()
    # 0 is not "the default": a batch of none is refused, as is a σ from one resample
    n0 = max(16, 8 * len(free)) if space_filling is None else checked_count("space_filling", space_filling, 1)
    bootstrap = checked_count("bootstrap", bootstrap, 0)
    if bootstrap == 1:
        raise ArgumentError("bootstrap", "is 1: a bootstrap σ needs at least 2 resamples (0: no bootstrap)")
    check_given_noise(measurement, noise)
    objective = make_objective(base, measurement, free, align_start_s, device)
    rng = np.random.default_rng(seed)
    if n0 > MAX_SPACE_FILLING:
        raise ArgumentError(
            "space_filling",
            f"{n0} variants in one launch is more than {MAX_SPACE_FILLING}; a "
            "Latin hypercube of a few dozen per parameter finds the basin",
        )
    # the resamples' indices and residuals (8 B each, at most two residuals per measured row),
    # sized before hours of fitting, not after
    check_memory(
        16 * bootstrap * 2 * len(measurement.t),
        f"--bootstrap {bootstrap}: the resamples",
        "ask for fewer (a few thousand give σ to about 1 %)",
    )
    history = _History(objective, max_iterations + 1, progress)
    state, other_minima = _space_filling(objective, n0, rng, history)
    state, result = _levenberg_marquardt(objective, state, max_iterations, history)
    history.close()
    u, shift = state.q[: len(free)], objective.shift_of(state.q)
    jac, residual = state.jac, state.residual
    # the Jacobian must be taken at the reported point (the last launch's, after a full step)
    if history.rows[-1]["stage"] != "step" or jac is None or result is None:
        result, jac, residual = _jacobian_at(objective, u, shift)
    fit = summarise(objective, u, shift, jac, residual, history.rows, state.converged, time.perf_counter() - started)
    if bootstrap > 0:
        sigma, fit.bootstrap_block = block_bootstrap_sigma(jac / objective.ranges, residual, bootstrap, rng)
        fit.sigma_bootstrap = dict(zip(fit.parameters, sigma.tolist(), strict=True))
    fit.at_bound = ended_at_bound(free, u)
    fit.bounds = {p.field: (p.lower, p.upper) for p in free} | (
        {SHIFT: (-objective.align, objective.align)} if objective.align else {}
    )
    fit.noise, fit.noise_source = judged_noise(measurement, noise, residual)
    fit.other_minima = other_minima
    fit.mesh_note = objective.mesh_note()
    fit.dt_s = objective.dt_s
    fit.spacing = {name: objective.spacing_of(name) for name in objective.spacing_fields}
    # result row 0 is the reported point (accepted last, or re-run above)
    missing = int(np.isnan(objective.residuals(result, 0, shift, penalise=False)).sum())
    order = objective.continuum_order()
    if continuum and order is not None and not missing:
        q = np.append(u, shift) if objective.align else u.copy()
        noise_sigma = np.array([fit.sigma[name] for name in objective.names])
        fit.apply_continuum(continuum_limit(objective, q, jac, residual, noise_sigma, order), objective)
    elif not continuum:
        fit.continuum = {"status": "not requested"}
    fit.wall_time_s = time.perf_counter() - started
    fit.judge(missing)
    return fit


class _History:
    # The search's history, one row per launch, shown on a progress bar whose total is the
    # most launches it may take, set to those it took when it ends.
    def __init__(self, objective: FitObjective, total: int, progress: bool) -> None:
        self.objective = objective
        self.rows: list[dict] = []
        self.bar = tqdm(total=total, desc="fit", unit="launch", disable=not progress)

    def __call__(self, stage: str, u: np.ndarray, shift: float, rms: float) -> None:
        self.rows.append(
            {"launch": self.objective.launches, "stage": stage, "rms": rms, "shift_s": shift} | self.objective.values(u)
        )
        self.bar.set_postfix(rms=f"{rms * 1e3:.4g} mm")  # the unit the result is printed in
        self.bar.update(1)

    def close(self) -> None:
        # The total was the most launches the search may take (--max-iterations); it
        # usually converges in far fewer, and a bar left at 15-50 % reads as a fit cut short
        self.bar.total = self.bar.n
        self.bar.refresh()
        self.bar.close()


def _space_filling(
    objective: FitObjective, n0: int, rng: np.random.Generator, record: _History
) -> tuple[lm.State, list[dict]]:
    # 1. One launch of a Latin hypercube (the scene's own values join the sample); its
    # best point starts the local search, its other basins are reported.
    d = len(objective.free)
    points = np.vstack([initial_point(objective.free), latin_hypercube(n0, d, rng)])
    result = objective.run(points)
    shifts = [objective.best_shift(result, j) for j in range(len(points))]
    costs = [np.mean(objective.residuals(result, j, s) ** 2) for j, s in enumerate(shifts)]
    best = int(np.argmin(costs))
    u, shift, cost = points[best], shifts[best], costs[best]
    record("space filling", u, shift, math.sqrt(cost))
    other_minima = _other_minima(objective, points, np.array(costs), best)
    q = np.append(u, shift) if objective.align else u.copy()  # the search is on q = (u, δ if aligning)
    return lm.start(q, cost, objective.residuals(result, best, shift)), other_minima


def _levenberg_marquardt(
    objective: FitObjective, state: lm.State, max_iterations: int, record: _History
) -> tuple[lm.State, RunResult | None]:
    # 2. Speculative Levenberg–Marquardt (.lm): each launch holds the proposed step, its
    # stencil and the cautious steps. Returns the last launch's result too (None without
    # one), whose row 0 is the last full step.
    d = len(objective.free)
    lower, upper = objective.box()
    result: RunResult | None = None
    for _ in range(max_iterations):
        proposals = lm.proposals(state, lower, upper)
        stencil_rows, pairs = lm.stencil(proposals[0][:d])
        result = objective.run(np.vstack([proposals[0][:d], *stencil_rows, *[p[:d] for p in proposals[1:]]]))
        rows = [0, *range(1 + 2 * d, 2 * d + len(proposals))]
        residuals = [
            objective.residuals(result, row, objective.shift_of(p)) for row, p in zip(rows, proposals, strict=True)
        ]
        jacobian = partial(objective.jacobian, result, pairs, 0, objective.shift_of(proposals[0]))
        state, stage = lm.step(state, proposals, residuals, jacobian)
        record(stage, state.q[:d], objective.shift_of(state.q), math.sqrt(state.cost))
        if state.converged:
            break
    return state, result


def _jacobian_at(objective: FitObjective, u: np.ndarray, shift: float) -> tuple[RunResult, np.ndarray, np.ndarray]:
    # One launch of u and its stencil: the result, the Jacobian and the residuals there.
    stencil_rows, pairs = lm.stencil(u)
    result = objective.run(np.vstack([u, *stencil_rows]))
    return result, objective.jacobian(result, pairs, 0, shift), objective.residuals(result, 0, shift)


MINIMA_SEPARATION = 0.25  # unit-box distance beyond which two low points may be different basins
MINIMA_FACTOR = 2.0  # a basin counts if its cost is within this factor of the best one's


def _other_minima(objective: FitObjective, points: np.ndarray, costs: np.ndarray, best: int) -> list[dict]:
    """Low points of the space-filling sample in basins other than the best one's.

    Candidates are sample points within :data:`MINIMA_FACTOR` of the best cost and
    :data:`MINIMA_SEPARATION` away from it and from each other; one launch evaluates the
    midpoint of each with the best, and a candidate is a separate basin when that
    midpoint is higher than both ends (a ridge between them)."""
    chosen: list[int] = [best]
    for j in np.argsort(costs):
        if costs[j] > MINIMA_FACTOR * costs[best] or len(chosen) > 4:
            break
        if all(np.linalg.norm(points[j] - points[c]) > MINIMA_SEPARATION for c in chosen):
            chosen.append(int(j))
    candidates = chosen[1:]
    if not candidates:
        return []
    midpoints = np.array([(points[best] + points[j]) / 2 for j in candidates])
    result = objective.run(midpoints)
    out = []
    for k, j in enumerate(candidates):
        shift = objective.best_shift(result, k)
        ridge = float(np.mean(objective.residuals(result, k, shift) ** 2))
        if ridge > max(costs[best], costs[j]):
            out.append(
                {"rms_mm": math.sqrt(costs[j]) * 1e3, "ridge_rms_mm": math.sqrt(ridge) * 1e3}
                | objective.values(points[j])
            )
    return out
