"""Warp vector and matrix types of one scalar precision, shared by every kernel file.

Each kernel file builds its functions per precision (``build(scalar)``, cached), so one
source serves float64 (the default) and float32.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

LAW_PARAMETER_SLOTS = 6
"""Length of every bending law's packed per-strip parameters: D first, the law's own next,
the law's index (kernels/laws.py) last, so strips of different laws share one array."""

LAW_MEMORY_SLOTS = 3
"""Length of every bending law's packed per-hinge memory: the law's own, then the
curvature at the last force evaluation last."""


@dataclass(frozen=True)
class Precision:
    """The scalar type and the small vectors built on it."""

    scalar: Any
    vec2: Any
    vec3: Any
    vec4: Any
    vec5: Any
    mat22: Any
    law_parameters: Any  # a bending law's packed per-strip parameters (LAW_PARAMETER_SLOTS)
    law_memory: Any  # a bending law's packed per-hinge memory (LAW_MEMORY_SLOTS)


@functools.cache
def precision(scalar: Any) -> Precision:
    """The types of ``scalar`` (wp.float64 or wp.float32), built once."""
    vector = {n: wp.types.vector(n, dtype=scalar) for n in (2, 3, 4, 5, LAW_PARAMETER_SLOTS, LAW_MEMORY_SLOTS)}
    return Precision(
        scalar=scalar,
        vec2=vector[2],
        vec3=vector[3],
        vec4=vector[4],
        vec5=vector[5],
        mat22=wp.types.matrix(shape=(2, 2), dtype=scalar),
        law_parameters=vector[LAW_PARAMETER_SLOTS],
        law_memory=vector[LAW_MEMORY_SLOTS],
    )
