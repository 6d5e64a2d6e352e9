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
from typing import Any

import warp as wp

from .bending_tagawa2003 import default_curvature_scale, default_loop_asymptote
from .law import BendingLaw, LawFunctions, LawParameter
from .types import precision

wp.set_module_options({"enable_backward": False})


def packed_parameters(bending_rigidity: float, moment: float, width: float) -> tuple[float, ...]:
    """The per-strip parameter vector (D, M_f, K_w) from D (N·m), M_f (N), K_w (1/m) in SI."""
    return (bending_rigidity, moment, width)


@functools.cache
def build(scalar: Any) -> LawFunctions:
    """The law's Warp functions for ``scalar``, on the shared parameter and memory types."""
    types = precision(scalar)
    Memory, Parameters, History = types.law_memory, types.law_parameters, types.reversal_memory  # 3 of 6 slots
    zero = scalar(0.0)
    one = scalar(1.0)

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        # A hinge that has never bent: the slider at rest in the middle of its play.
        return Memory(zero, one, curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
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
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # dM/dK on the current direction: D + M_f / K_w while the spring takes up the
        # change, D once the slider slips
        m_f = p[1]
        if m_f == zero or memory[1] * memory[0] >= m_f:
            return p[0]
        return p[0] + m_f / p[2]

    return LawFunctions(fresh_memory=fresh_memory, follow=follow, hysteretic_moment=hysteretic_moment, tangent=tangent)


LAW = BendingLaw(
    name="frictional_couple",
    summary="Grosberg's frictional couple",
    parameters=(
        LawParameter(
            "friction_moment",
            "friction_moment_gf_cm_per_cm",
            "moment",
            "Mf",
            "M_f",
            "M_f, the frictional couple (0 = elastic; 2HB = 2 M_f)",
            default=default_loop_asymptote,
            ge=0,
            amplitude=True,
        ),
        LawParameter(
            "friction_width",
            "friction_width_per_cm",
            "curvature",
            "Kw",
            "K_w",
            "K_w, curvature change over which the couple reverses (half of it each way; → 0: Grosberg's "
            "M_f sign(dK/dt))",
            default=default_curvature_scale,
            gt=0,
        ),
    ),
    pack=packed_parameters,
    memory=("hysteretic_moment", "direction", "previous_curvature"),  # h (N), +1 / −1, K (1/m)
    build=build,
    fitter="warpcloth.calibrate.kes.bending_frictional_couple:FRICTIONAL_COUPLE",
    mesh_independent=True,  # a Jenkins element: continuous in the curvature path, with return-point memory
)
"""Grosberg's frictional couple, described once (kernels/law.py)."""
