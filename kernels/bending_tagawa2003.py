"""The paper's hysteretic bending law, ``"tagawa2003"`` (paper eqs. 3-4; docs/model.md §4).

Moment per width M = D K + h(K − c), where h is the hysteretic offset on the current
branch (h₊ while curvature rises, h₋ while it falls) of a KES loop of amplitude D1,
steepness α and closing curvature K0, and c is the loop centre. At every reversal the
loop is translated along M = D K so that the moment stays continuous.

A law is one file ending with its description, ``LAW`` (kernels/law.py says what a law
provides; kernels/laws.py lists them): its per-strip parameters packed in one vector, its
per-hinge memory packed in one vector, and wp.funcs for a fresh hinge, the branch logic,
the hysteretic moment and its tangent dM/dK. The strip kernel and ``moment_along_path``
(the law alone, on prescribed curvature paths) use exactly these functions.

On a branch the offset obeys dh/dK = α (M0 − s h) (s = ±1 the direction), and at a
reversal h stays continuous while s flips: the Dahl model with exponent 1, saturation
moment M0 and curvature scale 1/α (kernels/bending_dahl.py; docs/model.md §4.8).
"""

import functools
import math
from collections.abc import Mapping
from typing import Any

import warp as wp

from .law import BendingLaw, LawFunctions, LawParameter
from .types import precision

PACKED = ("bending_rigidity", "hysteresis_d1", "hysteresis_alpha", "hysteresis_k0", "hysteresis_m0")
"""Layout of the packed per-strip parameter vector: D (N·m), D1 (N), α (m), K0 (1/m), M0 (N)."""

# Fraction of M0 kept between a hysteretic offset and its asymptote before the inverse
# branch takes a logarithm (docs/model.md §4.4: H is clamped to (−M0, M0) strictly).
HYSTERESIS_MARGIN = {wp.float64: 1e-12, wp.float32: 1e-6}

wp.set_module_options({"enable_backward": False})


def loop_asymptote(d1: float, alpha: float, k0: float) -> float:
    """M0 = ½ D1 (1 + e^{−2αK0}), the asymptote of the hysteretic offset (N)."""
    return 0.5 * d1 * (1.0 + math.exp(-2.0 * alpha * k0))


def default_loop_asymptote(loop: Mapping[str, Any]) -> float:
    """M0 of the default material's loop (D1, α, K0 by SI name, in KES units): the moment
    another law's default takes so that switching the law alone keeps that loop
    (docs/model.md §4.8)."""
    return loop_asymptote(loop["hysteresis_d1"], loop["hysteresis_alpha"], loop["hysteresis_k0"])


def default_curvature_scale(loop: Mapping[str, Any]) -> float:
    """1/α of the same loop: its curvature scale."""
    return 1.0 / loop["hysteresis_alpha"]


def packed_parameters(bending_rigidity: float, d1: float, alpha: float, k0: float) -> tuple[float, ...]:
    """The per-strip parameter vector (layout :data:`PACKED`) from D, D1, α, K0 in SI."""
    return (bending_rigidity, d1, alpha, k0, loop_asymptote(d1, alpha, k0))


