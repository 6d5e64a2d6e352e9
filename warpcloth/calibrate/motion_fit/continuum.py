"""The continuum limit of a motion fit: the fabric's parameters, not the mesh's.

A measurement is of the continuum; the fit's runs are of a mesh of spacing h, whose own
error moves the fitted values far beyond their noise σ on the bundled scenes' spacings
(docs/calibration.md, "The node spacing"). Under a law that converges in h at order p
(every law with return-point memory: :attr:`~warpcloth.kernels.law.BendingLaw.mesh_independent`;
p = 2 with the second-order clamp edge, 1 with the paper's), the simulated observables at
the fitted point q obey r_h(q) = r_0(q) + C(q) h^p + …, so

1. **The order is checked.** The best point is run at 2h and h/2 (one variant each; the
   step scaled with h as :meth:`~.objective.FitObjective.refined` says) and the observed
   order p_obs = log₂(‖x_h − x_2h‖ / ‖x_h/2 − x_h‖) compared with p, x_k = −J⁺ r_k the
   point level k's motion asks for in units of σ_noise (what the values see). Outside
   p ± :data:`ORDER_TOLERANCE` the ladder is refined once (h, h/2, h/4); if the three
   finer levels still disagree, there is no extrapolation the evidence supports and the
   fit says so (``spacing_limited``).
2. **The residual is extrapolated** from the finest two levels (c, f = c/2) by Richardson,
   r_∞(q) = r_f(q) + (r_f(q) − r_c(q)) / (2^p − 1), and the parameters follow it by
   Gauss–Newton steps with the fit's own Jacobian, q ← q − J⁺ r_∞(q), each step one run
   at c and one at f, until a step moves every parameter by less than
   :data:`SETTLED` × its noise σ (at most :data:`MAX_STEPS` steps, else ``spacing_limited``).
   At the fit's optimum J⁺ r_h = 0, so the first step is the Richardson extrapolation
   of the parameters themselves: (2^p / (2^p − 1)) × the move that refitting at h/2 would
   make (the old ``--check-spacing`` move, ×4/3 at p = 2).
3. **The mesh's share of σ** is the size of the extrapolation's correction from the
   finest level, σ_mesh = ``|J⁺(r_f − r_c)|`` / (2^p − 1) (or, where larger, what
   extrapolating at the observed order would change), with the last, linearly applied
   step added in quadrature. It bounds the extrapolation's error whenever the true order lies
   within p ± 1/2, the band the order check accepts (at order 1.5 the correction with
   p = 2 is 0.21 of the level difference short, at 2.5 0.12 too long; the correction
   itself is 0.33 of it), and σ_total² = σ_noise² + σ_mesh².

The Jacobian is the fit's at h (refreshing it at the finest level would cost 2d + 1 fine
runs), so the values carry a bias of order σ_noise × its relative change between levels.

Why this method, measured against a ladder of refits (benchmarks/continuum_fit.py,
docs/calibration.md): as accurate, at 1.1–1.7× the fit alone on the bundled strips where
the ladder costs 1.9–9.5×.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from warpcloth.errors import ArgumentError, SceneError

from .objective import FitObjective

ORDER_TOLERANCE = 0.5
"""The observed order may differ from the law's by this much (see the module doc: within it
σ_mesh bounds the error of extrapolating at the law's order)."""
LEVEL_RATIO = 2.0
"""Successive levels' spacing ratio."""
SETTLED = 1.0 / 3.0
"""A Gauss–Newton step on the extrapolated residual below this × σ_noise for every
parameter ends the iteration."""
MAX_STEPS = 4
NEGLIGIBLE = 1e-3
"""Finer levels whose values differ by less than this × σ_noise (all together) leave the
mesh nothing that matters to converge: no order is needed."""
ROUND_OFF = 1e-10
"""Levels whose residuals differ by less than this × the residuals' norm agree to
round-off: the mesh does not move the fit."""


