"""The frictional-couple bending law, ``"frictional_couple"`` (Grosberg's model of fabric
bending; docs/model.md §4.9).

Grosberg's couple is M = D K + M_f sign(dK/dt): an elastic moment plus a constant
frictional couple that reverses with the direction of bending, so that a KES-FB2 loop
has width 2HB = 2 M_f. The sign jumps at every reversal, which no explicit integrator
can take; here it is regularised by a spring in series with the frictional slider (a
Jenkins element), so the couple reverses continuously over a curvature change of 2 K_w:

    h ← clamp(h + (M_f / K_w) ΔK, −M_f, M_f),      M = D K + h,

rate-independent and exact for any sampling of the curvature path. K_w → 0 is
Grosberg's law; M_f = 0 is the elastic law. It is the Dahl law's n → 0 limit with
M_s = M_f and K_s = K_w (kernels/bending_dahl.py).
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from .types import precision

NAME = "frictional_couple"

PARAMETERS = ("bending_rigidity", "friction_moment", "friction_width")
"""Layout of the packed per-strip parameter vector: D (N·m), M_f (N), K_w (1/m)."""

MATERIAL_FIELDS = PARAMETERS
"""The :class:`warpcloth.sim.MaterialSI` fields :func:`packed_parameters` takes, in order."""

MEMORY = ("hysteretic_moment", "direction", "previous_curvature")
"""Layout of the packed per-hinge memory: h (N), the direction of the last change of
curvature (+1 / −1), K at the last force evaluation (1/m)."""

MESH_INDEPENDENT = True
"""Whether the law's answers converge as the mesh is refined: a Jenkins element: continuous
in the curvature path, with return-point memory."""

wp.set_module_options({"enable_backward": False})


def packed_parameters(bending_rigidity: float, moment: float, width: float) -> tuple[float, ...]:
    """The per-strip parameter vector (layout :data:`PARAMETERS`) from D, M_f, K_w in SI."""
    return (bending_rigidity, moment, width)


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """The law's Warp functions for ``scalar``, on the shared parameter and memory types."""
    types = precision(scalar)
    Memory, Parameters = types.law_memory, types.law_parameters  # this law uses 3 of the 6 parameter slots
    zero = scalar(0.0)
    one = scalar(1.0)

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters):
        # A hinge that has never bent: the slider at rest in the middle of its play.
        return Memory(zero, one, curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters):
        change = curvature - memory[2]
        m_f = p[1]
        if change == zero or m_f == zero:
            return Memory(memory[0], memory[1], curvature)
        h = wp.clamp(memory[0] + m_f / p[2] * change, -m_f, m_f)
        return Memory(h, wp.sign(change), curvature)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        return memory[0]

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters):
        # dM/dK on the current direction: D + M_f / K_w while the spring takes up the
        # change, D once the slider slips
        m_f = p[1]
        if m_f == zero or memory[1] * memory[0] >= m_f:
            return p[0]
        return p[0] + m_f / p[2]

    return SimpleNamespace(name=NAME, fresh_memory=fresh_memory, follow=follow, hysteretic_moment=hysteretic_moment,
                           tangent=tangent)
