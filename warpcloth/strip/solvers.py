"""What advances a batch of strips: one solver class per integrator, each owning its
time step and divergence limit, advancing every strip through a chunk of output samples
in one kernel launch (docs/model.md §9, §11).

Adding an integrator: a node update in ``kernels/integrators.py`` (or a new kernel) and a
solver class here registered in :data:`SOLVERS`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from warpcloth.core.divergence import BUDGET_TOLERANCE
from warpcloth.core.solver import FusedSolver
from warpcloth.errors import ArgumentTypeError
from warpcloth.kernels import STATUS_BUDGET, build_strip
from warpcloth.kernels.exp_lanes import lane_width

from .builder import Grip
from .control import StripControl
from .divergence import QUANTITY, Divergence, phase_at
from .material import MaterialSI
from .model import StripModel
from .stability import transverse_step_limit
from .state import StripState

STRIPS_PER_THREAD = 8
"""A CPU launch is split among threads only into ranges of at least this many strips: a
small batch gains nothing from splitting and, measured in the test suite, can lose
(2-strip to 8-strip batches ran 20 % slower on 2 threads there)."""


@dataclass(frozen=True)
class StepBound:
    """The longest step a scheme runs stably, the mode that sets it and whether the bound
    is exact (the stretching limit) or a linearised estimate (explicit bending)."""

    seconds: float
    mode: str
    exact: bool


class FusedStripSolver(FusedSolver):
    """The base of the strip's solvers: each launch of the fused strip kernel
    (kernels/strip.py) built for :attr:`scheme` advances every strip of the batch through
    many substeps of fixed ``dt`` (:class:`~warpcloth.core.solver.FusedSolver`). A subclass
    names its scheme (the node update, and whether stretching is implicit) and its
    stability bound.

    ``divergence_strain``: a strip whose tensile strain leaves ± this (NaN included)
    stops and is reported, as is one that folds onto itself or whose energy is not finite.
    """

    scheme = ""
    label = ""
    advice = ""
    bodies_per_thread = STRIPS_PER_THREAD

    def __init__(self, model: StripModel, dt: float, divergence_strain: float = 0.25) -> None:
        if not self.scheme:
            raise ArgumentTypeError(
                "solver",
                "FusedStripSolver is the base of the Euler solvers; use one of "
                f"{', '.join(c.__name__ for c in SOLVERS.values())}",
            )
        super().__init__(model, dt)
        self.divergence_strain = divergence_strain
        lanes = lane_width(model.scalar, model.device.is_cpu)
        self.kernels = build_strip(model.scalar, self.scheme, model.terms, lanes)
        self.kernel = self.kernels.advance

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
        chain's stiffest transverse mode (:func:`~warpcloth.strip.stability.transverse_step_limit`)."""
        return None

    def stepping(self, control: StripControl) -> object:
        """The kernel's Stepping struct: dt, the strain limit, the release and the carry."""
        s = self.kernels.Stepping()
        s.dt = self.model.scalar(self.dt)
        s.max_strain = self.model.scalar(self.divergence_strain)
        s.release_step = self.release_step(control)
        s.move_steps = max(1, self.step_of(control.move_time))
        return s

    def divergence_report(self, state: StripState, control: StripControl, strip: int) -> Divergence | None:
        """Where and how ``strip`` diverged, or None while it is healthy."""
        stopped = self.health(state, strip)
        if stopped is None:
            return None
        code, step, where, value = stopped
        time_s = (step - self.release_step(control)) * self.dt
        return Divergence(
            strip=strip,
            code=code,
            step=step,
            time_s=time_s,
            phase=phase_at(time_s, control),
            quantity=QUANTITY[code],
            where=where,
            value=value,
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


class TrapezoidalImexSolver(ImexSolver):
    """imex with the stretching by the trapezoidal rule (Newmark's average acceleration,
    β = 1/4; kernels/implicit_stretching.py): second order and without the backward
    Euler's damping of the stretching modes, so a hysteretic law without return-point
    memory keeps far less of imex's floor (docs/model.md §9.5.1)."""

    scheme = "imex_trapezoidal"
    label = "stretching implicit by the trapezoidal rule, the rest symplectic Euler"
    advice = " (with imex_trapezoidal, explicit bending limits dt: ∝ h², docs/model.md §9.5)"


SOLVERS: dict[str, type[FusedStripSolver]] = {
    SemiImplicitEulerSolver.scheme: SemiImplicitEulerSolver,
    ForwardEulerSolver.scheme: ForwardEulerSolver,
    ImexSolver.scheme: ImexSolver,
    TrapezoidalImexSolver.scheme: TrapezoidalImexSolver,
}
"""Solver class of each ``integrator.scheme``."""
