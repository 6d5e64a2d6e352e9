"""What a motion fit minimises: the residuals of simulated against measured motion (the
laser-line displacement, or tracked marker positions) for batches of parameter points,
each batch one launch of the strip kernel."""

from __future__ import annotations

import copy
import itertools
import math
from typing import Any

import numpy as np

from warpcloth import bodies
from warpcloth.errors import ArgumentError, ArgumentTypeError
from warpcloth.io.measured import LaserTrace, TrackedShapes
from warpcloth.kernels import bending_law
from warpcloth.runs import simulate
from warpcloth.scene import Scene, scene_from_dict, set_field, strip_scene_from_dict
from warpcloth.scene.step import AUTO, choose_step
from warpcloth.strip import RunResult

from .parameters import FreeParameter

MAX_STEP_CORNERS_FREE = 10
"""With ``integrator.dt_s = "auto"`` a fit chooses its one step over the 2^d corners of its
box: at most this many free parameters (1024 scenes, a few seconds)."""

SHIFT = "time_shift_s"
"""The name of the fitted start-time offset δ (simulated time = measured + δ)."""


class FitObjective:
    """What the search (:mod:`.search`) needs of an objective, for a strip's measurement
    (:class:`Objective`) or a sheet's (:class:`~.sheet.SheetObjective`): the free
    parameters on the unit box, the clock offset, a batch of points run in one launch
    (:meth:`run`), each variant's residuals (:meth:`residuals`) and their Jacobian."""

    measurement: Any
    free: list[FreeParameter]
    align: float
    device: str | None
    base: dict
    scene: Any  # the base scene as the runs see it (a Scene, or a SheetScene)
    shift_step: float
    launches: int
    variants: int

    @property
    def names(self) -> list[str]:
        """The fitted quantities: the free fields, then the clock offset when aligning."""
        return [p.field for p in self.free] + ([SHIFT] if self.align else [])

    @property
    def ranges(self) -> np.ndarray:
        """Each fitted quantity's length of the unit box's side (1 for the clock offset):
        ∂r/∂(field value) is ∂r/∂u divided by it."""
        return np.array([p.upper - p.lower for p in self.free] + ([1.0] if self.align else []))

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """The lower and upper corner of the search's points: the unit box, then the allowed
        clock offsets when aligning."""
        d = len(self.free)
        lower, upper = np.zeros(d), np.ones(d)
        if self.align:
            lower, upper = np.append(lower, -self.align), np.append(upper, self.align)
        return lower, upper

    def shift_of(self, q: np.ndarray) -> float:
        """The clock offset of a search point (0 when not aligning)."""
        d = len(self.free)
        return float(q[d]) if len(q) > d else 0.0

    def values(self, u: np.ndarray) -> dict[str, float]:
        """Physical values (the scene fields) of a unit-box point."""
        return {p.field: p.lower + float(x) * (p.upper - p.lower) for p, x in zip(self.free, u, strict=False)}

    def scene_data(self, u: np.ndarray) -> dict:
        """Raw scene data of a point (the duration and output rate set for fitting)."""
        data = copy.deepcopy(self.base)
        for name, value in self.values(u).items():
            set_field(data, name, value)
        return data

    def _choose_step(self) -> None:
        # dt_s = "auto": one step for every candidate (a batch shares it, and a fit's cost
        # must not jump between launches), the one that suits every corner of the box:
        # the step bounds move with the fitted stiffnesses and density
        if self.base.get("integrator", {}).get("dt_s") != AUTO:
            return
        if len(self.free) > MAX_STEP_CORNERS_FREE:
            raise ArgumentError(
                "free",
                f"integrator.dt_s = auto checks every corner of the box, 2^{len(self.free)} "
                f"scenes for {len(self.free)} free parameters (at most {MAX_STEP_CORNERS_FREE}); "
                "give integrator.dt_s a number",
            )
        corners = [
            self.scene_data(np.array(c, dtype=float)) for c in itertools.product((0.0, 1.0), repeat=len(self.free))
        ]
        set_field(self.base, "integrator.dt_s", self.corner_step(corners))
        set_field(self.base, "integrator.dt_chosen_by", AUTO)

    def corner_step(self, corners: list[dict]) -> float:
        """The step that suits every corner scene (raw data) of the box."""
        raise NotImplementedError

    spacing_fields: tuple[str, ...] = ()
    """The scene fields that set the mesh's spacing (mm), refined together."""

    def scene_of(self, data: dict) -> Any:
        """The scene (checked, ready to run) of raw scene data."""
        raise NotImplementedError

    def mesh_note(self) -> str:
        """Why the fit's values hold at its spacing only (a law whose answers depend on the
        mesh), or "" when every law of the scene converges in h."""
        raise NotImplementedError

    @property
    def dt_s(self) -> float:
        """The step every run of this objective takes (s)."""
        return float(self.scene.integrator.dt_s)

    def spacing_of(self, name: str) -> float:
        """The value (mm) of the spacing field ``name`` in the scene the runs see."""
        section, _, key = name.partition(".")
        return float(getattr(getattr(self.scene, section), key))

    @property
    def spacing_mm(self) -> float:
        """The mesh's spacing (mm; a sheet's along its warp)."""
        return self.spacing_of(self.spacing_fields[0])

    def continuum_order(self) -> float | None:
        """The order in h at which the scene's runs converge (None where a law has no
        continuum limit: its answers depend on the mesh)."""
        raise NotImplementedError

    def refined(self, factor: float) -> FitObjective:
        """The same objective on a mesh ``factor`` × as fine in spacing (``factor`` 0.5
        halves h), its step scaled with it: the fit's step × ``factor``, never above the
        longest step the new spacing allows (where ``dt_s = "auto"`` chose the fit's step:
        auto's choice over the box there; imex's bending bound shrinks as h², and the probe
        interval caps every step), a whole fraction of the probe interval. A fixed step is
        scaled as given: one the new spacing cannot run stably is the scene's refusal."""
        data = copy.deepcopy(self.base)
        for name in self.spacing_fields:
            set_field(data, name, self.spacing_of(name) * factor)
        kind: Any = type(self)  # each objective is made from the same arguments
        dt = self.dt_s * factor
        if self.scene.integrator.dt_chosen_by == AUTO:
            set_field(data, "integrator.dt_s", AUTO)
            set_field(data, "integrator.dt_chosen_by", "scene")
            dt = min(dt, kind(copy.deepcopy(data), self.measurement, self.free, self.align, self.device).dt_s)
        interval = self.scene.output_interval
        set_field(data, "integrator.dt_s", interval / math.ceil(interval / dt * (1 - 1e-12)))
        set_field(data, "integrator.dt_chosen_by", "scene")
        return kind(data, self.measurement, self.free, self.align, self.device)

    def run(self, points: np.ndarray) -> Any:
        """Simulate every point (rows) in one batch."""
        raise NotImplementedError

    def residuals(self, result: Any, j: int, shift: float, penalise: bool = True) -> np.ndarray:
        """Simulated minus measured, SI, for variant j of a result at clock offset δ."""
        raise NotImplementedError

    def residual_groups(self) -> np.ndarray | None:
        """Each residual's group of possibly shared errors (its tracked frame), or None
        where the errors are independent, as a laser's samples are (:func:`~.report.summarise`)."""
        return None

    def best_shift(self, result: Any, j: int) -> float:
        """The clock offset minimising the RMS for variant j (a scan; 0 when not aligning)."""
        if not self.align:
            return 0.0
        shifts = np.linspace(-self.align, self.align, 81)
        costs = [np.mean(self.residuals(result, j, d) ** 2) for d in shifts]
        return float(shifts[int(np.argmin(costs))])

    def jacobian(self, result: Any, stencil: list[tuple[int, int, float]], centre: int, shift: float) -> np.ndarray:
        """Columns ∂r/∂u_i from stencil pairs (plus, minus, Δu), and ∂r/∂δ by re-sampling."""
        columns = [
            (self.residuals(result, plus, shift) - self.residuals(result, minus, shift)) / du
            for plus, minus, du in stencil
        ]
        if self.align:
            h = self.shift_step
            columns.append(
                (self.residuals(result, centre, shift + h) - self.residuals(result, centre, shift - h)) / (2 * h)
            )
        return np.column_stack(columns)


