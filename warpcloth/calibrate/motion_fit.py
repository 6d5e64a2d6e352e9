"""Fitting free scene parameters to a measured motion with batched runs.

The paper tuned viscous damping and the rotation centre by hand until simulation matched
its vacuum experiments; this does the same by least squares. The discrepancy is the RMS
over time of simulated minus measured (the laser-line displacement, or tracked marker
positions), optionally after shifting the measured clock by a fitted start-time offset.

Search, every step one batched launch of the strip kernel:

1. **Space filling.** A seeded Latin hypercube over the bounds (``space_filling``
   variants in one batch; the sampler of a sweep's random block,
   :func:`warpcloth.scene.sampling.latin_hypercube`); the best variant starts the local
   search.
2. **Speculative Levenberg–Marquardt.** Each iteration launches one batch holding the
   proposed step from the current Jacobian, a central-difference stencil around that
   proposal (so if it is accepted its Jacobian comes with it), and two more cautious
   steps (10× and 100× the damping) in case it is not. The start-time offset is a
   parameter too, but its Jacobian column comes from re-sampling the same runs, so it
   costs no variants. Not :func:`scipy.optimize.least_squares`: it asks for one residual
   vector (or one Jacobian) per call, each a launch of its own, where one launch here
   holds the step, its Jacobian's stencil and two fallback steps.

The uncertainty is the Gauss–Newton covariance s²(JᵀJ)⁻¹ at the optimum with s² the
residual variance. It assumes independent residuals; measured residuals are usually
correlated in time, so read it as a lower bound (the profile of the cost along each
parameter, in ``history``, shows the actual valley).

Every fit ends with a :data:`STATUSES` verdict that cannot read as success when it is
not: ``failed`` (the best run does not reproduce the measured quantity everywhere, or the
search stopped at its iteration limit), ``at_bound`` (a parameter within 0.1 % of the
range of a bound: the optimum lies beyond, the value is not an estimate),
``not_identifiable`` (two parameters correlated beyond 0.95, or a singular Jacobian: the
data do not separate them), ``poor_fit`` (RMS above :data:`~warpcloth.calibrate.noise.POOR_FIT_FACTOR` × the
measurement noise, given or estimated from the data by
:func:`~warpcloth.calibrate.noise.difference_noise`: the rule every fit shares,
:func:`~warpcloth.calibrate.noise.poor_fit_ratio`), ``spacing_limited`` (with
``check_spacing``: the fit at half the spacing would move a parameter by more than its σ,
:func:`spacing_shift`), else ``converged``.
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from warpcloth.errors import ArgumentError, SceneError
from warpcloth.io.measured import LaserTrace, TrackedShapes
from warpcloth.kernels import bending_law
from warpcloth.runs import simulate
from warpcloth.scene import Scene, batch_fields, check_step, field_laws, law_fields, scene_from_dict, set_field
from warpcloth.scene.sampling import latin_hypercube
from warpcloth.scene.step import AUTO, choose_step, stable_step_of
from warpcloth.sim import RunResult
from warpcloth.sim.resources import check_memory

from .bootstrap import block_bootstrap_sigma
from .noise import difference_noise, poor_fit_ratio

MAX_STEP_CORNERS_FREE = 10
"""With ``integrator.dt_s = "auto"`` a fit chooses its one step over the 2^d corners of its
box: at most this many free parameters (1024 scenes, a few seconds)."""

ALIASES = {
    "gamma": "damping.gamma_per_s",
    "D": "material.bending_rigidity_gf_cm2_per_cm",
    "D1": "material.hysteresis_d1_gf_cm_per_cm",
    "alpha": "material.hysteresis_alpha_cm",
    "K0": "material.hysteresis_k0_per_cm",
    "Ms": "material.dahl_moment_gf_cm_per_cm",
    "Ks": "material.dahl_curvature_per_cm",
    "n": "material.dahl_exponent",
    "Mf": "material.friction_moment_gf_cm_per_cm",
    "Kw": "material.friction_width_per_cm",
    "density": "material.density_g_per_cm2",
    "rotation_centre_dx_mm": "clamp.rotation_centre_dx_mm",
    "rotation_centre_dy_mm": "clamp.rotation_centre_dy_mm",
    "hold_x_mm": "release.hold_x_mm",
    "hold_y_mm": "release.hold_y_mm",
    "K_rest": "strip.rest_curvature_per_cm",
    "grip_factor": "clamp.grip_bending_factor",
    "grip_hysteresis": "clamp.grip_hysteresis_factor",
    "grip_length": "clamp.grip_length_mm",
}
"""Short names accepted by ``--free`` (any per-strip numeric field also works by its dotted name);
a bending law's parameters only for a scene whose material uses that law."""

REST_CURVATURE_SPAN = 0.2
"""Default range of ``K_rest``: ± this (1/cm) around the scene's value, a set down to a
radius of 5 cm either way (docs/calibration.md)."""

HYSTERESIS_AMPLITUDES = ("material.hysteresis_d1_gf_cm_per_cm", "material.dahl_moment_gf_cm_per_cm",
                         "material.friction_moment_gf_cm_per_cm")
"""Fitted from 0 (no hysteresis) to 4× the scene's value by default."""

