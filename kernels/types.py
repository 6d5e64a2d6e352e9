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

LAST_CURVATURE_SLOT = LAW_MEMORY_SLOTS - 1
"""Where every law's memory keeps the curvature of its last force evaluation."""


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
    reversal_memory: Any  # the reversal points of a law with return-point memory (kernels/bending_masing.py)


@functools.cache
def precision(scalar: Any) -> Precision:
    """The types of ``scalar`` (wp.float64 or wp.float32), built once."""
    vector = {n: wp.types.vector(n, dtype=scalar) for n in (2, 3, 4, 5, LAW_PARAMETER_SLOTS, LAW_MEMORY_SLOTS)}
    vec2 = vector[2]

    @wp.struct
    class ReversalMemory:
        """Every hinge's open reversal points and, per strip, what did not fit; passed to
        every law's functions, read only by a law with return-point memory."""

        points: wp.array3d(dtype=vec2)  # [level, hinge, strip]: (K, H); level 0 is the origin (K_o, 0)
        overflows: wp.array(dtype=int)  # [strip]: reversals not stored because the memory was full
        deepest: wp.array(dtype=int)  # [strip]: the most reversal points any of its hinges held

    return Precision(
        scalar=scalar,
        vec2=vector[2],
        vec3=vector[3],
        vec4=vector[4],
        vec5=vector[5],
        mat22=wp.types.matrix(shape=(2, 2), dtype=scalar),
        law_parameters=vector[LAW_PARAMETER_SLOTS],
        law_memory=vector[LAW_MEMORY_SLOTS],
        reversal_memory=ReversalMemory,
    )
