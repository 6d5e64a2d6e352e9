"""Force terms: external forces on every free node of a strip or a sheet, each with the
energy channel its work is tallied in (docs/model.md §10.4).

A term is a frozen dataclass with a ``channel`` name and a ``build(scalar, vec)`` that
returns a Warp function ``(x, v, m) -> force`` of a node's position, velocity and mass.
The bodies' fused substeps add every term of their model to the free nodes' forces and
tally the work done against each over the step's centred displacement, as they do for
damping, so the budget closes with the term's channel in it (:meth:`ProbeSet.with_terms`).
Adding a term is this file (or one of its own) and a test: no substep, probe or budget
is edited.
"""

import functools
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import warp as wp


@dataclass(frozen=True)
class LinearDrag:
    """A drag proportional to the node's velocity and mass, ``−rate · m · v`` (``rate`` in
    1/s): still air around a body whose own damping γ stays a material property."""

    rate: float
    channel: str = "drag_work"

    def build(self, scalar: Any, vec: Any) -> Any:
        """The term's Warp function for ``scalar`` and the body's vector type ``vec``."""
        rate = scalar(self.rate)

        @wp.func
        def drag(x: vec, v: vec, m: scalar):
            return -(rate * m) * v

        return drag


@dataclass(frozen=True)
class RigidFloor:
    """A rigid horizontal floor at ``height`` (m): a node below it is pushed up by a
    penalty spring ``m ω² (height − y)``, ``ω`` (rad/s) fast against the motion so the
    penetration is small. Conservative: the work done against it is its spring's energy,
    returned as the node leaves."""

    height: float
    omega: float
    channel: str = "floor_work"

    def build(self, scalar: Any, vec: Any) -> Any:
        """The term's Warp function for ``scalar`` and the body's vector type ``vec``."""
        height = scalar(self.height)
        stiffness = scalar(self.omega * self.omega)
        up = vec()
        up[1] = scalar(1.0)

        @wp.func
        def floor(x: vec, v: vec, m: scalar):
            depth = height - x[1]
            if depth > scalar(0.0):
                return (m * stiffness * depth) * up
            return vec()

        return floor


FORCE_TERMS = {"drag": LinearDrag, "floor": RigidFloor}
"""The force terms by name."""


def _sum_of(functions: tuple[Any, ...], scalar: Any, vec: Any) -> Any:
    # Each term's function is called by name, never looked up by a loop index: Warp hashes
    # the functions a function names, not those a loop's wp.static picks (two terms of one
    # count would otherwise share a cached kernel, tests/test_bodies.py).
    head = functions[0]
    if len(functions) == 1:

        @wp.func
        def force(x: vec, v: vec, m: scalar):
            return head(x, v, m)

        return force
    tail = _sum_of(functions[1:], scalar, vec)

    @wp.func
    def force_sum(x: vec, v: vec, m: scalar):
        return head(x, v, m) + tail(x, v, m)

    return force_sum


def _work_of(functions: tuple[Any, ...], scalar: Any, vec: Any, tally: Any, slot: int) -> Any:
    head = functions[0]
    if len(functions) == 1:

        @wp.func
        def work(x: vec, v: vec, m: scalar, sweep: vec):
            w = tally()
            w[wp.static(slot)] = -wp.dot(head(x, v, m), sweep)
            return w

        return work
    tail = _work_of(functions[1:], scalar, vec, tally, slot + 1)

    @wp.func
    def work_sum(x: vec, v: vec, m: scalar, sweep: vec):
        w = tail(x, v, m, sweep)
        w[wp.static(slot)] = -wp.dot(head(x, v, m), sweep)
        return w

    return work_sum


@functools.cache
def build(terms: tuple[Any, ...], scalar: Any, vec: Any, tally: Any, first_channel: int) -> SimpleNamespace:
    """``force(x, v, m)``, the sum of ``terms``' forces on a node, and ``work(x, v, m,
    sweep)``, the tally with the work done against each term over the displacement
    ``sweep`` in its channel (``first_channel`` + its place in ``terms``); ``present`` is
    False, and neither is called, without terms."""
    if not terms:
        return SimpleNamespace(force=None, work=None, present=False)
    functions = tuple(t.build(scalar, vec) for t in terms)
    return SimpleNamespace(
        force=_sum_of(functions, scalar, vec),
        work=_work_of(functions, scalar, vec, tally, first_channel),
        present=True,
    )