SHIFT = "time_shift_s"
STENCIL_STEP = 2e-3  # central-difference step, as a fraction of each parameter's range
MAX_LAMBDA = 1e8
AT_BOUND = 1e-3  # a parameter this close to a bound, as a fraction of its range, ended on it
MAX_SPACE_FILLING = 10_000
NOT_IDENTIFIABLE_CORRELATION = 0.95
STATUSES = ("converged", "spacing_limited", "at_bound", "poor_fit", "not_identifiable", "failed")
"""Verdicts of a fit, from the only one that is a fit to the worst (see the module docstring)."""


@dataclass(frozen=True)
class FreeParameter:
    """A scene field fitted within [lower, upper]."""

    name: str
    field: str
    lower: float
    upper: float
    initial: float


def _field_value(scene: Scene, name: str) -> float:
    section, key = name.split(".")
    return getattr(getattr(scene, section), key)


def free_parameters(names: str | list[str], base: Scene, bounds: str | None = None) -> list[FreeParameter]:
    """Resolve ``--free`` names (aliases or dotted fields) and ``--bounds name=lo:hi,...``.

    Default bounds: a rotation centre or held position ± 10 mm around the scene's value;
    γ from 0 to 4× the scene's value (at least 2 /s); a hysteresis amplitude (D1, M_s,
    M_f) from 0 to 4×; K_rest ± :data:`REST_CURVATURE_SPAN` around the scene's value; the
    grip length from 0 to 4× the scene's value (at least 4 h, at most the free length);
    any other positive field from ¼× to 4×.
    """
    names = [n.strip() for n in (names.split(",") if isinstance(names, str) else names) if n.strip()]
    if not names:
        raise ArgumentError("names", "name at least one parameter to fit, e.g. gamma,D1")
    given = _parse_bounds(bounds)
    fixed = set(batch_fields())
    out = []
    for name in names:
        dotted = ALIASES.get(name, name)
        if dotted.count(".") != 1 or not hasattr(base, dotted.split(".")[0]) or not hasattr(
                getattr(base, dotted.split(".")[0]), dotted.split(".")[1]):
            raise ArgumentError("names", f"{name!r} is neither a scene field nor one of {', '.join(ALIASES)}")
        value = _field_value(base, dotted)
        if dotted in fixed or isinstance(value, (bool, str, list)):
            raise ArgumentError("names", f"{name} ({dotted}) cannot vary between the strips of one batch or is not "
                              "a number; only per-strip numeric fields can be fitted")
        laws = field_laws(dotted)
        if laws and base.material.bending_law not in laws:
            raise ArgumentError("names", f"{name} ({dotted}) is a parameter of the {' or '.join(laws)} bending law, "
                              "but the scene's "
                              f"material uses {base.material.bending_law} (whose parameters are "
                              f"{', '.join(law_fields(base.material.bending_law))}); set material.bending_law to "
                              "fit it")
        key = name if name in given else dotted if dotted in given else None
        if key is not None:
            lower, upper = given.pop(key)
        elif dotted.endswith("_mm") and ("rotation_centre" in dotted or "hold_" in dotted):
            lower, upper = value - 10.0, value + 10.0
        elif dotted == "damping.gamma_per_s":
            lower, upper = 0.0, max(4 * value, 2.0)
        elif dotted == "strip.rest_curvature_per_cm":
            lower, upper = value - REST_CURVATURE_SPAN, value + REST_CURVATURE_SPAN
        elif dotted == "clamp.grip_length_mm":
            lower, upper = 0.0, min(max(4 * value, 4 * base.strip.spacing_mm), base.strip.free_length_mm)
        elif dotted in HYSTERESIS_AMPLITUDES and value > 0:
            lower, upper = 0.0, 4 * value
        elif value > 0:
            lower, upper = value / 4, value * 4
        else:
            raise ArgumentError("bounds", f"{name} is {value:g} in the scene, so no default range; give "
                              f"--bounds {name}=LOW:HIGH")
        if not lower < upper:
            raise ArgumentError("bounds", f"{name}: lower bound {lower:g} must be below upper bound {upper:g}")
        if any(p.field == dotted for p in out):
            raise ArgumentError("names", f"{name} ({dotted}) is named twice")
        for bound in (lower, upper):  # every point of the box must be a valid scene
            data = base.to_dict()
            set_field(data, dotted, float(bound))
            if base.integrator.dt_chosen_by == AUTO:  # the fit chooses its step over the box
                set_field(data, "integrator.dt_s", AUTO)
            try:
                check_step(scene_from_dict(data))
            except SceneError as exc:
                raise ArgumentError("bounds", f"{name} = {bound:g} is not a valid scene: {exc}") from None
        out.append(FreeParameter(name, dotted, float(lower), float(upper), float(min(max(value, lower), upper))))
    if given:
        raise ArgumentError("bounds", f"{next(iter(given))!r} is not among the --free parameters")
    return out


def _parse_bounds(text: str | None) -> dict[str, tuple[float, float]]:
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        try:
            name, span = item.split("=")
            lo, hi = span.split(":")
            out[name.strip()] = (float(lo), float(hi))
        except ValueError:
            raise ArgumentError("bounds", f"{item.strip()!r} is not name=LOW:HIGH (e.g. gamma=0:2)") from None
    return out