@dataclass
class ContinuumEstimate:
    """The fit extrapolated to h → 0: the values, their mesh σ, and the evidence."""

    status: str  # "extrapolated", or "unresolved" (the levels disagree with the law's order)
    order: float  # the law's order in h (p)
    levels_mm: list[float]  # every spacing run (coarse to fine)
    pair_mm: tuple[float, float] = (math.nan, math.nan)  # the levels extrapolated from (c, f)
    observed_orders: list[dict] = field(default_factory=list)  # {"levels_mm": [3], "order": p_obs}
    q: np.ndarray | None = None  # the extrapolated search point (unit box, clock offset)
    sigma_mesh: np.ndarray | None = None  # per search coordinate, in the field's units
    residual: np.ndarray | None = None  # r_∞ at q (extrapolated: no run made it)
    residual_finest: np.ndarray | None = None  # the finest level's residual at q (its run, and the last step)
    moves: list[np.ndarray] = field(default_factory=list)  # each Gauss–Newton step, field units
    note: str = ""
    runs: int = 0
    wall_time_s: float = 0.0
    dt_s: dict[float, float] = field(default_factory=dict)  # each level's step
    finest: FitObjective | None = None  # the objective at the finest level of the pair

    def to_json(self, names: list[str]) -> dict:
        """The evidence as fit.json's ``continuum``: levels, orders, steps, the correction."""
        out = {
            "status": self.status,
            "law_order": self.order,
            "levels_mm": self.levels_mm,
            "dt_s": {f"{h:g}": dt for h, dt in self.dt_s.items()},
            "observed_orders": self.observed_orders,
            "note": self.note,
            "runs": self.runs,
            "wall_time_s": self.wall_time_s,
        }
        if self.status == "extrapolated":
            out |= {
                "extrapolated_from_mm": list(self.pair_mm),
                "steps": [dict(zip(names, m.tolist(), strict=True)) for m in self.moves],
            }
        return out


def observed_order(coarse: np.ndarray, middle: np.ndarray, fine: np.ndarray, negligible: float = 0.0) -> float:
    """log₂ of the ratio of successive level differences (levels at spacing ratio 2);
    +inf when the two finer levels agree to round-off, or within ``negligible`` (nothing
    left to converge that matters)."""
    far, near = float(np.linalg.norm(middle - coarse)), float(np.linalg.norm(fine - middle))
    scale = max(ROUND_OFF * max(float(np.linalg.norm(fine)), 1e-300), negligible)
    if near <= scale:
        return math.inf
    return math.log(far / near, LEVEL_RATIO) if far > 0 else -math.inf


