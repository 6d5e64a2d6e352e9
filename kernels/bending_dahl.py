"""The Dahl bending law, ``"dahl"`` (Dahl 1968, as Miguel et al. 2013 used it for cloth
bending; docs/model.md §4.8).

Moment per width M = D K + h, with a hysteretic moment h that follows the curvature as

    dh/dK = (M_s / K_s) · (1 − s h / M_s)^n,      s = sign(dK/dt),

so h approaches ±M_s (the saturation moment) over the curvature scale K_s, with a branch
shape set by the exponent n. h is the state, continuous through every reversal. On each
step of monotone curvature the equation is integrated exactly (y = 1 − s h / M_s):

    y = y₀ · exp(−|ΔK| / K_s)                              n = 1
    y = (y₀^(1−n) + (n − 1) |ΔK| / K_s)^(1/(1−n))          n ≠ 1 (y = 0 once it reaches 0, n < 1)

(evaluated as y₀ exp(−ln(1 + x)/(n − 1)), x = (n − 1)(|ΔK|/K_s) y₀^(n−1), which does not
cancel as n → 1)

so the moment does not depend on how the curvature path is sampled. n = 1 is exactly the
paper's law with M0 = M_s and α = 1/K_s (kernels/bending_tagawa2003.py); n → 0 is a
frictional couple regularised by a spring of stiffness M_s / K_s
(kernels/bending_frictional_couple.py). M_s = 0 is the elastic law M = D K.
"""

import functools
from typing import Any

import warp as wp

from .bending_tagawa2003 import default_curvature_scale, default_loop_asymptote
from .law import BendingLaw, LawFunctions, LawParameter
from .types import precision

wp.set_module_options({"enable_backward": False})


def packed_parameters(bending_rigidity: float, moment: float, curvature: float, exponent: float) -> tuple[float, ...]:
    """The per-strip parameter vector (D, M_s, K_s, n) from D (N·m), M_s (N), K_s (1/m), n in SI."""
    return (bending_rigidity, moment, curvature, exponent)


@functools.cache
def build(scalar: Any) -> LawFunctions:
    """The law's Warp functions for ``scalar``, on the shared parameter and memory types."""
    types = precision(scalar)
    Memory, Parameters, History = types.law_memory, types.law_parameters, types.reversal_memory  # 4 of 6 slots
    zero = scalar(0.0)
    one = scalar(1.0)

    @wp.func
    def log1p(x: scalar):
        # ln(1 + x) to full precision for small x (Goldberg: the rounding of 1 + x cancels)
        w = one + x
        if w == one:
            return x
        return wp.log(w) * x / (w - one)

    @wp.func
    def remaining(y0: scalar, run: scalar, n: scalar):
        # y after a monotone run of |ΔK| / K_s = run, from y0 (exact for dy/dK ∝ −y^n):
        # y^(1−n) = y0^(1−n) + (n − 1) run, written as y0 exp(−ln(1 + x)/(n − 1)) with
        # x = (n − 1) run y0^(n−1), which stays accurate as n → 1 (the difference of two
        # powers would cancel) and tends to the exponential branch there
        if y0 <= zero:
            return zero
        if n == one:
            return y0 * wp.exp(-run)
        x = (n - one) * run * wp.pow(y0, n - one)
        if x <= -one:
            return zero  # n < 1: saturated within the step
        return y0 * wp.exp(-log1p(x) / (n - one))

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: History, hinge: int, strip: int):
        # A hinge that has never bent: no hysteretic moment, loading upward.
        return Memory(zero, one, curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        h = memory[0]
        direction = memory[1]
        change = curvature - memory[2]
        m_s = p[1]
        if change == zero or m_s == zero:
            return Memory(h, direction, curvature)
        direction = wp.sign(change)
        y = remaining(one - direction * h / m_s, wp.abs(change) / p[2], p[3])
        return Memory(direction * m_s * (one - y), direction, curvature)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        return memory[0]

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: History, hinge: int, strip: int):
        # dM/dK on the current direction: D + (M_s / K_s) y^n
        m_s = p[1]
        if m_s == zero:
            return p[0]
        y = one - memory[1] * memory[0] / m_s
        if y <= zero:
            return p[0]  # saturated: the hysteretic moment no longer grows (0^0 is not 1 here)
        return p[0] + m_s / p[2] * wp.pow(y, p[3])

    return LawFunctions(fresh_memory=fresh_memory, follow=follow, hysteretic_moment=hysteretic_moment, tangent=tangent)


LAW = BendingLaw(
    name="dahl",
    summary="Dahl's",
    parameters=(
        LawParameter(
            "dahl_moment",
            "dahl_moment_gf_cm_per_cm",
            "moment",
            "Ms",
            "M_s",
            "M_s, saturation of the hysteretic moment (0 = elastic; 2HB → 2 M_s for K_s ≪ 1 1/cm)",
            default=default_loop_asymptote,
            ge=0,
            amplitude=True,
        ),
        LawParameter(
            "dahl_curvature",
            "dahl_curvature_per_cm",
            "curvature",
            "Ks",
            "K_s",
            "K_s, curvature scale over which the hysteretic moment saturates",
            default=default_curvature_scale,
            gt=0,
        ),
        LawParameter(
            "dahl_exponent",
            "dahl_exponent",
            "number",
            "n",
            "Dahl exponent n",
            "n, shape of the branches (1: the paper's exponential branches; → 0: a frictional couple)",
            default=1.0,
            ge=0,
        ),
    ),
    pack=packed_parameters,
    memory=("hysteretic_moment", "direction", "previous_curvature"),  # h (N), +1 / −1, K (1/m)
    build=build,
    fitter="warpcloth.calibrate.kes.bending_dahl:DAHL",
    # the hysteretic moment depends on the total variation of the curvature history (no
    # return-point memory), so fitted values depend on h (docs/model.md §15.6)
    mesh_independent=False,
)
"""Dahl's law, described once (kernels/law.py)."""