class Objective:
    """Residuals of simulated against measured motion for batches of parameter points.

    A point is ``u`` in the unit box (one coordinate per free parameter) plus, when
    the start time is aligned, the clock offset δ (s): simulated time = measured + δ.
    """

    def __init__(self, base: dict, measurement: LaserTrace | TrackedShapes, free: list[FreeParameter],
                 align_start_s: float = 0.0, device: str | None = None) -> None:
        self.measurement = measurement
        self.free = free
        self.align = float(align_start_s)
        self.device = device
        self.base = copy.deepcopy(base)
        self.base.pop("sweep", None)
        scene = scene_from_dict(copy.deepcopy(self.base))
        span = float(measurement.t[-1] - measurement.t[0])
        if self.align > span:
            raise ArgumentError("align_start_s", f"{self.align:g} s is longer than the measured record ({span:g} s)")
        t_end = float(measurement.t[-1]) + self.align
        if measurement.t[0] + self.align < 0:
            raise ArgumentError("measurement", f"measured times start at {measurement.t[0]:g} s, before the scene's "
                              "t = 0 (release or clamp start) even with the allowed --align-start; shift them")
        set_field(self.base, "run.duration_s", t_end + scene.output_interval)
        if isinstance(measurement, TrackedShapes):
            # Shapes are compared at the probe rate, so the time alignment interpolates
            # between samples 1/600 s apart instead of video frames.
            set_field(self.base, "output.frame_rate_hz", scene.output.frame_rate_hz * scene.output.probes_per_frame)
            set_field(self.base, "output.probes_per_frame", 1)
        self._choose_step()
        self.scene = scene_from_dict(copy.deepcopy(self.base))
        if isinstance(measurement, TrackedShapes):
            free_length = self.scene.strip.free_length_mm * 1e-3
            beyond = measurement.s > free_length * (1 + 1e-9)
            if beyond.any():
                raise ArgumentError("measurement", f"a marker at s = {measurement.s[beyond][0] * 1e3:g} mm lies beyond "
                                  f"the free end ({free_length * 1e3:g} mm below the clamp's lowest point); s is the "
                                  "arc length from the clamp's lowest point, not from the clamp's top")
        self.shift_step = 0.5 * self.scene.output_interval
        self.launches = 0
        self.variants = 0

    def _choose_step(self) -> None:
        # dt_s = "auto": one step for every candidate (a batch shares it), the one that
        # suits every corner of the box: the step bounds move with D, D1, α and density
        if self.base.get("integrator", {}).get("dt_s") != AUTO:
            return
        if len(self.free) > MAX_STEP_CORNERS_FREE:
            raise ArgumentError("free", f"integrator.dt_s = auto checks every corner of the box, 2^{len(self.free)} "
                              f"scenes for {len(self.free)} free parameters (at most {MAX_STEP_CORNERS_FREE}); "
                              "give integrator.dt_s a number")
        corners = [scene_from_dict(self.scene_data(np.array(c, dtype=float)), choose_step=False)
                   for c in itertools.product((0.0, 1.0), repeat=len(self.free))]
        set_field(self.base, "integrator.dt_s", choose_step(corners).dt_s)
        set_field(self.base, "integrator.dt_chosen_by", AUTO)

    def values(self, u: np.ndarray) -> dict[str, float]:
        """Physical values (the scene fields) of a unit-box point."""
        return {p.field: p.lower + float(x) * (p.upper - p.lower) for p, x in zip(self.free, u, strict=False)}

    def scene_data(self, u: np.ndarray) -> dict:
        """Raw scene data of a point (the duration and output rate set for fitting)."""
        data = copy.deepcopy(self.base)
        for name, value in self.values(u).items():
            set_field(data, name, value)
        return data

    def run(self, points: np.ndarray) -> RunResult:
        """Simulate every point (rows) in one batch."""
        scenes = [scene_from_dict(self.scene_data(u)) for u in points]
        self.launches += 1
        self.variants += len(points)
        return simulate(scenes, device=self.device, on_divergence="record",
                        keep_frames=isinstance(self.measurement, TrackedShapes))

    def residuals(self, result: RunResult, j: int, shift: float, penalise: bool = True) -> np.ndarray:
        """Simulated minus measured, SI, for variant j of a result at clock offset δ.

        Where the simulation has no value (the strip misses the laser line, or diverged)
        the residual is a penalty that steers the search away, or NaN with
        ``penalise=False`` (for reporting)."""
        m = self.measurement
        t = m.t + shift
        if isinstance(m, LaserTrace):
            sim = np.interp(t, result.t, result.probe("laser_x", j))
            # Where the strip misses the laser line the signal is undefined: count the
            # whole measured swing as missed there, so the search moves away.
            return np.where(np.isfinite(sim) | (not penalise), sim - m.x, np.ptp(m.x))
        frames = result.frames[:, j]  # [time, node, xy], from the clamp's lowest point like the markers
        nc = self.scene.n_clamped
        arc = m.s / self.scene.spacing + (nc - 1)  # fractional node index of each marker
        node = np.clip(np.floor(arc).astype(int), 0, self.scene.n_nodes - 2)
        w_node = (arc - node)[:, None]
        ft = result.frame_times
        k = np.clip(np.searchsorted(ft, t) - 1, 0, len(ft) - 2)
        w_time = ((t - ft[k]) / (ft[k + 1] - ft[k])).clip(0, 1)[:, None]

        def at(frame: np.ndarray) -> np.ndarray:
            return frame[np.arange(len(node)), node] * (1 - w_node) + frame[np.arange(len(node)), node + 1] * w_node

        sim = at(frames[k]) * (1 - w_time) + at(frames[k + 1]) * w_time
        diff = sim - np.column_stack([m.x, m.y])
        missing = 0.1 if penalise else np.nan  # a diverged strip: 10 cm per coordinate
        return np.where(np.isfinite(diff), diff, missing).ravel()

    def best_shift(self, result: RunResult, j: int) -> float:
        """The clock offset minimising the RMS for variant j (a scan; 0 when not aligning)."""
        if not self.align:
            return 0.0
        shifts = np.linspace(-self.align, self.align, 81)
        costs = [np.mean(self.residuals(result, j, d) ** 2) for d in shifts]
        return float(shifts[int(np.argmin(costs))])

    def jacobian(self, result: RunResult, stencil: list[tuple[int, int, float]], centre: int,
                 shift: float) -> np.ndarray:
        """Columns ∂r/∂u_i from stencil pairs (plus, minus, Δu), and ∂r/∂δ by re-sampling."""
        columns = [(self.residuals(result, plus, shift) - self.residuals(result, minus, shift)) / du
                   for plus, minus, du in stencil]
        if self.align:
            h = self.shift_step
            columns.append((self.residuals(result, centre, shift + h) - self.residuals(result, centre, shift - h))
                           / (2 * h))
        return np.column_stack(columns)


