"""When a strip has diverged, and what it says: the health codes the kernel sets, the
energy budget the runner checks on the recorded probes, and the typed report of each
stopped strip (docs/model.md §11)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from warpcloth.kernels import (
    PROBE_INDEX,
    STATUS_BUDGET,
    STATUS_FOLDED,
    STATUS_NONFINITE_ENERGY,
    STATUS_STRAIN,
)

if TYPE_CHECKING:
    from .control import Control
    from .model import Model
    from .solvers import Solver
    from .state import State

BUDGET_TOLERANCE = 0.1
"""A strip whose energy budget (docs/model.md §10) has *gained* more than this fraction of
its energy scale since the release has diverged, even if no strain or fold check fired:
an unstable step (imex beyond its bending limit, forward Euler) creates energy, and can
grow a zig-zag or an oscillation long before a segment overstretches. Energy the step
removes is not counted: imex's backward Euler damps the stretching modes by design
(docs/model.md §9.5), which a soft or long strip started unstretched shows as a budget
loss of about its initial strain energy. The scale is the peak kinetic energy up to that
sample, and at least 1e-3 of the strip's weight times its free length, or of D W / L
(the work of bending it through a radian) where that is larger, as without gravity (just
after a release, or for a strip at rest, the kinetic energy is near 0, and rounding is
not). A healthy run's budget
stays within 1e-2 of its peak kinetic energy (imex at its largest stable dt), usually
1e-4. The check reads the recorded samples, so where it fires does not depend on how the
run is cut into launches."""

BUDGET_TERMS = ("kinetic", "gravitational", "tensile", "bending_elastic_work", "hysteresis_work", "damping_work")

QUANTITY = {
    STATUS_STRAIN: "tensile strain",
    STATUS_FOLDED: "hinge chord |e1+e2|/h (the strip folded onto itself)",
    STATUS_NONFINITE_ENERGY: "total energy (not finite)",
    STATUS_BUDGET: (
        "energy budget residual (in units of the peak kinetic energy, at least 1e-3 of the strip's "
        "weight times its free length or of D W / L)"
    ),
}


PHASES = ("move", "hold", "record")
"""Phases of a run: the free end carried to its hold target, held there while the strip
settles, then the record from t = 0 (the release, or the start of a run without one)."""


def phase_at(time_s: float, control: Control) -> str:
    """The phase (:data:`PHASES`) a time after the release (negative before it) falls in."""
    if time_s >= 0:
        return "record"
    return "move" if time_s + control.release_time < control.move_time else "hold"


@dataclass(frozen=True)
class Divergence:
    """Where and how one strip of a batch diverged: what the runner stops it for, the run
    directory records (:meth:`as_dict`) and the user reads (:meth:`describe`)."""

    strip: int  # index in the batch
    code: int  # the health code the kernel set (kernels/status.py)
    step: int  # the step it was set at
    time_s: float  # that step's time after t = 0 (negative before the release)
    phase: str  # PHASES
    quantity: str  # what left its range, in words
    where: int  # the segment of a strain, the hinge node of a fold
    value: float  # the quantity's value
    limit: float  # the range it left
    scheme: str  # the solver's integrator.scheme
    advice: str  # what the solver adds to "try a smaller dt" (its own way out)
    precision: str
    dt_s: float

    def as_dict(self) -> dict:
        """The report as the run directory's meta.json writes it."""
        return dataclasses.asdict(self)

    @property
    def sample_lost(self) -> bool:
        """Whether the probe sample at :attr:`step` is already unusable (an energy that is
        not finite or off budget), so only the samples before it are kept."""
        return self.code in (STATUS_NONFINITE_ENERGY, STATUS_BUDGET)

    def describe(self) -> str:
        """One sentence a user can act on."""
        where = (
            f" at segment {self.where}"
            if self.code == STATUS_STRAIN
            else (f" at hinge node {self.where}" if self.code == STATUS_FOLDED else "")
        )
        limit = {
            STATUS_STRAIN: f", beyond integrator.divergence_strain = {self.limit:g}",
            STATUS_BUDGET: f", above {self.limit:g}: the step is unstable",
        }.get(self.code, "")
        advice = f"try a smaller integrator.dt_s (now {self.dt_s:g} s, e.g. {self.dt_s / 4:g})"
        advice += self.advice
        if self.code == STATUS_BUDGET and self.precision == "float32":
            advice = (
                "float32 rounding feeds energy into the stretching modes over a long run (a smaller dt makes "
                'it worse): use integrator.precision = "float64", or ' + advice
            )
        during = {
            "move": "while its free end was carried to the hold",
            "hold": "during the hold",
            "record": "after t = 0",
        }[self.phase]
        return (
            f"strip {self.strip} diverged {during}, at t = {self.time_s:.6g} s (step {self.step}): "
            f"{self.quantity} = {self.value:.4g}{where}{limit}; {advice}"
        )