class Objective(FitObjective):
    """Residuals of simulated against measured motion for batches of parameter points.

    A point is ``u`` in the unit box (one coordinate per free parameter) plus, when
    the start time is aligned, the clock offset δ (s): simulated time = measured + δ.
    """

    def __init__(
        self,
        base: dict,
        measurement: LaserTrace | TrackedShapes,
        free: list[FreeParameter],
        align_start_s: float = 0.0,
        device: str | None = None,
    ) -> None:
        if not isinstance(measurement, LaserTrace | TrackedShapes):
            raise ArgumentTypeError(
                "measurement",
                f"a strip scene is fitted to a laser trace or tracked shapes, not a {type(measurement).__name__}",
            )
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
            raise ArgumentError(
                "measurement",
                f"measured times start at {measurement.t[0]:g} s, before the scene's "
                "t = 0 (release or clamp start) even with the allowed --align-start; shift them",
            )
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
                # a whole strip's length times a hundred is a unit, not a clamp, mistaken
                unit = (
                    " (a hundred times the strip or more: millimetres under a header in metres? head the column s_mm)"
                    if measurement.s.max() >= 100 * free_length
                    else ""
                )
                raise ArgumentError(
                    "measurement",
                    f"a marker at s = {measurement.s[beyond][0] * 1e3:g} mm lies beyond "
                    f"the free end ({free_length * 1e3:g} mm below the clamp's lowest point){unit}; s is the "
                    "arc length from the clamp's lowest point, not from the clamp's top",
                )
        self.shift_step = 0.5 * self.scene.output_interval
        self.launches = 0
        self.variants = 0

    spacing_fields = ("strip.spacing_mm",)

    def mesh_note(self) -> str:
        """Why the fit holds at its spacing only (:func:`mesh_note`), or ""."""
        return mesh_note(self.base)

    def scene_of(self, data: dict) -> Scene:
        """The strip scene of raw scene data."""
        return scene_from_dict(data)

    def continuum_order(self) -> float | None:
        """2 (the paper's clamp edge: 1, docs/model.md §5.3); None under a law without
        return-point memory, whose answers do not converge in h (§15.6)."""
        if not bending_law(self.scene.material.bending_law).mesh_independent:
            return None
        return 1.0 if self.scene.clamp.edge_hinge == "paper" else 2.0

    def corner_step(self, corners: list[dict]) -> float:
        """The step that suits every corner scene of the box (the strip's own choice)."""
        return choose_step([strip_scene_from_dict(data, choose_step=False) for data in corners]).dt_s

    def run(self, points: np.ndarray) -> RunResult:
        """Simulate every point (rows) in one batch."""
        scenes = [scene_from_dict(self.scene_data(u)) for u in points]
        self.launches += 1
        self.variants += len(points)
        return simulate(
            scenes, device=self.device, on_divergence="record", keep_frames=isinstance(self.measurement, TrackedShapes)
        )

    def residual_groups(self) -> np.ndarray | None:
        """A tracked shape's residuals (x and y of each point, or a curve's across and along
        it, row by row) grouped by frame, whose errors its points share; a laser's samples
        are independent (None)."""
        m = self.measurement
        return np.repeat(m.frame, 2) if isinstance(m, TrackedShapes) else None

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
        if result.frames is None:
            raise ArgumentError(
                "result", "tracked markers are compared with the run's frames: run it with keep_frames=True"
            )
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
        if m.u_along is not None:
            # a curve's point: across the strip, and along it less its frame's mean: the free
            # end's error, which every arc of the frame carries (u_along_mm), is one unknown per
            # frame; what is left is the points' own, as across (0.002-0.03 mm on the rig)
            w = w_time[:, 0]

            def position(n: np.ndarray) -> np.ndarray:  # a node at the measured time, as sim is
                return frames[k, n] * (1 - w)[:, None] + frames[k + 1, n] * w[:, None]

            tangent = position(node + 1) - position(node)
            tangent /= np.linalg.norm(tangent, axis=1)[:, None]
            across = diff[:, 0] * -tangent[:, 1] + diff[:, 1] * tangent[:, 0]
            along = less_group_mean((diff * tangent).sum(axis=1), m.frame)
            diff = np.column_stack([across, along])
        missing = 0.1 if penalise else np.nan  # a diverged strip: 10 cm per coordinate
        return np.where(np.isfinite(diff), diff, missing).ravel()