@dataclass
class FitResult:
    """Best parameters, their uncertainty, and how the search went."""

    parameters: dict[str, float]
    sigma: dict[str, float]
    correlation: list[list[float]]
    rms: float
    shift_s: float
    n_residuals: int
    launches: int
    variants: int
    wall_time_s: float
    history: list[dict] = field(default_factory=list)
    converged: bool = False  # the search met its convergence test (not the iteration limit)
    at_bound: list[str] = field(default_factory=list)  # fields within 0.1 % of the range of a bound
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    sigma_bootstrap: dict[str, float] = field(default_factory=dict)  # block bootstrap (``bootstrap`` > 0)
    other_minima: list[dict] = field(default_factory=list)  # separate basins of the space-filling stage, not refined
    bootstrap_block: int = 0  # residuals per bootstrap block
    noise: float = float("nan")  # measurement noise σ the RMS is judged against, SI
    noise_source: str = ""
    status: str = "failed"
    problems: list[str] = field(default_factory=list)  # why the status is not "converged"
    mesh_note: str = ""  # why the values hold at the fitted spacing only (a law whose answers depend on h)
    spacing_check: dict = field(default_factory=dict)  # check_spacing: the fit's move at h/2 (:func:`spacing_shift`)
    dt_s: float = float("nan")  # the step every run of the fit took (one per batch)

    def to_json(self) -> dict:
        """The verdict, each parameter with its 1σ and bounds, and how the search went;
        lengths in mm, names with their units."""
        return {
            "status": self.status,
            "problems": self.problems,
            "mesh_note": self.mesh_note,
            "spacing_check": self.spacing_check,
            "rms_mm": self.rms * 1e3,
            "noise_mm": self.noise * 1e3,
            "noise_source": self.noise_source,
            "parameters": {name: {"value": value, "sigma": self.sigma[name], "at_bound": name in self.at_bound,
                                  "bounds": list(self.bounds.get(name, ()))}
                           | ({"sigma_bootstrap": self.sigma_bootstrap[name]} if self.sigma_bootstrap else {})
                           for name, value in self.parameters.items()},
            "bootstrap_block": self.bootstrap_block,
            "other_minima": self.other_minima,
            "correlation": {"names": list(self.parameters), "matrix": self.correlation},
            "n_residuals": self.n_residuals,
            "search_converged": self.converged,
            "launches": self.launches,
            "variants": self.variants,
            "wall_time_s": self.wall_time_s,
            "history": self.history,
        }

    def judge(self, missing: int) -> None:
        """Set :attr:`status` and :attr:`problems` (``missing``: measured points the best
        run has no value for). Problems are listed in order of precedence and the status is
        the first's: a result that is not an estimate (failed, at_bound) before one whose
        parameters are not separated or whose model does not fit, and the iteration limit
        last (a fit at a bound that also ran out of iterations is reported at_bound)."""
        names = list(self.parameters)
        corr = np.asarray(self.correlation, dtype=float)
        found: list[tuple[str, str]] = []
        if missing or not math.isfinite(self.rms):
            found.append(("failed", f"the best run has no value for {missing} of the {self.n_residuals} measured "
                                    "points (the strip misses the laser line or diverged)" if missing
                          else f"the RMS is {self.rms}"))
        for name in self.at_bound:
            low, high = self.bounds[name]
            found.append(("at_bound", f"{name} = {self.parameters[name]:.6g} ended on a bound ({low:g}:{high:g}); "
                                      "the optimum lies outside, so it is not an estimate: widen --bounds or fix "
                                      "the model"))
        if not all(math.isfinite(v) for v in self.sigma.values()):
            found.append(("not_identifiable", "the Jacobian is singular: some parameter does not change the fit"))
        for i in range(len(names)):
            for j in range(i):
                if abs(corr[i, j]) > NOT_IDENTIFIABLE_CORRELATION:
                    found.append(("not_identifiable", f"{names[i]} and {names[j]} are correlated {corr[i, j]:+.3f}: "
                                                      "the data do not separate them; fix one, or measure what "
                                                      "distinguishes them"))
        ratio = poor_fit_ratio(self.rms, self.noise)
        if ratio is not None:
            found.append(("poor_fit", f"the RMS {self.rms * 1e3:.4g} mm is {ratio:.1f}× the "
                                      f"measurement noise {self.noise * 1e3:.3g} mm ({self.noise_source}): the "
                                      "model with these free parameters does not explain the data"))
        if self.spacing_check.get("note"):
            found.append(("failed", f"--check-spacing could not check the spacing: {self.spacing_check['note']}"))
        moved = self.spacing_check.get("moves", {})
        for name, delta in moved.items():
            if abs(delta) > self.sigma.get(name, math.inf):
                found.append(("spacing_limited", f"refining the strip to strip.spacing_mm = "
                                                 f"{self.spacing_check['spacing_mm']:g} moves {name} by {delta:+.4g} "
                                                 f"({abs(delta) / self.sigma[name]:.1f}σ): the mesh, not the data, "
                                                 "limits it; fit at a finer strip.spacing_mm"))
        if not self.converged:
            found.append(("failed", "the search stopped at its iteration limit before converging "
                                    "(raise --max-iterations)"))
        self.status = found[0][0] if found else "converged"
        self.problems = [message for _, message in found]


