"""Fitting the clamp motion to an encoder series: rest, a general quartic, straight lines,
and rest again if the clamp stops within the record (the paper's Fig. 12 fitted a
4th-order polynomial to its encoder start, then a constant speed).

The forms (:data:`FORMS`)::

    θ(t) = θ0                                          t < t0          (at rest)
         = θ0 + a1 τ + a2 τ² + a3 τ³ + a4 τ⁴, τ = t − t0   t0 ≤ t < t1     (the impulsive start)
         = θ(t1) + ω1 (t − t1),  ω1 = θ'(t1⁻)          t1 ≤ t < t2     (constant angular speed)
         = θ(t2) + ω2 (t − t2)                         t2 ≤ t < ts     (a second speed, if any)
         = θ(ts)                                       t ≥ ts          (stopped, if it stops)

A record that starts at rest reads θ0 from it: the mean of the samples before the onset,
not a fitted constant (an encoder offset must not trade against the start). Many rigs
trigger the recording on the motion, so a record may have no rest: its "moving" forms
put the onset at the first sample t0 = t[0] and fit θ0 with a1…a4 (an onset before the
record is the same quartic re-expanded: θ0 and a1 take up the difference, so nothing in
the data places it). Both families are judged on every sample and by the same Bayesian
information criterion, each counting what it takes from the data (the moving forms one
breakpoint fewer), so a record with 0, 3 or 30 ms of rest before the motion gets the same
θ(t) within the noise (tests/test_calibration_path.py).

θ is continuous everywhere and θ' at the quartic's end (the line continues the start's
speed); between two lines and at the stop the speed may jump, as a drive's does. For given
breakpoints the model is linear in a1…a4 and the later speeds (and θ0 when moving), so each
candidate is one small least-squares solve; the breakpoints come from a grid over the
record refined by coordinate scans. The form is chosen by the lowest BIC among those the
data can hold (each needs a few samples per piece, a rest at least :data:`MIN_REST`).

The noise is estimated from the data, from the 4th differences of the whole record
(:func:`~warpcloth.calibrate.noise.difference_noise`, never below the encoder's count). A fit
whose RMS exceeds :data:`~warpcloth.calibrate.noise.POOR_FIT_FACTOR` × that noise (the rule
every fit shares, :func:`~warpcloth.calibrate.noise.poor_fit_ratio`) is ``poor_fit``: its
θ(t) does not describe the encoder and a scene driven by it would be wrong for the whole
record.

What the fit determines is θ(t) itself, within the noise. Its parameters may not be:
a quartic start is flat at its onset, so an earlier onset with a small a1…a3 draws the
same curve, and the coefficients of a polynomial over a short piece trade against each
other. :func:`parameter_uncertainties` gives each parameter's 1σ from the fit's
Jacobian and says which are not determined (:mod:`warpcloth.calibrate.uncertainty`), so
none is printed as if measured.
"""

from __future__ import annotations

import copy
import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from warpcloth.errors import ArgumentError

from .motion_fit.lm import covariance
from .noise import difference_noise, poor_fit_ratio
from .uncertainty import FittedValue, from_sigma, judge

FORMS = {
    "quartic, line, rest": (1, True, True),
    "quartic, line": (1, False, True),
    "quartic, line, line, rest": (2, True, True),
    "quartic, line, line": (2, False, True),
    "moving: quartic, line, rest": (1, True, False),
    "moving: quartic, line": (1, False, False),
    "moving: quartic, line, line, rest": (2, True, False),
    "moving: quartic, line, line": (2, False, False),
}
"""Each form's number of straight lines, whether the clamp comes to rest in the record, and
whether the record starts at rest (else "moving": the clamp is in motion at the first sample)."""
GRID = 26  # breakpoint candidates per axis in the first search
STARTS = 6  # best grid cells refined (a breakpoint search has local minima)
REFINE_ROUNDS = 6
MIN_PER_PIECE = 4  # samples a piece needs to be fitted
MIN_REST = 3  # samples before the onset needed to read the rest angle


