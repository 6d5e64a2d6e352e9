"""When a body has diverged: the health codes its kernel sets, the energy budget checked on
the recorded probes, and which samples of a stopped body are kept (docs/model.md §11).
One policy for every body; a body's solver words the report (strips:
:class:`warpcloth.strip.Divergence`, sheets: :class:`warpcloth.sheet.SheetDivergence`)."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from warpcloth.kernels import STATUS_BUDGET, STATUS_NONFINITE_ENERGY

BUDGET_TOLERANCE = 0.1
"""A body whose energy budget (docs/model.md §10) has *gained* more than this fraction of
its energy scale since the release has diverged, even if no strain or fold check fired:
an unstable step (imex beyond its bending limit, forward Euler) creates energy, and can
grow a zig-zag or an oscillation long before a segment overstretches. Energy the step
removes is not counted: imex's backward Euler damps the stretching modes by design
(docs/model.md §9.5), which a soft or long strip started unstretched shows as a budget
loss of about its initial strain energy. The scale is the peak kinetic energy up to that
sample, and at least the body's floor (:meth:`BudgetWatch`): 1e-3 of its weight times its
free length, or of D W / L (the work of bending it through a radian) where that is
larger, as without gravity (just after a release, or for a body at rest, the kinetic
energy is near 0, and rounding is not). A healthy run's budget stays within 1e-2 of its
peak kinetic energy (imex at its largest stable dt), usually 1e-4. The check reads the
recorded samples, so where it fires does not depend on how the run is cut into launches."""


class BodyDivergence(Protocol):
    """What the runner and a run directory need of a body's divergence report."""

    body: int
    step: int
    time_s: float

    @property
    def sample_lost(self) -> bool:
        """Whether the sample at :attr:`step` is unusable (only the ones before it are kept)."""

    def describe(self) -> str:
        """One sentence a user can act on."""

    def as_dict(self) -> dict:
        """The report as a run directory's meta.json writes it."""


def sample_lost(code: int) -> bool:
    """Whether a stop with health ``code`` leaves its step's sample unusable: an energy
    that is not finite or off budget is; a strain, a fold or a collapsed cell is caught
    before the step that would make it, so the sample at that step is the last good one."""
    return code in (STATUS_NONFINITE_ENERGY, STATUS_BUDGET)


class BudgetWatch:
    """Each body's energy budget at the release and its peak kinetic energy so far, to
    stop a body whose budget no longer closes (:data:`BUDGET_TOLERANCE`), ``floor`` the
    least energy scale of each."""

    def __init__(self, floor: np.ndarray) -> None:
        self.floor = np.asarray(floor, dtype=float)
        self.reference = np.full(len(self.floor), np.nan)
        self.peak_kinetic = np.zeros(len(self.floor))

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


def stop_unbalanced(
    state: Any, budget: BudgetWatch, total: np.ndarray, kinetic: np.ndarray, steps: np.ndarray, known: set[int]
) -> None:
    """Stop, with STATUS_BUDGET in ``state.struct``'s health fields, every body not in
    ``known`` whose budget ``total[sample, body]`` fails at ``steps`` (its kinetic energy
    ``kinetic``), unless the kernel stopped it earlier: the first of the two events is the
    one reported, however the run is cut into launches (the samples from it on are dropped
    like others')."""
    fields = {
        name: getattr(state.struct, name).numpy() for name in ("status", "status_step", "status_index", "status_value")
    }
    # a kernel stop keeps the sample of its step unless that sample is lost (sample_lost);
    # only kept samples are checked
    stopped = fields["status"] != 0
    through = np.where(fields["status"] == STATUS_NONFINITE_ENERGY, fields["status_step"] - 1, fields["status_step"])
    usable = ~stopped[None, :] | (steps[:, None] <= through[None, :])
    failed = {s: v for s, v in budget.first_violation(total, kinetic, usable).items() if s not in known}
    if not failed:
        return
    for body, (sample, residual) in failed.items():
        fields["status"][body] = STATUS_BUDGET
        fields["status_step"][body] = int(steps[sample])
        fields["status_index"][body] = -1
        fields["status_value"][body] = residual
    for name, value in fields.items():
        getattr(state.struct, name).assign(value)


class DivergenceMonitor:
    """Which bodies of a batch have stopped, and why: the kernel's health codes read after
    each launch, the energy budget checked on the chunk's probes (:class:`BudgetWatch`,
    the model's :meth:`budget_floor`), and which of the chunk's samples each stopped body
    still owns. The same for every body."""

    def __init__(self, model: Any, solver: Any, control: Any) -> None:
        self.solver, self.control = solver, control
        self.probes = model.probes
        self.budget = BudgetWatch(model.budget_floor())
        self.diverged: list[Any] = []
        self.n_bodies = model.n_bodies

    def check(self, state: Any, values: np.ndarray, steps: np.ndarray) -> list[Any]:
        """The bodies that stopped in the chunk just run (``values[sample, field, body]`` at
        ``steps``, the samples from the release on), each reported once."""
        known = {d.body for d in self.diverged}
        if len(steps):
            total = self.probes.energy_total(values)
            kinetic = values[:, self.probes.index["kinetic"], :]
            stop_unbalanced(state, self.budget, total, kinetic, steps, known)
        status = state.struct.status.numpy()
        new = [
            self.solver.divergence_report(state, self.control, int(s)) for s in np.nonzero(status)[0] if s not in known
        ]
        self.diverged.extend(new)
        return new

    def valid(self, steps: np.ndarray) -> np.ndarray:
        """``[sample, body]``: whether each sample at ``steps`` precedes its body's stop (the
        sample of a strain, a fold or a collapsed cell is kept, one whose energy failed is
        not)."""
        valid = np.ones((len(steps), self.n_bodies), dtype=bool)
        for d in self.diverged:
            valid[:, d.body] &= steps < d.step if d.sample_lost else steps <= d.step
        return valid

    @property
    def all_stopped(self) -> bool:
        """Whether no body is left running."""
        return len(self.diverged) == self.n_bodies