def _stencil(point: np.ndarray, d: int) -> tuple[list[np.ndarray], list[tuple[int, int, float]]]:
    # Rows after the centre: +h and −h along each coordinate, kept inside the box.
    rows, pairs = [], []
    for i in range(d):
        plus, minus = point.copy(), point.copy()
        plus[i] = min(point[i] + STENCIL_STEP, 1.0)
        minus[i] = max(point[i] - STENCIL_STEP, 0.0)
        pairs.append((1 + 2 * i, 2 + 2 * i, plus[i] - minus[i]))
        rows += [plus, minus]
    return rows, pairs


def fit_motion(base: dict, measurement: LaserTrace | TrackedShapes, free: list[FreeParameter], *,
               align_start_s: float = 0.0, space_filling: int | None = None, max_iterations: int = 25,
               seed: int = 0, device: str | None = None, progress: bool = True,
               noise: float | None = None, bootstrap: int = 0, check_spacing: bool = False) -> FitResult:
    """Fit ``free`` parameters of raw scene ``base`` to ``measurement`` (see the module doc).

    ``noise`` is the measurement's σ (m) the RMS is judged against; by default it is
    estimated from the measurement (:func:`measurement_noise`). ``bootstrap`` > 0 adds a
    moving-block bootstrap σ from that many resamples (:mod:`.bootstrap`).
    ``check_spacing`` runs the best point once more at half the spacing and reports how
    far that would move each parameter (:func:`spacing_shift`); a move beyond its σ makes
    the status ``spacing_limited``."""
    started = time.perf_counter()
    objective = Objective(base, measurement, free, align_start_s, device)
    d = len(free)
    rng = np.random.default_rng(seed)
    n0 = space_filling or max(16, 8 * d)
    if n0 > MAX_SPACE_FILLING:
        raise ArgumentError("space_filling", f"{n0} variants in one launch is more than {MAX_SPACE_FILLING}; a "
                          "Latin hypercube of a few dozen per parameter finds the basin")
    # the resamples' indices and residuals (8 B each, at most two residuals per measured row),
    # sized before hours of fitting, not after
    check_memory(16 * bootstrap * 2 * len(measurement.t), f"--bootstrap {bootstrap}: the resamples",
                 "ask for fewer (a few thousand give σ to about 1 %)")
    bar = tqdm(total=max_iterations + 1, desc="fit", unit="launch", disable=not progress)
    history: list[dict] = []

    def record(stage: str, u: np.ndarray, shift: float, rms: float) -> None:
        history.append({"launch": objective.launches, "stage": stage, "rms": rms, "shift_s": shift}
                       | objective.values(u))
        bar.set_postfix(rms=f"{rms:.4g}")
        bar.update(1)

    # 1. space filling (the scene's own values join the sample)
    points = np.vstack([[(p.initial - p.lower) / (p.upper - p.lower) for p in free], latin_hypercube(n0, d, rng)])
    result = objective.run(points)
    shifts = [objective.best_shift(result, j) for j in range(len(points))]
    costs = [np.mean(objective.residuals(result, j, s) ** 2) for j, s in enumerate(shifts)]
    best = int(np.argmin(costs))
    u, shift, cost = points[best], shifts[best], costs[best]
    record("space filling", u, shift, math.sqrt(cost))
    other_minima = _other_minima(objective, points, np.array(costs), best)

    # 2. speculative Levenberg–Marquardt on q = (u, δ if aligning)
    q = np.append(u, shift) if objective.align else u.copy()
    jac, residual = None, objective.residuals(result, best, shift)
    lam, converged = 1e-2, False
    for _ in range(max_iterations):
        # The first launch only takes the Jacobian at the start; later ones also try steps.
        proposals = [q] if jac is None else [_lm_step(q, jac, residual, lam * f, objective) for f in (1, 10, 100)]
        stencil_rows, pairs = _stencil(proposals[0][:d], d)
        result = objective.run(np.vstack([proposals[0][:d], *stencil_rows, *[p[:d] for p in proposals[1:]]]))
        rows = [0, *range(1 + 2 * d, 2 * d + len(proposals))]
        trials = [(objective.residuals(result, row, _shift_of(p, d)), row, p) for row, p in zip(rows, proposals,
                                                                                                 strict=True)]
        trial_costs = [float(np.mean(r**2)) for r, _, _ in trials]
        if jac is None or trial_costs[0] < cost:
            improvement = cost - trial_costs[0] if jac is not None else math.inf
            q, cost, residual = proposals[0], trial_costs[0], trials[0][0]
            jac = objective.jacobian(result, pairs, 0, _shift_of(q, d))
            lam = max(lam / 3, 1e-7)
            record("step", q[:d], _shift_of(q, d), math.sqrt(cost))
            if 0 <= improvement <= 1e-4 * cost:
                converged = True
                break
        elif min(trial_costs[1:]) < cost:
            k = 1 + int(np.argmin(trial_costs[1:]))
            q, cost, residual = proposals[k], trial_costs[k], trials[k][0]
            lam *= 10  # the Jacobian stays the one taken nearby; it is refreshed on the next full step
            record("cautious step", q[:d], _shift_of(q, d), math.sqrt(cost))
        else:
            lam *= 100
            record("rejected", q[:d], _shift_of(q, d), math.sqrt(cost))
            if lam > MAX_LAMBDA:
                converged = True
                break
    bar.close()
    u, shift = q[:d], _shift_of(q, d)
    if history[-1]["stage"] != "step":  # the Jacobian must be taken at the reported point
        stencil_rows, pairs = _stencil(u, d)
        result = objective.run(np.vstack([u, *stencil_rows]))
        jac = objective.jacobian(result, pairs, 0, shift)
        residual = objective.residuals(result, 0, shift)
    fit = _summarise(objective, u, shift, jac, residual, history, converged, time.perf_counter() - started)
    if bootstrap > 0:
        ranges = np.array([p.upper - p.lower for p in free] + ([1.0] if objective.align else []))
        sigma, fit.bootstrap_block = block_bootstrap_sigma(jac / ranges, residual, bootstrap, rng)
        fit.sigma_bootstrap = dict(zip(fit.parameters, sigma.tolist(), strict=True))
    # A parameter on its bound is not a fitted value (the optimum lies beyond), and its
    # σ from the local Jacobian means nothing: say so rather than report it as a fit.
    fit.at_bound = [p.field for p, ui in zip(free, u, strict=True) if min(ui, 1.0 - ui) <= AT_BOUND]
    fit.bounds = {p.field: (p.lower, p.upper) for p in free} | ({SHIFT: (-objective.align, objective.align)}
                                                                  if objective.align else {})
    if noise is None:
        fit.noise, fit.noise_source = measurement_noise(measurement), "estimated from the data's 4th differences"
    else:
        fit.noise, fit.noise_source = float(noise), "given"
    fit.other_minima = other_minima
    if check_spacing:
        fit.spacing_check = spacing_shift(objective, u, shift, jac, residual)
    # result row 0 is the reported point (accepted last, or re-run above)
    fit.judge(int(np.isnan(objective.residuals(result, 0, shift, penalise=False)).sum()))
    fit.mesh_note = mesh_note(base)
    fit.dt_s = objective.scene.integrator.dt_s
    return fit