def continuum_limit(
    objective: FitObjective,
    q: np.ndarray,
    jac: np.ndarray,
    residual: np.ndarray,
    sigma_noise: np.ndarray,
    order: float,
) -> ContinuumEstimate:
    """Extrapolate the fit at search point ``q`` (its Jacobian ``jac`` in search
    coordinates and residuals ``residual`` at the objective's spacing h) to h → 0 at the
    law's ``order`` (see the module doc). ``sigma_noise`` is each search coordinate's
    noise σ in its field's units (the clock offset's in seconds)."""
    started = time.perf_counter()
    d = len(objective.free)
    ranges = objective.ranges
    h = objective.spacing_mm
    objectives: dict[float, FitObjective] = {1.0: objective}
    estimate = ContinuumEstimate("unresolved", order, [])

    def level(factor: float) -> FitObjective:
        if factor not in objectives:
            objectives[factor] = objective.refined(factor)
        return objectives[factor]

    unavailable: list[str] = []

    def at(factor: float, point: np.ndarray) -> np.ndarray:
        obj = level(factor)
        estimate.runs += 1
        return obj.residuals(obj.run(point[:d][None]), 0, obj.shift_of(point), penalise=False)

    def finish(note: str) -> ContinuumEstimate:
        estimate.note = note
        estimate.levels_mm = sorted((h * f for f in objectives), reverse=True)
        estimate.dt_s = {h * f: obj.dt_s for f, obj in sorted(objectives.items())[::-1]}
        estimate.wall_time_s = time.perf_counter() - started
        return estimate

    def move(r: np.ndarray) -> np.ndarray:
        # the Gauss–Newton step −J⁺ r in search coordinates
        return -np.linalg.lstsq(jac, r, rcond=None)[0]

    def weighted(r: np.ndarray) -> np.ndarray:
        # what of a level's motion the values see: its Gauss–Newton point, in units of σ_noise
        return move(r) * ranges / sigma_noise

    residuals = {1.0: residual}
    ladder = [(LEVEL_RATIO, 1.0, 1 / LEVEL_RATIO), (1.0, 1 / LEVEL_RATIO, 1 / LEVEL_RATIO**2)]
    pair: tuple[float, float] | None = None
    for levels in ladder:
        try:
            for f in levels:
                if f not in residuals:
                    residuals[f] = at(f, q)
        except (SceneError, ArgumentError) as exc:  # a level the scene cannot be built at (a marker off its nodes)
            unavailable.append(f"h = {h * f:g} mm cannot be run ({exc})")
            continue
        missing = [f for f in levels if not np.all(np.isfinite(residuals[f]))]
        if missing and missing[0] > 1.0:  # the coarser level alone: the finer rung does without it
            unavailable.append(f"at h = {h * missing[0]:g} mm the best fit misses measured points")
            continue
        if missing:
            return finish(
                f"the best fit run at h = {h * missing[0]:g} mm misses measured points (the laser line, or it "
                "diverged): no continuum estimate"
            )
        coarse_point, middle_point, fine_point = (weighted(residuals[f]) for f in levels)
        p_obs = observed_order(coarse_point, middle_point, fine_point, negligible=NEGLIGIBLE)
        estimate.observed_orders.append({"levels_mm": [h * f for f in levels], "order": p_obs})
        if abs(p_obs - order) <= ORDER_TOLERANCE or p_obs == math.inf:
            pair = levels[1], levels[2]
            break
    if pair is None:
        found = ", ".join(
            f"{o['order']:.2f} from h = {'/'.join(f'{x:g}' for x in o['levels_mm'])} mm"
            for o in estimate.observed_orders
        )
        return finish(
            "; ".join(
                unavailable
                + [
                    f"the simulated motion converges at order {found}, not the law's {order:g} "
                    f"(± {ORDER_TOLERANCE:g}): the mesh is not in its asymptotic range, so no extrapolation is "
                    "supported; fit at a finer spacing"
                ]
            )
        )
    coarse, fine = pair
    gain = 1.0 / (LEVEL_RATIO**order - 1.0)

    def extrapolated(rc: np.ndarray, rf: np.ndarray) -> np.ndarray:
        return rf + (rf - rc) * gain

    # σ_mesh: the correction from the finest level, or, if larger, what extrapolating at the
    # observed order instead of the law's would change (at p = 1 the band reaches orders
    # whose true correction exceeds the law's)
    level_move = np.abs(move(residuals[fine] - residuals[coarse])) * ranges
    gain_observed = 0.0 if p_obs == math.inf else 1.0 / (LEVEL_RATIO ** max(p_obs, 1e-3) - 1.0)
    correction = level_move * max(gain, abs(gain_observed - gain))
    point = q.copy()
    rc, rf = residuals[coarse], residuals[fine]
    lower, upper = objective.box()
    for _ in range(MAX_STEPS + 1):
        target = np.clip(point + move(extrapolated(rc, rf)), lower, upper)  # a coordinate on a bound stays
        applied = target - point
        estimate.moves.append(applied * ranges)
        if np.all(np.abs(applied * ranges) <= SETTLED * sigma_noise):
            # small enough to take linearly: applied, its residual predicted, its size in σ_mesh
            estimate.residual_finest = rf + jac @ applied
            estimate.residual = extrapolated(rc, rf) + jac @ applied
            point = target
            break
        point = target
        rc, rf = at(coarse, point), at(fine, point)
        if not (np.all(np.isfinite(rc)) and np.all(np.isfinite(rf))):
            return finish("a run on the way to the continuum estimate misses measured points: no estimate")
    else:
        return finish(
            f"the continuum estimate did not settle in {MAX_STEPS} Gauss–Newton steps (the last moved "
            + ", ".join(f"{n} {m:+.3g}" for n, m in zip(objective.names, estimate.moves[-1], strict=True))
            + "): the mesh's error is too large to extrapolate linearly; fit at a finer spacing"
        )
    estimate.status = "extrapolated"
    estimate.pair_mm = (h * coarse, h * fine)
    estimate.q = point
    estimate.sigma_mesh = np.hypot(correction, estimate.moves[-1])
    estimate.finest = level(fine)
    return finish("; ".join(unavailable))  # why the ladder started finer, if it did