@dataclass(frozen=True)
class ClampMotionFit:
    """A fitted clamp motion (SI: s, rad, rad/s^k) and how well it describes the encoder."""

    form: str
    onset_s: float
    breaks_s: tuple[float, ...]  # quartic → first line, then line → line
    stop_s: float | None  # None: still moving at the end of the record
    rest_rad: float  # θ0: the encoder's reading at rest, or θ fitted at the first sample of a moving record
    quartic_si: tuple[float, float, float, float]  # a1 … a4
    speeds_rad_per_s: tuple[float, ...]  # each line's speed
    rms_rad: float
    noise_rad: float
    noise_source: str
    n_samples: int
    bic: float
    status: str = "converged"
    problems: list[str] = field(default_factory=list)
    candidates: dict[str, float] = field(default_factory=dict)  # form → RMS (rad) of its best fit
    record_end_s: float = 0.0  # the encoder's last sample: a motion still going continues at least to here

    def theta(self, t: np.ndarray) -> np.ndarray:
        """The fitted θ(t)."""
        return self.rest_rad + _shape(
            np.atleast_1d(np.asarray(t, dtype=float)),
            self.onset_s,
            self.breaks_s,
            self.stop_s,
            np.array([*self.quartic_si, *self.speeds_rad_per_s[1:]]),
        )

    def segments(self, until_s: float | None = None) -> list[dict]:
        """The motion as scene ``clamp.segments`` (θ = Σ c_k (t − t_start)^k), measured
        from the rest reading θ0: a scene's θ turns the clamp away from the hanging rest
        shape, so an encoder offset must not become a jump at t = 0. A motion that does
        not stop in the record continues its last line to ``until_s`` (then holds)."""
        ends = [*self.breaks_s[1:], self.stop_s if self.stop_s is not None else max(until_s or 0.0, self.record_end_s)]
        pieces = [
            {"t_start_s": self.onset_s, "t_end_s": self.breaks_s[0], "theta_coefficients_si": [0.0, *self.quartic_si]}
        ]
        for start, end, speed in zip(self.breaks_s, ends, self.speeds_rad_per_s, strict=True):
            pieces.append(
                {
                    "t_start_s": start,
                    "t_end_s": end,
                    "theta_coefficients_si": [float(self.theta(start)[0] - self.rest_rad), speed],
                }
            )
        return pieces

    @property
    def moving_at_start(self) -> bool:
        """The clamp is in motion at the first sample (no rest before the onset in the record)."""
        return self.form.startswith("moving")

    @property
    def end_s(self) -> float:
        """The last breakpoint (the stop, or the last line's start)."""
        return self.stop_s if self.stop_s is not None else self.breaks_s[-1]

    @property
    def breakpoints_s(self) -> tuple[float, ...]:
        """Onset, breaks and stop, in time order."""
        return (self.onset_s, *self.breaks_s, *(() if self.stop_s is None else (self.stop_s,)))


def _shape(
    t: np.ndarray, t0: float, breaks: tuple[float, ...], stop: float | None, coefficients: np.ndarray
) -> np.ndarray:
    point = np.array([[t0, *breaks, *(() if stop is None else (stop,))]])
    return _columns(t, point, len(breaks), stop is not None)[0] @ coefficients


def _columns(t: np.ndarray, points: np.ndarray, lines: int, stops: bool) -> np.ndarray:
    # θ − θ0 = A @ (a1, a2, a3, a4, ω2, ...) for breakpoint sets ``points`` [candidate,
    # onset, breaks..., stop?]: every piece continues the one before it.
    t = t[None, :]
    t0, breaks = points[:, :1], [points[:, 1 + i : 2 + i] for i in range(lines)]
    te = np.minimum(t, points[:, -1:]) if stops else t
    t1 = breaks[0]
    tau = np.clip(np.minimum(te, t1) - t0, 0, None)
    tau1 = t1 - t0
    after = np.clip(np.minimum(te, breaks[1] if lines > 1 else np.inf) - t1, 0, None)
    cols = [tau**k + k * tau1 ** (k - 1) * after for k in range(1, 5)]
    for i in range(1, lines):
        end = breaks[i + 1] if i + 1 < lines else np.inf
        cols.append(np.clip(np.minimum(te, end) - breaks[i], 0, None))
    return np.stack(cols, axis=-1)