def spacing_shift(objective: Objective, u: np.ndarray, shift: float, jac: np.ndarray,
                  residual: np.ndarray) -> dict:
    """How far the fit at point ``u`` would move at half the strip's spacing: the best point
    run once more at h/2 (dt halved, or chosen again where ``dt_s = "auto"`` chose it) and
    the Gauss–Newton step its residuals ask for, −J⁺(r_{h/2} − r_h) with the fit's own
    Jacobian J (``jac``, unit-box coordinates) and residuals r_h (``residual``). Returns
    ``{"spacing_mm": h/2, "moves": {field: Δ}}`` (Δ in the field's units); a move larger
    than the parameter's σ means the spacing, not the measurement, limits it (docs/
    calibration.md). A law that converges at second order moves a third as far again
    from h/2 to the continuum."""
    fine = copy.deepcopy(objective.base)
    for name, value in objective.values(u).items():
        set_field(fine, name, value)
    scene = scene_from_dict(copy.deepcopy(fine))
    set_field(fine, "strip.spacing_mm", scene.strip.spacing_mm / 2)
    if scene.integrator.dt_chosen_by == AUTO:
        set_field(fine, "integrator.dt_s", AUTO)
        set_field(fine, "integrator.dt_chosen_by", "scene")
    else:  # dt/2, or shorter where the bound at h/2 asks (imex's bending bound shrinks as h²)
        stable = stable_step_of(scene_from_dict(copy.deepcopy(fine), choose_step=False))
        dt = scene.integrator.dt_s / 2
        if stable is not None and dt > stable:
            dt = scene.output_interval / math.ceil(scene.output_interval / stable)
        set_field(fine, "integrator.dt_s", dt)
    refined = Objective(fine, objective.measurement, [], objective.align, objective.device)
    fine_residual = refined.residuals(refined.run(np.zeros((1, 0))), 0, shift, penalise=False)
    names = [p.field for p in objective.free] + ([SHIFT] if objective.align else [])
    if not np.all(np.isfinite(fine_residual)):
        return {"spacing_mm": scene.strip.spacing_mm / 2, "moves": {},
                "note": "the run at half the spacing misses measured points (the laser line, or it diverged)"}
    ranges = np.array([p.upper - p.lower for p in objective.free] + ([1.0] if objective.align else []))
    step = -np.linalg.lstsq(jac, fine_residual - residual, rcond=None)[0] * ranges
    return {"spacing_mm": scene.strip.spacing_mm / 2, "moves": dict(zip(names, step.tolist(), strict=True))}


