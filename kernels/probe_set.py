"""What a body records at each output sample, described once (docs/model.md §10, §12).

A :class:`Probe` is a name, its SI unit and its place in the energy budget; a
:class:`ProbeSet` is a body's probes in the order of the probe buffer's second axis.
The budget that must stay constant, the work channels the kernel tallies, the slots the
kernel writes and the units a run directory states are all read from the descriptions,
so a new probe or a new force term's work channel is one entry, not an edit of every
place that sums the budget.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

STORED = "stored"
"""A probe that is energy the body holds (kinetic, gravitational, strain): + in the budget."""
WORK_AGAINST = "work_against"
"""Work done *against* a force (bending, damping, a force term): + in the budget; tallied per step."""
WORK_BY = "work_by"
"""Work done *by* a prescribed motion on the body (the clamp): − in the budget; tallied per step."""
BUDGET_SIGN = {STORED: 1, WORK_AGAINST: 1, WORK_BY: -1}


@dataclass(frozen=True)
class Probe:
    """One recorded quantity: its ``name``, SI ``unit`` (as meta.json states it) and its
    ``budget`` role (:data:`STORED`, :data:`WORK_AGAINST`, :data:`WORK_BY`, or None when it
    is not energy). The work probes are the kernel's energy tally channels, in order."""

    name: str
    unit: str
    budget: str | None = None

    @property
    def is_work(self) -> bool:
        """Whether the kernel tallies it step by step (a work channel)."""
        return self.budget in (WORK_AGAINST, WORK_BY)


class ProbeSet:
    """A body's probes in buffer order, and what follows from them."""

    def __init__(self, probes: tuple[Probe, ...]) -> None:
        names = [p.name for p in probes]
        if len(set(names)) != len(names):
            raise AssertionError(f"probe names repeat: {names}")  # a description error, caught by the tests
        self.probes = tuple(probes)
        self.fields: tuple[str, ...] = tuple(names)
        """Probe names in the buffer's order."""
        self.index: dict[str, int] = {name: i for i, name in enumerate(names)}
        """Slot of each probe."""
        self.units: dict[str, str] = {p.name: p.unit for p in probes}
        """SI unit of each probe."""
        self.channels: tuple[str, ...] = tuple(p.name for p in probes if p.is_work)
        """The work probes, in the order of the kernel's energy tally."""
        self.channel_slots: tuple[int, ...] = tuple(self.index[c] for c in self.channels)
        """The probe slot of each tally channel."""
        self.channel_signs: tuple[int, ...] = tuple(BUDGET_SIGN[probes[i].budget] for i in self.channel_slots)
        """Each channel's sign in the budget (+1 work against, −1 work by)."""
        self.stored: tuple[str, ...] = tuple(p.name for p in probes if p.budget == STORED)
        """The probes that are energy the body holds."""

    def channel(self, name: str) -> int:
        """The tally slot of work channel ``name``."""
        return self.channels.index(name)

    def with_terms(self, terms: tuple[Any, ...]) -> ProbeSet:
        """This set with each force term's work channel appended (the term's ``channel``)."""
        if not terms:
            return self
        return ProbeSet(self.probes + tuple(Probe(t.channel, "J", WORK_AGAINST) for t in terms))

    def energy_total(self, values: Any) -> Any:
        """The budget ``[sample, body]`` from probes ``[sample, field, body]``: the stored
        energies and the work done against forces, in buffer order, less the work done by
        prescribed motion. It stays constant to O(dt) (docs/model.md §10)."""
        plus = [values[:, i, :] for i, p in enumerate(self.probes) if p.budget in (STORED, WORK_AGAINST)]
        minus = [values[:, i, :] for i, p in enumerate(self.probes) if p.budget == WORK_BY]
        total = sum(plus[1:], plus[0])
        for term in minus:
            total = total - term
        return total
