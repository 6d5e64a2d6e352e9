"""What advances a batch of strips: one solver class per integrator, each owning its
time step and divergence limit, advancing every strip through a chunk of output samples
in one kernel launch (docs/model.md §9, §11).

Adding an integrator: a node update in ``kernels/integrators.py`` (or a new kernel) and a
solver class here registered in :data:`SOLVERS`.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import warp as wp

from warpcloth.kernels import (
    STATUS_BUDGET,
    STATUS_OK,
    build_strip,
)

from .builder import Grip
from .control import Control
from .divergence import BUDGET_TOLERANCE, QUANTITY, Divergence, phase_at
from .material import MaterialSI
from .model import Model
from .recorder import OutputChunk, Recorder
from .stability import transverse_step_limit
from .state import State

STRIPS_PER_THREAD = 8
"""A CPU launch is split among threads only into ranges of at least this many strips."""


def launch_over_threads(
    kernel: object, n_bodies: int, inputs: list, device: object, threads: int, per_thread: int
) -> None:
    """Launch ``kernel`` over ``n_bodies`` (strips, sheets) whose last input is the first
    body's index: on a CPU as ``threads`` launches of contiguous ranges of at least
    ``per_thread`` bodies, each from its own thread (Warp runs a CPU launch on one thread
    and releases the GIL), else one launch. Every body's arithmetic is the same either way."""
    parts = max(1, min(threads, n_bodies // per_thread)) if device.is_cpu else 1
    bounds = np.linspace(0, n_bodies, parts + 1).round().astype(int)

    def launch(part: int) -> None:
        wp.launch(kernel, dim=int(bounds[part + 1] - bounds[part]), device=device, inputs=[*inputs, int(bounds[part])])

    if parts == 1:
        launch(0)
        return
    with ThreadPoolExecutor(parts) as pool:
        list(pool.map(launch, range(parts)))


@dataclass(frozen=True)
class StepBound:
    """The longest step a scheme runs stably, the mode that sets it and whether the bound
    is exact (the stretching limit) or a linearised estimate (explicit bending)."""

    seconds: float
    mode: str
    exact: bool


class Solver(Protocol):
    """What the runner needs of a solver: its time step, where t = 0 falls, one launch
    that advances every strip through a chunk of outputs, and a divergence report."""

    dt: float

    def release_step(self, control: Control) -> int:
        """Step index of t = 0 under ``control``."""

    def advance(self, state: State, control: Control, recorder: Recorder, chunk: OutputChunk, threads: int = 1) -> None:
        """Advance every healthy strip to each output step of ``chunk``, recording its probes
        and frames there, on up to ``threads`` CPU threads."""

    def divergence_report(self, state: State, control: Control, strip: int) -> Divergence | None:
        """Where and how ``strip`` diverged, or None while it is healthy."""


class FusedStripSolver:
    """The base of the solvers: each launch of the fused strip kernel (kernels/strip.py)
    built for :attr:`scheme` advances every strip of the batch through many substeps of
    fixed ``dt``. A subclass names its scheme (the node update, and whether stretching is
    implicit) and its stability bound.

    ``divergence_strain``: a strip whose tensile strain leaves ± this (NaN included)
    stops and is reported, as is one that folds onto itself or whose energy is not finite.
    """

    scheme = ""
    label = ""
    advice = ""

    def __init__(self, model: Model, dt: float, divergence_strain: float = 0.25) -> None:
        if not self.scheme:
            raise TypeError(
                "FusedStripSolver is the base of the Euler solvers; use one of "
                f"{', '.join(c.__name__ for c in SOLVERS.values())}"
            )
        self.model = model
        self.dt = dt
        self.divergence_strain = divergence_strain
        self.kernels = build_strip(model.scalar, self.scheme, model.terms)

    @staticmethod
    def step_limit(material: MaterialSI, spacing: float, free_nodes: int) -> float | None:
        """The dt (s) beyond which this scheme is unstable for ``material`` on a chain of
        ``free_nodes`` nodes below the clamp at segment length ``spacing`` (m), or None
        where no such bound is known."""
        return None

    @classmethod
    def stable_step(
        cls,
        material: MaterialSI,
        spacing: float,
        free_nodes: int,
        edge_hinge_length: float,
        gravity: float,
        grip: Grip | None = None,
    ) -> StepBound | None:
        """The longest step this scheme runs stably on the chain :meth:`step_limit`
        describes (the clamp-edge hinge bending ``edge_hinge_length``, under ``gravity``,
        with the clamp's ``grip``),
        or None where no bound is known. Explicit bending enters as the straight hanging
        chain's stiffest transverse mode (:func:`~warpcloth.sim.stability.transverse_step_limit`)."""
        return None

    def step_of(self, time: float) -> int:
        """The step count nearest ``time`` seconds."""
        return round(time / self.dt)

    def release_step(self, control: Control) -> int:
        """Step index of t = 0 under ``control``."""
        return self.step_of(control.release_time)

    def _stepping(self, control: Control) -> object:
        s = self.kernels.Stepping()
        s.dt = self.model.scalar(self.dt)
        s.max_strain = self.model.scalar(self.divergence_strain)
        s.release_step = self.release_step(control)
        s.move_steps = max(1, self.step_of(control.move_time))
        return s

    def advance(self, state: State, control: Control, recorder: Recorder, chunk: OutputChunk, threads: int = 1) -> None:
        """Advance every healthy strip to each output step of ``chunk``, recording there
        (:class:`~warpcloth.sim.recorder.OutputChunk`): one launch, or on a CPU one launch
        per thread over contiguous ranges of strips (Warp runs a CPU launch on one thread and
        releases the GIL, so ``threads`` launches fill that many cores); every strip's
        arithmetic is the same either way, bit for bit. Strips that diverge stop and report
        through ``state.struct.status``.
        """
        model = self.model
        steps = wp.array(np.asarray(chunk.output_steps, dtype=np.int32), dtype=int, device=model.device)
        inputs = [
            model.struct,
            control.struct,
            self._stepping(control),
            state.struct,
            recorder.settings(self.kernels.ProbeSettings, model.scalar),
            steps,
            int(chunk.first_output),
            int(chunk.first_frame),
            chunk.probes,
            chunk.frames,
        ]
        # at least STRIPS_PER_THREAD strips per thread: a small batch gains nothing from
        # splitting and, measured in the test suite, can lose (2-strip to 8-strip batches
        # ran 20 % slower on 2 threads there)
        launch_over_threads(self.kernels.advance, model.n_strips, inputs, model.device, threads, STRIPS_PER_THREAD)

    def divergence_report(self, state: State, control: Control, strip: int) -> Divergence | None:
        """Where and how ``strip`` diverged, or None while it is healthy."""
        code = int(state.struct.status.numpy()[strip])
        if code == STATUS_OK:
            return None
        step = int(state.struct.status_step.numpy()[strip])
        time_s = (step - self.release_step(control)) * self.dt
        return Divergence(
            strip=strip,
            code=code,
            step=step,
            time_s=time_s,
            phase=phase_at(time_s, control),
            quantity=QUANTITY[code],
            where=int(state.struct.status_index.numpy()[strip]),
            value=float(state.struct.status_value.numpy()[strip]),
            limit=BUDGET_TOLERANCE if code == STATUS_BUDGET else self.divergence_strain,
            scheme=self.scheme,
            advice=self.advice,
            precision=self.model.precision,
            dt_s=self.dt,
        )


class SemiImplicitEulerSolver(FusedStripSolver):
    """Symplectic (semi-implicit) Euler: velocities first, positions with the new velocity."""

    scheme = "semi_implicit"
    label = "symplectic Euler"

    @staticmethod
    def step_limit(material: MaterialSI, spacing: float, free_nodes: int) -> float | None:
        """h·√(ρ_A/a1) / cos(π/4N): symplectic Euler is stable while ω_max·dt < 2, and the
        stiffest mode of the unstrained chain (N free nodes of mass m = ρ_A·W·h, the last
        m/2, the clamp edge fixed, springs k = a1·W/h) has ω_max = 2√(k/m)·cos(π/4N)
        (modes 2√(k/m)·sin((2j − 1)π/4N), j = 1…N). tests/test_stability.py runs 0.98 and
        1.02 of it at N = 2 and 20. Strain (a2..a4 > 0) and damping only lower the limit;
        the hold (free end fixed) raises it. None for a law with no initial stiffness."""
        a1 = material.tensile[0]
        if a1 <= 0:
            return None
        return spacing * float(np.sqrt(material.density / a1)) / float(np.cos(np.pi / (4 * free_nodes)))

    @classmethod
    def stable_step(
        cls,
        material: MaterialSI,
        spacing: float,
        free_nodes: int,
        edge_hinge_length: float,
        gravity: float,
        grip: Grip | None = None,
    ) -> StepBound | None:
        """The smaller of the exact stretching limit and the transverse (bending) estimate."""
        stretching = cls.step_limit(material, spacing, free_nodes)
        bending = transverse_step_limit(material, spacing, free_nodes, edge_hinge_length, gravity, grip)
        if stretching is not None and stretching <= bending:
            return StepBound(stretching, "stretching", exact=True)
        return StepBound(bending, "bending", exact=False)


class ForwardEulerSolver(FusedStripSolver):
    """Forward Euler, the paper's eqs. 5-6; it amplifies every undamped oscillation."""

    scheme = "forward"
    label = "paper eqs. 5–6"
    advice = (
        " or integrator.scheme = semi_implicit with a dt below its stretching limit (forward Euler"
        " amplifies every undamped oscillation, docs/model.md §9)"
    )


class ImexSolver(FusedStripSolver):
    """Symplectic Euler with the segments' axial stretching implicit (linearised backward
    Euler, one tridiagonal solve per strip and step; kernels/implicit_stretching.py): the
    stretching mode no longer limits dt, bending and the rest stay explicit."""

    scheme = "imex"
    label = "stretching implicit, the rest symplectic Euler"
    advice = " (with imex, explicit bending limits dt: ∝ h², docs/model.md §9.5)"

    @classmethod
    def stable_step(
        cls,
        material: MaterialSI,
        spacing: float,
        free_nodes: int,
        edge_hinge_length: float,
        gravity: float,
        grip: Grip | None = None,
    ) -> StepBound | None:
        """The transverse (bending) estimate: stretching is implicit."""
        return StepBound(
            transverse_step_limit(material, spacing, free_nodes, edge_hinge_length, gravity, grip),
            "bending",
            exact=False,
        )


SOLVERS: dict[str, type[FusedStripSolver]] = {
    SemiImplicitEulerSolver.scheme: SemiImplicitEulerSolver,
    ForwardEulerSolver.scheme: ForwardEulerSolver,
    ImexSolver.scheme: ImexSolver,
}
"""Solver class of each ``integrator.scheme``."""