def mesh_note(base: dict) -> str:
    """Why a fit of the scene ``base`` (as a dict) holds at its spacing only, when its bending
    law's answers depend on the mesh; "" for a law that converges in h."""
    scene = scene_from_dict(base)
    law = scene.material.bending_law
    if bending_law(law).MESH_INDEPENDENT:
        return ""
    return (f"the {law} law's hysteresis depends on the mesh (no return-point memory, docs/model.md §15.6): these "
            f"values hold at strip.spacing_mm = {scene.strip.spacing_mm:g} only, and refining h moves them (its "
            "decrement grows without converging); the masing law takes the same parameters and converges in h")


MINIMA_SEPARATION = 0.25  # unit-box distance beyond which two low points may be different basins
MINIMA_FACTOR = 2.0  # a basin counts if its cost is within this factor of the best one's


def _other_minima(objective: Objective, points: np.ndarray, costs: np.ndarray, best: int) -> list[dict]:
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
            out.append({"rms_mm": math.sqrt(costs[j]) * 1e3, "ridge_rms_mm": math.sqrt(ridge) * 1e3}
                       | objective.values(points[j]))
    return out


def measurement_noise(measurement: LaserTrace | TrackedShapes) -> float:
    """σ of a measurement's noise from the data alone (each marker coordinate a series)."""
    if isinstance(measurement, LaserTrace):
        return difference_noise([measurement.x])
    order = np.lexsort((measurement.frame, measurement.s))
    s = measurement.s[order]
    starts = np.flatnonzero(np.r_[True, np.diff(s) != 0, True])
    pieces = [slice(a, b) for a, b in zip(starts[:-1], starts[1:], strict=True)]
    return difference_noise([measurement.x[order][p] for p in pieces] + [measurement.y[order][p] for p in pieces])


def _shift_of(q: np.ndarray, d: int) -> float:
    return float(q[d]) if len(q) > d else 0.0


def _lm_step(q: np.ndarray, jac: np.ndarray, residual: np.ndarray, lam: float, objective: Objective) -> np.ndarray:
    # (JᵀJ + λ diag JᵀJ) Δ = −Jᵀr, then back into the box (and the allowed clock offsets).
    normal = jac.T @ jac
    scale = np.diag(normal).copy()
    scale[scale <= 0] = 1.0
    point = q + np.linalg.solve(normal + lam * np.diag(scale), -jac.T @ residual)
    d = len(objective.free)
    point[:d] = np.clip(point[:d], 0.0, 1.0)
    if objective.align:
        point[d] = np.clip(point[d], -objective.align, objective.align)
    return point


def _summarise(objective: Objective, u: np.ndarray, shift: float, jac: np.ndarray, residual: np.ndarray,
               history: list[dict], converged: bool, wall: float) -> FitResult:
    n, p = len(residual), jac.shape[1]
    ranges = np.array([f.upper - f.lower for f in objective.free] + ([1.0] if objective.align else []))
    physical = jac / ranges  # ∂r/∂(field value)
    variance = float(residual @ residual) / max(n - p, 1)
    try:
        covariance = variance * np.linalg.inv(physical.T @ physical)
    except np.linalg.LinAlgError:
        covariance = np.full((p, p), np.nan)
    sigma = np.sqrt(np.clip(np.diag(covariance), 0, None))
    correlation = covariance / np.outer(sigma, sigma)
    names = [f.field for f in objective.free] + ([SHIFT] if objective.align else [])
    values = objective.values(u) | ({SHIFT: shift} if objective.align else {})
    return FitResult(values, dict(zip(names, sigma.tolist(), strict=True)), correlation.tolist(),
                     float(np.sqrt(np.mean(residual**2))), shift, n, objective.launches, objective.variants, wall,
                     history, converged)