class BudgetWatch:
    """Each body's energy budget at the release and its peak kinetic energy so far, to
    stop a body whose budget no longer closes (:data:`BUDGET_TOLERANCE`): a strip's
    (:meth:`for_strips`) or a sheet's, ``floor`` the least energy scale of each."""

    def __init__(self, floor: np.ndarray) -> None:
        self.floor = np.asarray(floor, dtype=float)
        self.reference = np.full(len(self.floor), np.nan)
        self.peak_kinetic = np.zeros(len(self.floor))

    @classmethod
    def for_strips(cls, model: Model) -> BudgetWatch:
        """The watch of a batch of strips: the floor 1e-3 of each strip's weight times its
        free length, or of D W / L where that is larger."""
        free = model.n_nodes - model.n_clamped
        weight = model.node_mass * (free - 0.5) * model.gravity * free * model.spacing
        # without gravity (a set strip curling at rest) the scale is bending's: D W over the
        # free length, the work of bending it through one radian
        bending = model.bending[:, 0] * model.width / (free * model.spacing)
        return cls(1e-3 * np.maximum(weight, bending))

    def first_violation(
        self, total: np.ndarray, kinetic: np.ndarray, usable: np.ndarray
    ) -> dict[int, tuple[int, float]]:
        """``body → (sample index, residual / scale)`` of the first failing sample of each
        body in a chunk of its budget ``total[sample, body]`` and kinetic energy (samples
        from the release on), looking only where ``usable[sample, body]``."""
        kinetic = np.where(usable, kinetic, 0.0)
        self.reference = np.where(np.isnan(self.reference), total[0], self.reference)
        peak = np.maximum(self.peak_kinetic, np.fmax.accumulate(np.nan_to_num(kinetic, nan=0.0), axis=0))
        self.peak_kinetic = peak[-1]
        with np.errstate(invalid="ignore"):
            bad = usable & (total - self.reference > BUDGET_TOLERANCE * np.maximum(peak, self.floor))
        out = {}
        for body in np.flatnonzero(bad.any(axis=0)):
            n = int(np.argmax(bad[:, body]))
            out[int(body)] = (
                n,
                float((total[n, body] - self.reference[body]) / max(peak[n, body], self.floor[body])),
            )
        return out


class DivergenceMonitor:
    """Which strips have stopped, and why: the kernel's health codes read after each
    launch, the energy budget checked on the chunk's probes (:class:`BudgetWatch`), and
    which of the chunk's samples each stopped strip still owns."""

    def __init__(self, model: Model, solver: Solver, control: Control) -> None:
        self.solver, self.control = solver, control
        self.budget = BudgetWatch.for_strips(model)
        self.diverged: list[Divergence] = []
        self.n_strips = model.n_strips

    def check(self, state: State, values: np.ndarray, steps: np.ndarray) -> list[Divergence]:
        """The strips that stopped in the chunk just run (``values[sample, field, strip]`` at
        ``steps``, the samples from the release on), each reported once."""
        known = {d.strip for d in self.diverged}
        if len(steps):
            total = (
                sum(values[:, PROBE_INDEX[name], :] for name in BUDGET_TERMS) - values[:, PROBE_INDEX["drive_work"], :]
            )
            stop_unbalanced(state, self.budget, total, values[:, PROBE_INDEX["kinetic"], :], steps, known)
        status = state.struct.status.numpy()
        new = [
            self.solver.divergence_report(state, self.control, int(s)) for s in np.nonzero(status)[0] if s not in known
        ]
        self.diverged.extend(new)
        return new

    def valid(self, steps: np.ndarray) -> np.ndarray:
        """``[sample, strip]``: whether each sample at ``steps`` precedes its strip's stop (the
        sample of a strain or a fold is kept, one whose energy failed is not)."""
        valid = np.ones((len(steps), self.n_strips), dtype=bool)
        for d in self.diverged:
            valid[:, d.strip] &= steps < d.step if d.sample_lost else steps <= d.step
        return valid

    @property
    def all_stopped(self) -> bool:
        """Whether no strip is left running."""
        return len(self.diverged) == self.n_strips


def stop_unbalanced(
    state: Any, budget: BudgetWatch, total: np.ndarray, kinetic: np.ndarray, steps: np.ndarray, known: set[int]
) -> None:
    """Stop, with STATUS_BUDGET in ``state.struct``'s health fields, every body (a strip, a
    sheet) not in ``known`` whose budget ``total[sample, body]`` fails at ``steps`` (its
    kinetic energy ``kinetic``), unless the kernel stopped it earlier: the first of the two
    events is the one reported, however the run is cut into launches (the samples from it
    on are dropped like others')."""
    fields = {
        name: getattr(state.struct, name).numpy() for name in ("status", "status_step", "status_index", "status_value")
    }
    # a kernel stop keeps the sample of its step for strain and fold (1, 2), not for a
    # non-finite energy (3); only kept samples are checked
    stopped = fields["status"] != 0
    through = np.where(fields["status"] == STATUS_NONFINITE_ENERGY, fields["status_step"] - 1, fields["status_step"])
    usable = ~stopped[None, :] | (steps[:, None] <= through[None, :])
    failed = {s: v for s, v in budget.first_violation(total, kinetic, usable).items() if s not in known}
    if not failed:
        return
    for strip, (sample, residual) in failed.items():
        fields["status"][strip] = STATUS_BUDGET
        fields["status_step"][strip] = int(steps[sample])
        fields["status_index"][strip] = -1
        fields["status_value"][strip] = residual
    for name, value in fields.items():
        getattr(state.struct, name).assign(value)