def less_group_mean(values: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """``values`` less the mean of their group (over its finite values), scaled by
    √(m/(m − 1)) for a group of m so that independent errors keep their spread; a value
    alone in its group is 0 (nothing is left of it once its mean is taken out)."""
    _, index = np.unique(groups, return_inverse=True)
    finite = np.isfinite(values)
    count = np.bincount(index, finite)
    mean = np.bincount(index, np.where(finite, values, 0.0)) / np.maximum(count, 1)
    scale = np.sqrt(count / np.maximum(count - 1, 1))
    return np.where(count[index] > 1, (values - mean[index]) * scale[index], 0.0)


def mesh_note(base: dict) -> str:
    """Why a fit of the scene ``base`` (as a dict) holds at its spacing only, when its bending
    law's answers depend on the mesh; "" for a law that converges in h."""
    scene = scene_from_dict(base)
    law = scene.material.bending_law
    if bending_law(law).mesh_independent:
        return ""
    return (
        f"the {law} law's hysteresis depends on the mesh (no return-point memory, docs/model.md §15.6): these "
        f"values hold at strip.spacing_mm = {scene.strip.spacing_mm:g} only, and refining h moves them (its "
        "decrement grows without converging); the masing law takes the same parameters and converges in h"
    )


def make_objective(
    base: dict,
    measurement: Any,
    free: list[FreeParameter],
    align_start_s: float = 0.0,
    device: str | None = None,
) -> FitObjective:
    """The objective of raw scene ``base`` (its body's, :mod:`warpcloth.bodies`) against
    ``measurement``: a strip is fitted to a laser trace or tracked shapes, a sheet to its
    tracked markers; a measurement of the other body's kind is refused, naming it."""
    return bodies.of_data(base)("objective", base, measurement, free, align_start_s, device)