def write_fit(fit: FitResult, objective_base: dict, measurement: LaserTrace | TrackedShapes, out: str | Path,
              device: str | None = None, inputs: dict | None = None) -> list[Path]:
    """Write the fit: ``best.toml`` (reruns the best fit with the scene's own duration and
    output), ``fit.json`` (with ``inputs``, e.g. the measured file and its checksum, the
    seed, and the provenance), ``history.csv``, ``residuals.csv`` and ``overlay.png``.

    The best fit is rerun and every file prepared under a temporary name before any is
    renamed into place, so a failure leaves no mixture of old and new files."""
    import pandas as pd
    import tomli_w

    from warpcloth.io.atomic import write_files_atomically
    from warpcloth.io.provenance import provenance
    from warpcloth.viz.plots import plot_fit_overlay

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    best = copy.deepcopy(objective_base)
    best.pop("sweep", None)
    for name, value in fit.parameters.items():
        if name != SHIFT:
            set_field(best, name, value)
    if best.get("integrator", {}).get("dt_s") == AUTO and math.isfinite(fit.dt_s):
        set_field(best, "integrator.dt_s", fit.dt_s)  # the box's step, which the RMS was measured at
        set_field(best, "integrator.dt_chosen_by", AUTO)
    scene = scene_from_dict(copy.deepcopy(best))
    objective = Objective(best, measurement, [], abs(fit.shift_s), device)
    result = objective.run(np.zeros((1, 0)))
    residual = objective.residuals(result, 0, fit.shift_s, penalise=False)
    if isinstance(measurement, LaserTrace):
        table = pd.DataFrame({"t_s": measurement.t, "measured_x_mm": measurement.x * 1e3,
                              "simulated_x_mm": (measurement.x + residual) * 1e3, "residual_mm": residual * 1e3})
    else:
        r = residual.reshape(-1, 2)
        table = pd.DataFrame({"frame": measurement.frame, "t_s": measurement.t, "s_mm": measurement.s * 1e3,
                              "residual_x_mm": r[:, 0] * 1e3, "residual_y_mm": r[:, 1] * 1e3})
    return write_files_atomically(out, {
        "best.toml": lambda p: p.write_text(tomli_w.dumps(scene.to_dict())),
        "fit.json": lambda p: p.write_text(json.dumps(fit.to_json() | {"inputs": inputs or {},
                                                                        "provenance": provenance(device)}, indent=1)),
        "history.csv": lambda p: pd.DataFrame(fit.history).to_csv(p, index=False),
        "residuals.csv": lambda p: table.to_csv(p, index=False),
        "overlay.png": lambda p: plot_fit_overlay(result, objective, measurement, fit, p),
    })


@dataclass
class Identifiability:
    """What an experiment (or several together) can determine about the free parameters at a
    point, before any fit: the Gauss–Newton σ and correlation for measurement noise σ_m, and
    the pairs correlated beyond :data:`NOT_IDENTIFIABLE_CORRELATION` (the fit's
    ``not_identifiable`` verdict)."""

    names: list[str]
    sigma: dict[str, float]
    correlation: np.ndarray
    not_identifiable: list[tuple[str, str, float]]

    def table(self) -> str:
        """The correlation matrix as text, with σ and the pairs the data do not separate."""
        width = max(len(n) for n in self.names)
        lines = [" " * width + "  " + " ".join(f"{i:>6d}" for i in range(len(self.names))) + "   σ"]
        for i, name in enumerate(self.names):
            row = " ".join(f"{c:+6.3f}" for c in self.correlation[i])
            lines.append(f"{name:<{width}}  {row}   {self.sigma[name]:.3g}")
        lines += [f"not identifiable: {a} and {b} correlated {c:+.3f}" for a, b, c in self.not_identifiable]
        return "\n".join(lines)


def weighted_jacobian(base: dict, measurement: LaserTrace | TrackedShapes, noise: float, names: str | list[str],
                      bounds: str | None = None, device: str | None = None) -> tuple[list[str], np.ndarray]:
    """The fields of the ``--free`` parameters ``names`` and ∂r/∂(field value) / σ_m of the
    experiment (raw scene ``base``, its ``measurement``, noise σ_m in m) at the scene's own
    values: one batched launch of the central-difference stencil, as the fit takes it."""
    free = free_parameters(names, scene_from_dict(copy.deepcopy(base)), bounds)
    objective = Objective(base, measurement, free, 0.0, device)
    u = np.array([(p.initial - p.lower) / (p.upper - p.lower) for p in free])
    rows, pairs = _stencil(u, len(free))
    result = objective.run(np.vstack([u, *rows]))
    ranges = np.array([p.upper - p.lower for p in free])
    return [p.field for p in free], objective.jacobian(result, pairs, 0, 0.0) / ranges / noise


def identifiability(blocks: list[tuple[list[str], np.ndarray]]) -> Identifiability:
    """σ and correlation of the parameters from experiments' :func:`weighted_jacobian`
    blocks, stacked as one fit of all their residuals would stack them (the same fields in
    each). A correlation beyond :data:`NOT_IDENTIFIABLE_CORRELATION`, or a singular
    Jacobian, is a pair the data do not separate (docs/calibration.md, "What the data
    determine")."""
    fields = blocks[0][0]
    if any(f != fields for f, _ in blocks):
        raise ValueError("every experiment must have the same free parameters, in the same order")
    jac = np.vstack([j for _, j in blocks])
    try:
        covariance = np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        covariance = np.full((len(fields), len(fields)), np.nan)
    sigma = np.sqrt(np.clip(np.diag(covariance), 0, None))
    correlation = covariance / np.outer(sigma, sigma)
    pairs = [(fields[i], fields[j], float(correlation[i, j])) for i in range(len(fields)) for j in range(i)
             if not abs(correlation[i, j]) <= NOT_IDENTIFIABLE_CORRELATION]
    return Identifiability(fields, dict(zip(fields, sigma.tolist(), strict=True)), correlation, pairs)
