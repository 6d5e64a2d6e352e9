"""The bending laws a strip can use, and the one set of Warp functions that serves them
all, so strips of different laws run in the same batch and launch.

Each law is one file, ``bending_<name>.py``, providing ``NAME``; ``PARAMETERS`` (the
layout of its packed per-strip parameters, bending rigidity D first);
``MATERIAL_FIELDS`` (the :class:`warpcloth.sim.MaterialSI` fields its
``packed_parameters`` takes); ``MEMORY`` (its per-hinge memory, the last curvature
last); and ``build(scalar)`` with the wp.funcs ``fresh_memory``, ``follow``,
``hysteretic_moment`` and ``tangent`` on the shared types
(:data:`~warpcloth.kernels.types.LAW_PARAMETER_SLOTS`,
:data:`~warpcloth.kernels.types.LAW_MEMORY_SLOTS`). Every law's moment is D K plus its
hysteretic moment. Adding a law: its file and one entry in :data:`LAWS`.

The packed parameters carry the law's index in :data:`LAWS` in their last slot; the
functions here dispatch on it per strip (one branch per hinge evaluation, uniform across
a GPU warp when a batch is sorted by law).
"""

import functools
from types import ModuleType, SimpleNamespace
from typing import Any

import warp as wp

from . import bending_dahl, bending_frictional_couple, bending_masing, bending_tagawa2003
from .types import LAW_PARAMETER_SLOTS, precision

LAWS: tuple[ModuleType, ...] = (bending_tagawa2003, bending_dahl, bending_frictional_couple, bending_masing)
"""Every bending law, by its index in the packed parameters."""

BENDING_LAWS: dict[str, ModuleType] = {law.NAME: law for law in LAWS}
DEFAULT_BENDING_LAW = bending_tagawa2003.NAME
LAW_SLOT = LAW_PARAMETER_SLOTS - 1
"""Where the packed parameters hold the law's index."""

wp.set_module_options({"enable_backward": False})


def bending_law(name: str) -> ModuleType:
    """The module of the bending law ``name``; KeyError lists the known ones."""
    try:
        return BENDING_LAWS[name]
    except KeyError:
        raise KeyError(f"unknown bending law {name!r}; known: {', '.join(BENDING_LAWS)}") from None


def packed_parameters(name: str, *values: float) -> tuple[float, ...]:
    """The shared per-strip parameter vector of law ``name`` from its ``MATERIAL_FIELDS``
    values (SI): the law's own layout, zeros, then the law's index."""
    law = bending_law(name)
    own = tuple(float(v) for v in law.packed_parameters(*values))
    return own + (0.0,) * (LAW_SLOT - len(own)) + (float(LAWS.index(law)),)


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """The laws' Warp types, dispatching functions and path kernel for ``scalar``."""
    types = precision(scalar)
    Parameters, Memory = types.law_parameters, types.law_memory
    tagawa, dahl, friction, masing = (law.build(scalar) for law in LAWS)
    History = masing.ReversalMemory
    zero = scalar(0.0)

    @wp.func
    def law_of(p: Parameters):
        return int(p[LAW_SLOT])

    # ``history`` (the reversal points, [level, hinge, strip]) is read only by a law with
    # return-point memory; the others keep everything in their memory vector.
    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        law = law_of(p)
        if law == 1:
            return dahl.fresh_memory(curvature, p)
        if law == 2:
            return friction.fresh_memory(curvature, p)
        if law == 3:
            return masing.fresh_memory(curvature, p, history, hinge, strip)
        return tagawa.fresh_memory(curvature, p)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        law = law_of(p)
        if law == 1:
            return dahl.follow(curvature, memory, p)
        if law == 2:
            return friction.follow(curvature, memory, p)
        if law == 3:
            return masing.follow(curvature, memory, p, history, hinge, strip)
        return tagawa.follow(curvature, memory, p)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        law = law_of(p)
        if law == 1:
            return dahl.hysteretic_moment(curvature, memory, p)
        if law == 2:
            return friction.hysteretic_moment(curvature, memory, p)
        if law == 3:
            return masing.hysteretic_moment(curvature, memory, p)
        return tagawa.hysteretic_moment(curvature, memory, p)

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        law = law_of(p)
        if law == 1:
            return dahl.tangent(curvature, memory, p)
        if law == 2:
            return friction.tangent(curvature, memory, p)
        if law == 3:
            return masing.tangent(curvature, memory, p, history, hinge, strip)
        return tagawa.tangent(curvature, memory, p)

    @wp.func
    def elastic_moment(curvature: scalar, p: Parameters):
        return p[0] * curvature

    @wp.func
    def last_curvature(memory: Memory):
        # The curvature the hinge saw at its last force evaluation (every law's last slot).
        return memory[2]

    @wp.kernel(module="unique", enable_backward=False)
    def moment_along_path(
        curvature_path: wp.array2d(dtype=scalar),
        parameters: wp.array(dtype=Parameters),
        history: History,
        moment: wp.array2d(dtype=scalar),
        slope: wp.array2d(dtype=scalar),
        work: wp.array(dtype=scalar),
    ):
        """Moment per width M and tangent dM/dK along curvature paths ``[sample, hinge]``.

        Each hinge starts fresh at its first sample (path s is hinge 0 of strip s in
        ``history``); ``work`` accumulates
        Σ M_n (K_{n+1} − K_n), the bending work per width with a left-point rule.
        """
        s = wp.tid()
        p = parameters[s]
        memory = fresh_memory(curvature_path[0, s], p, history, 0, s)
        w = zero
        for n in range(curvature_path.shape[0]):
            k = curvature_path[n, s]
            memory = follow(k, memory, p, history, 0, s)
            m = elastic_moment(k, p) + hysteretic_moment(k, memory, p)
            moment[n, s] = m
            slope[n, s] = tangent(k, memory, p, history, 0, s)
            if n + 1 < curvature_path.shape[0]:
                w = w + m * (curvature_path[n + 1, s] - k)
        work[s] = w

    return SimpleNamespace(
        Parameters=Parameters,
        Memory=Memory,
        History=History,
        fresh_memory=fresh_memory,
        follow=follow,
        last_curvature=last_curvature,
        elastic_moment=elastic_moment,
        hysteretic_moment=hysteretic_moment,
        tangent=tangent,
        moment_along_path=moment_along_path,
    )
