"""The paper's hysteretic bending law, ``"tagawa2003"`` (paper eqs. 3-4; docs/model.md §4).

Moment per width M = D K + h(K − c), where h is the hysteretic offset on the current
branch (h₊ while curvature rises, h₋ while it falls) of a KES loop of amplitude D1,
steepness α and closing curvature K0, and c is the loop centre. At every reversal the
loop is translated along M = D K so that the moment stays continuous. A hinge keeps its
branch s, the gap g = M0 − s h to that branch's asymptote and its last curvature; the
centre is implicit (docs/model.md §4.3): g decays as e^{−α s ΔK} along a branch, so each
step integrates it exactly, and a reversal, which keeps h, is g ← 2 M0 − g. That is one
exponential a step with no logarithm at a reversal, and no margin where a branch has
saturated (g = 0).

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
    two = scalar(2.0)

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        # A hinge that has never bent back: rising branch, no offset, so its gap to the
        # rising asymptote is M0.
        return Memory(one, p[4], curvature)

    @wp.func
    def follow_before_decay(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # The gap g = M0 − s h between the offset and its branch's asymptote decays as
        # e^{−α s ΔK} along a branch (the branch equation, integrated exactly over the
        # step); a reversal at the previous curvature keeps h, so the new branch's gap is
        # 2 M0 − g: the loop translated along M = D K without a logarithm or a centre.
        # Returns the memory with the gap before its decay, and the decay's exponent
        # −α |ΔK| ≤ 0 (s has the sign of ΔK once a reversal has flipped it). Without
        # hysteresis (D1 = 0, so M0 = 0) the gap stays 0 and the exponent is 0: no
        # exponential, the largest single cost of a hinge (elastic sweep variants run
        # ~25 % faster).
        b = memory[0]
        gap = memory[1]
        change = curvature - memory[2]
        if change * b < zero:
            b = -b
            gap = two * p[4] - gap
        exponent = zero
        if p[1] != zero:
            exponent = -p[2] * b * change
        return Memory(b, gap, curvature), exponent

    @wp.func
    def decay(memory: Memory, factor: scalar, p: Parameters):
        return Memory(memory[0], memory[1] * factor, memory[2])

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        followed, exponent = follow_before_decay(curvature, memory, p, history, hinge, strip)
        if exponent != zero:  # e^0 = 1 exactly: no exponential without a change
            followed = decay(followed, wp.exp(exponent), p)
        return followed

    @wp.func
    def gap_at(curvature: scalar, memory: Memory, p: Parameters):
        # g at ``curvature`` on the current branch: the stored one at the curvature follow
        # left (and 0 without hysteresis), else the branch on to it
        if curvature == memory[2] or p[1] == zero:
            return memory[1]
        return memory[1] * wp.exp(-p[2] * memory[0] * (curvature - memory[2]))

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        # h = s (M0 − g)
        return memory[0] * (p[4] - gap_at(curvature, memory, p))

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # dM/dK on the current branch: D plus the slope of h, α g ≥ 0.
        return p[0] + p[2] * gap_at(curvature, memory, p)

    return LawFunctions(
        fresh_memory=fresh_memory,
        follow=follow,
        hysteretic_moment=hysteretic_moment,
        tangent=tangent,
        follow_before_decay=follow_before_decay,
        decay=decay,
    )


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
    memory=("branch", "gap_to_asymptote", "previous_curvature"),  # +1 rising / −1 falling, M0 − s h (N), K (1/m)
    build=build,
    fitter="warpcloth.calibrate.kes.bending_tagawa2003:TAGAWA2003",
    # the offset depends on the total variation of the curvature history (no return-point
    # memory), so fitted values depend on h (docs/model.md §15.6)
    mesh_independent=False,
    loop_closure="hysteresis_k0",
)
"""The paper's law, described once (kernels/law.py)."""
