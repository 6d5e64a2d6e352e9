"""Warp vector and matrix types of one scalar precision, shared by every kernel file.

Each kernel file builds its functions per precision (``build(scalar)``, cached), so one
source serves float64 (the default) and float32.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp


@dataclass(frozen=True)
class Precision:
    """The scalar type and the small vectors built on it."""

    scalar: Any
    vec2: Any
    vec3: Any
    vec4: Any
    vec5: Any
    mat22: Any


@functools.cache
def precision(scalar: Any) -> Precision:
    """The types of ``scalar`` (wp.float64 or wp.float32), built once."""
    return Precision(
        scalar=scalar,
        vec2=wp.types.vector(2, dtype=scalar),
        vec3=wp.types.vector(3, dtype=scalar),
        vec4=wp.types.vector(4, dtype=scalar),
        vec5=wp.types.vector(5, dtype=scalar),
        mat22=wp.types.matrix(shape=(2, 2), dtype=scalar),
    )
