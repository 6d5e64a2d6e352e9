"""Discrete geometry of a chain of nodes in the plane: normals and hinge curvature."""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from .types import precision


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """``perp`` and ``signed_curvature`` for ``scalar``."""
    vec2 = precision(scalar).vec2

    @wp.func
    def perp(v: vec2):
        return vec2(-v[1], v[0])

    @wp.func
    def signed_curvature(e1: vec2, e2: vec2, inverse_l1: scalar, inverse_l2: scalar):
        # Curvature of the circle through the three nodes (segments e1, e2, given by the
        # reciprocals of their lengths, which the force pass needs anyway), and the chord
        # |e1 + e2| (docs/model.md §4.1): one division, by the chord.
        chord = wp.length(e1 + e2)
        cross = e1[0] * e2[1] - e1[1] * e2[0]
        return scalar(2.0) * cross * inverse_l1 * inverse_l2 / chord, chord

    return SimpleNamespace(perp=perp, signed_curvature=signed_curvature)