@functools.cache
def build(scalar: Any) -> LawFunctions:
    """The law's Warp functions for ``scalar``, on the shared parameter and memory types."""
    types = precision(scalar)
    Memory, Parameters, History = types.law_memory, types.law_parameters, types.reversal_memory  # 5 of 6 slots
    zero = scalar(0.0)
    one = scalar(1.0)
    margin = scalar(HYSTERESIS_MARGIN[scalar])

    @wp.func
    def hysteretic_offset(u: scalar, branch: scalar, p: Parameters):
        # h₊ / h₋ with u = K − c measured from the loop centre. Without hysteresis
        # (D1 = 0, so M0 = 0) both branches are exactly 0: skip the exponential, the
        # largest single cost of a hinge (elastic sweep variants run ~25 % faster).
        d1 = p[1]
        if d1 == zero:
            return zero
        alpha = p[2]
        k0 = p[3]
        m0 = p[4]
        if branch > zero:
            return m0 - d1 * wp.exp(-alpha * (k0 + u))
        return -m0 + d1 * wp.exp(-alpha * (k0 - u))

    @wp.func
    def loop_centre_through(curvature: scalar, offset: scalar, branch: scalar, p: Parameters):
        # Centre c that puts the point (curvature, offset) on the given branch, so the
        # moment stays continuous when the branch is entered there.
        d1 = p[1]
        if d1 <= zero:
            return curvature
        alpha = p[2]
        k0 = p[3]
        m0 = p[4]
        limit = m0 * (one - margin)
        h = wp.clamp(offset, -limit, limit)
        # c = K − u with u = h₊⁻¹(H) or h₋⁻¹(H)
        if branch > zero:
            return curvature + k0 + wp.log((m0 - h) / d1) / alpha
        return curvature - k0 - wp.log((h + m0) / d1) / alpha

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        # A hinge that has never bent back: rising branch, no offset at its curvature.
        return Memory(one, loop_centre_through(curvature, zero, one, p), curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # A reversal happens at the previous curvature; the loop is translated along
        # M = D K so that the offset there is unchanged on the new branch.
        b = memory[0]
        c = memory[1]
        previous = memory[2]
        if (curvature - previous) * b < zero:
            offset = hysteretic_offset(previous - c, b, p)
            b = -b
            c = loop_centre_through(previous, offset, b, p)
        return Memory(b, c, curvature)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        return hysteretic_offset(curvature - memory[1], memory[0], p)

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # dM/dK on the current branch: D plus the slope of h, α D1 e^{−α(K0 ± u)} > 0.
        d1 = p[1]
        if d1 == zero:
            return p[0]
        alpha = p[2]
        k0 = p[3]
        u = curvature - memory[1]
        if memory[0] > zero:
            return p[0] + alpha * d1 * wp.exp(-alpha * (k0 + u))
        return p[0] + alpha * d1 * wp.exp(-alpha * (k0 - u))

    return LawFunctions(fresh_memory=fresh_memory, follow=follow, hysteretic_moment=hysteretic_moment, tangent=tangent)


LOOP_PARAMETERS = (
    LawParameter(
        "hysteresis_d1",
        "hysteresis_d1_gf_cm_per_cm",
        "moment",
        "D1",
        "D1",
        "D1, hysteresis amplitude (0 = elastic)",
        default=None,
        ge=0,
        amplitude=True,
    ),
    LawParameter(
        "hysteresis_alpha",
        "hysteresis_alpha_cm",
        "inverse_curvature",
        "alpha",
        "α",
        "α, steepness of the hysteresis branches",
        default=None,
        gt=0,
    ),
    LawParameter(
        "hysteresis_k0",
        "hysteresis_k0_per_cm",
        "curvature",
        "K0",
        "K0",
        "K0, curvature where the KES loop closes (masing: only there, not in the dynamics)",
        default=None,
        gt=0,
    ),
)
"""The paper's loop (D1, α, K0), read by this law and by masing (the same major loop)."""

LAW = BendingLaw(
    name="tagawa2003",
    summary="the paper's",
    parameters=LOOP_PARAMETERS,
    pack=packed_parameters,
    memory=("branch", "loop_centre", "previous_curvature"),  # +1 rising / −1 falling, c (1/m), K (1/m)
    build=build,
    fitter="warpcloth.calibrate.kes.bending_tagawa2003:TAGAWA2003",
    # the offset depends on the total variation of the curvature history (no return-point
    # memory), so fitted values depend on h (docs/model.md §15.6)
    mesh_independent=False,
    loop_closure="hysteresis_k0",
)
"""The paper's law, described once (kernels/law.py)."""