def _solve(
    t: np.ndarray, theta: np.ndarray, points: np.ndarray, lines: int, stops: bool, rest_first: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cost, coefficients and θ0 of many breakpoint sets ``points`` [candidate, k]
    (times scaled to the record, so the columns are O(1)); infinite cost for a set that
    leaves a piece too few samples. θ0 is the mean of the samples before the onset for a
    record that starts at rest, a fitted constant for one moving from its first sample."""
    edges = np.searchsorted(t, points)
    counts = np.diff(np.column_stack([np.zeros(len(points), int), edges, np.full(len(points), len(t))]), axis=1)
    usable = (counts[:, 0] >= MIN_REST if rest_first else counts[:, 0] == 0) & np.all(
        counts[:, 1:] >= MIN_PER_PIECE, axis=1
    )
    costs = np.full(len(points), np.inf)
    coefficients = np.zeros((len(points), 3 + lines))
    prefix = np.concatenate([[0.0], np.cumsum(theta)])
    rests = prefix[edges[:, 0]] / np.maximum(edges[:, 0], 1)
    for chunk in np.array_split(np.flatnonzero(usable), max(1, int(usable.sum()) // 1500 + 1)):
        if not len(chunk):
            continue
        a = _columns(t, points[chunk], lines, stops)
        if rest_first:
            b = theta[None, :] - rests[chunk, None]
        else:
            a = np.concatenate([np.ones((*a.shape[:2], 1)), a], axis=-1)
            b = np.broadcast_to(theta, (len(chunk), len(theta)))
        # Columns scaled to unit norm before the normal equations: a short quartic's τ⁴ is
        # 1e-4 of the constant θ0's column, and an unscaled ridge would bias it.
        norms = np.sqrt(np.einsum("csi,csi->ci", a, a))
        norms[norms == 0] = 1.0
        a_unit = a / norms[:, None, :]
        normal = np.einsum("csi,csj->cij", a_unit, a_unit) + 1e-12 * np.eye(a.shape[-1])
        x = np.linalg.solve(normal, np.einsum("csi,cs->ci", a_unit, b)[..., None])[..., 0] / norms
        r = np.einsum("csi,ci->cs", a, x) - b
        costs[chunk] = np.sum(r**2, axis=1)
        if rest_first:
            coefficients[chunk] = x
        else:
            rests[chunk], coefficients[chunk] = x[:, 0], x[:, 1:]
    return costs, coefficients, rests


def _guided(t: np.ndarray, theta: np.ndarray, lines: int, stops: bool, rest_first: bool) -> np.ndarray:
    # Candidates placed by the data: the onset between the start of the record and where θ
    # first leaves its rest band (a quartic start is flat, so the onset precedes that),
    # the stop where θ last leaves its final value; the breaks on a fine grid between.
    # A grid over the whole record is too coarse for a stop that must sit within a sample.
    sigma = max(difference_noise([theta]), 1e-12)
    moved = np.flatnonzero(np.abs(theta - np.median(theta[:MIN_REST])) > 6 * sigma)
    departure = t[moved[0]] if len(moved) else t[-1]
    settled = np.flatnonzero(np.abs(theta - np.median(theta[-MIN_REST:])) > 6 * sigma)
    arrival = t[min(settled[-1] + 1, len(t) - 1)] if len(settled) else t[-1]
    onsets = np.linspace(t[0], departure, 8)[1:] if rest_first else [t[0]]
    step = np.median(np.diff(t))
    ends = arrival + step * np.arange(-2, 3) if stops else [t[-1]]
    out = []
    for t0 in onsets:
        for end in ends:
            inner = np.linspace(t0, end, 42)[1:-1]
            for breaks in itertools.combinations(inner, lines):
                out.append([t0, *breaks, *([end] if stops else [])])
    return np.array(out).reshape(-1, 1 + lines + (1 if stops else 0))


def _search(
    t: np.ndarray, theta: np.ndarray, lines: int, stops: bool, rest_first: bool
) -> tuple[float, np.ndarray, np.ndarray, float]:
    """Cost, breakpoints, coefficients and θ0 of the best breakpoint set: a grid over the
    record, then coordinate scans around the best few (distinct) starts. A record moving
    from its first sample has its onset there (an onset before the record reads the same
    quartic: θ0 and a1 take up the difference), so only the later breakpoints are searched.

    Not :mod:`scipy.optimize`: the cost steps wherever a breakpoint crosses a sample
    (the pieces' sample counts change), so ``minimize``'s simplex and gradient methods
    stall on its flat steps; ``brute`` asks for one breakpoint set per call where
    :func:`_solve` solves some thousand in one batch, and ``differential_evolution``
    (even vectorised) is a stochastic search whose result depends on its seed, where this
    one is deterministic.
    """
    k = 1 + lines + (1 if stops else 0)
    first = 0 if rest_first else 1  # the first breakpoint searched (the onset, or the first break)
    grid = np.linspace(t[0], t[-1], GRID)
    cells = np.array(list(itertools.combinations(grid[1:-1], k - first)))
    if not rest_first:
        cells = np.column_stack([np.full(len(cells), t[0]), cells])
    points = np.vstack([cells, _guided(t, theta, lines, stops, rest_first)])
    costs, _, _ = _solve(t, theta, points, lines, stops, rest_first)
    if not np.isfinite(costs).any():
        return math.inf, np.zeros(k), np.zeros(3 + lines), 0.0
    best_cost, best_point = math.inf, None
    for start in np.argsort(costs)[:STARTS]:
        if not np.isfinite(costs[start]):
            break
        point, cost = points[start].copy(), costs[start]
        span = (t[-1] - t[0]) / (GRID - 1)
        for _ in range(REFINE_ROUNDS):
            for i in range(first, k):
                trial = np.repeat(point[None], 25, axis=0)
                trial[:, i] = np.linspace(point[i] - span, point[i] + span, 25)
                trial = trial[
                    np.all(np.diff(trial, axis=1) > 0, axis=1) & (trial[:, first] > t[0]) & (trial[:, -1] < t[-1])
                ]
                c, _, _ = _solve(t, theta, trial, lines, stops, rest_first)
                j = int(np.argmin(c))
                if c[j] < cost:
                    point, cost = trial[j], c[j]
            span /= 4
        if cost < best_cost:
            best_cost, best_point = cost, point
    c, x, r = _solve(t, theta, best_point[None], lines, stops, rest_first)
    return float(c[0]), best_point, x[0], float(r[0])


def fit_clamp_motion(t: np.ndarray, theta: np.ndarray, forms: tuple[str, ...] = tuple(FORMS)) -> ClampMotionFit:
    """Least-squares fit of each of ``forms`` (names in :data:`FORMS`, all by default) to
    an encoder series (s, rad), the one with the lowest BIC returned with its status (see
    the module docstring)."""
    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    needed = MIN_REST + 3 * MIN_PER_PIECE
    if len(t) < needed:
        raise ArgumentError(
            "t", f"{len(t)} samples are too few for rest, a quartic, a line and a stop; give at least {needed}"
        )
    if np.ptp(theta) <= 0:
        raise ArgumentError("theta", "the angle never changes: there is no clamp motion to fit")
    n = len(t)
    origin, scale = t[0], t[-1] - t[0]
    unit_t = (t - origin) / scale  # the search works on the record scaled to [0, 1]
    found = {}
    unknown = [form for form in forms if form not in FORMS]
    if unknown or not forms:
        raise ArgumentError(
            "forms",
            f"{unknown[0] if unknown else 'none'!r} is not a clamp-motion form; the forms are " + ", ".join(FORMS),
        )
    for form in forms:
        lines, stops, rest_first = FORMS[form]
        cost, point, x, rest = _search(unit_t, theta, lines, stops, rest_first)
        point = origin + point * scale
        x = x / scale ** np.array([1, 2, 3, 4, *[1] * (lines - 1)])
        if not math.isfinite(cost):
            continue
        # Every form is judged on every sample, and counts what it takes from the data: θ0
        # (the rest's mean, or fitted), the linear coefficients and the breakpoints it
        # searched (a moving record's onset is the first sample, not searched).
        k = 1 + len(x) + len(point) - (0 if rest_first else 1)
        bic = n * math.log(max(cost, 1e-300) / n) + k * math.log(n)
        found[form] = (bic, cost, point, x, rest, lines, stops)
    if not found:
        raise ArgumentError(
            "theta", f"no form fits: every candidate leaves a piece with fewer than {MIN_PER_PIECE} samples"
        )
    form = min(found, key=lambda f: found[f][0])
    bic, cost, point, x, rest, lines, stops = found[form]
    t0, breaks = float(point[0]), tuple(float(b) for b in point[1 : 1 + lines])
    stop = float(point[1 + lines]) if stops else None
    speeds = (float(sum(k * x[k - 1] * (breaks[0] - t0) ** (k - 1) for k in range(1, 5))), *map(float, x[4:]))
    # The 4th differences of the whole record, not the smaller of that and the scatter at
    # rest: a minimum of two estimates is biased low, and 20 samples at rest scatter by
    # ±16 % (one seed in 12 of issue 12's record read 0.58 σ, its right fit 1.6× "poor").
    # The median of the differences ignores the few samples where θ changes abruptly.
    noise = difference_noise([theta])
    source = "the encoder's 4th differences"
    rms = math.sqrt(cost / n)
    problems = []
    ratio = poor_fit_ratio(rms, noise)
    if ratio is not None:
        problems.append(
            f"the RMS {rms:.3g} rad is {ratio:.1f}× the encoder's noise {noise:.2g} rad "
            f"({source}): no form of rest, quartic, lines and stop describes this encoder"
        )
    return ClampMotionFit(
        form,
        t0,
        breaks,
        stop,
        rest,
        tuple(float(v) for v in x[:4]),
        speeds,
        rms,
        noise,
        source,
        n,
        bic,
        "poor_fit" if problems else "converged",
        problems,
        {f: math.sqrt(v[1] / n) for f, v in found.items()},
        float(t[-1]),
    )


def scene_with_clamp_motion(raw_scene: dict, fit: ClampMotionFit, until_s: float | None = None) -> dict:
    """A copy of raw scene data whose clamp follows ``fit`` (motion = "piecewise"); a
    motion still going at the end of the record continues to ``until_s`` (the scene's
    ``run.duration_s``). The scene's t = 0 is the motion's start, on the record's clock: a
    motion that starts after the scene's record ends, or ends before its t = 0, is an
    ArgumentError naming the record's times (a late clock, or times not in seconds),
    never a scene whose clamp does not move."""
    if until_s is not None and fit.onset_s >= until_s:
        raise ArgumentError(
            "t",
            f"the clamp's motion starts at {fit.onset_s:.4g} s on the record's clock, after the scene's record "
            f"ends at {until_s:g} s (run.duration_s), so its clamp would never move: the scene's t = 0 is the "
            "start of the motion; shift the record's times (its clock is late), or state their unit in the "
            "header (t_ms) if they are not seconds",
        )
    if fit.stop_s is not None and fit.stop_s <= 0:
        raise ArgumentError(
            "t",
            f"the clamp's motion ends at {fit.stop_s:.4g} s on the record's clock, before the scene's t = 0 (the "
            "start of the motion), so the clamp would stand turned while the strip starts from its hanging "
            "rest shape: shift the record's times (its clock is early)",
        )
    data = copy.deepcopy(raw_scene)
    clamp = data.setdefault("clamp", {})
    clamp["motion"] = "piecewise"
    clamp["segments"] = fit.segments(until_s)
    for key in ("table_t_s", "table_theta_rad"):
        clamp.pop(key, None)
    return data


def _parameters(fit: ClampMotionFit) -> tuple[list[str], list[str], np.ndarray]:
    # The fitted parameters as one vector: θ0, the searched breakpoints (a moving record's
    # onset is its first sample, not fitted), a1…a4 and the later lines' speeds.
    times = [*([] if fit.moving_at_start else ["onset"]), *[f"break {i + 1}" for i in range(len(fit.breaks_s))]]
    times += [] if fit.stop_s is None else ["stop"]
    names = [
        "θ0",
        *times,
        "a1",
        "a2",
        "a3",
        "a4",
        *[f"ω{i + 2} (line {i + 2}'s speed)" for i in range(len(fit.speeds_rad_per_s) - 1)],
    ]
    units = ["rad", *["s"] * len(times), *[f"rad/s^{k}" if k > 1 else "rad/s" for k in range(1, 5)]]
    units += ["rad/s"] * (len(fit.speeds_rad_per_s) - 1)
    point = [fit.onset_s, *fit.breaks_s, *(() if fit.stop_s is None else (fit.stop_s,))]
    values = [fit.rest_rad, *point[1 if fit.moving_at_start else 0 :], *fit.quartic_si, *fit.speeds_rad_per_s[1:]]
    return names, units, np.array(values)


def _model(fit: ClampMotionFit, p: np.ndarray, t: np.ndarray) -> np.ndarray:
    # θ(t) at the parameter vector p of :func:`_parameters`
    n_times = len(fit.breakpoints_s) - (1 if fit.moving_at_start else 0)
    times = p[1 : 1 + n_times]
    point = (fit.onset_s, *times) if fit.moving_at_start else tuple(times)
    lines = len(fit.breaks_s)
    stop = point[1 + lines] if fit.stop_s is not None else None
    return p[0] + _shape(t, point[0], tuple(point[1 : 1 + lines]), stop, p[1 + n_times :])


def _first_speed(fit: ClampMotionFit, p: np.ndarray) -> float:
    # ω1, the quartic's slope at its end (the first line continues it), at p
    n_times = len(fit.breakpoints_s) - (1 if fit.moving_at_start else 0)
    onset = fit.onset_s if fit.moving_at_start else p[1]
    length = p[2 - (1 if fit.moving_at_start else 0)] - onset
    a = p[1 + n_times : 5 + n_times]
    return float(sum(k * a[k - 1] * length ** (k - 1) for k in range(1, 5)))


def _central(f: Callable[[np.ndarray], np.ndarray], p: np.ndarray, steps: list[float]) -> np.ndarray:
    # ∂f/∂p_i by central differences, one column (last axis) per parameter
    columns = []
    for i, step in enumerate(steps):
        delta = np.zeros_like(p)
        delta[i] = step
        columns.append((f(p + delta) - f(p - delta)) / (2 * step))
    return np.stack(columns, axis=-1)


def parameter_uncertainties(fit: ClampMotionFit, t: np.ndarray, theta: np.ndarray) -> list[FittedValue]:
    """Every value :func:`fit_clamp_motion` reports for encoder series ``t``, ``theta`` (s,
    rad), with its 1σ and whether it is determined (see the module docstring).

    The covariance is s² (JᵀJ)⁻¹ (:func:`~warpcloth.calibrate.motion_fit.lm.covariance`)
    with J the model's Jacobian in every parameter, the breakpoints included (θ(t) is
    continuous in them: central differences a thousandth of a sample apart), and s² the
    residual variance; the first line's speed ω1, a function of the quartic, by
    propagation. A singular Jacobian leaves every value not determined."""
    t = np.asarray(t, dtype=float)
    names, units, p = _parameters(fit)
    # a thousandth of a sample for a time; the model is linear in the others
    sample = float(np.median(np.diff(t)))
    steps = [1e-3 * sample if unit == "s" else max(abs(v), 1.0) * 1e-6 for unit, v in zip(units, p, strict=True)]
    jac = _central(lambda q: _model(fit, q, t), p, steps)
    residual = _model(fit, p, t) - np.asarray(theta, dtype=float)
    # unit columns: a4's column is 1e-6 of θ0's, and the normal matrix would lose it
    norms = np.linalg.norm(jac, axis=0)
    norms[norms == 0] = 1.0
    cov = covariance(jac / norms, residual) / np.outer(norms, norms)
    gradient = _central(lambda q: np.array(_first_speed(fit, q)), p, steps)  # ω1's, for its σ
    # a time's 0 is the record's clock: its σ is judged against the pieces it bounds
    pieces = np.diff([t[0], *fit.breakpoints_s, t[-1]])  # the rest (if any), quartic, lines, stop
    scales = {}
    for i, unit in enumerate(units):
        if unit == "s":
            k = fit.breakpoints_s.index(p[i])
            shortest = float(min(pieces[k], pieces[k + 1]))
            scales[i] = (shortest, f"more than a third of the shortest piece it bounds, {shortest:.2g} s")
    omega = from_sigma(
        "ω1 (line 1's speed, the quartic's at its end)",
        fit.speeds_rad_per_s[0],
        math.sqrt(max(float(gradient @ cov @ gradient), 0.0)),
        "rad/s",
    )
    return [*judge(names, units, p, cov, scales), omega]
