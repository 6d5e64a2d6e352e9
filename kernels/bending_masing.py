"""The paper's hysteretic bending law with return-point memory, ``"masing"`` (Masing's
rules; docs/model.md §4.10).

Moment per width M = D K + H, where H follows Masing's rules on the paper's branch shape:

- a hinge that has never reversed is on the virgin curve H = F(K − K_o) from the
  curvature K_o it started at, F(y) = ½ D1 (1 − e^{−2α|y|}) sgn y;
- after a reversal at (K_r, H_r) it follows the branch H = H_r + s D1 (1 − e^{−α s (K − K_r)})
  (s = ±1 the new direction: twice the virgin curve, stretched twice, Masing's rule);
- when the curvature passes the reversal point before the current one, the inner loop
  has closed and the hinge goes on along the older branch as if the inner loop had never
  happened (return-point memory); the first reversal's branch closes on the virgin curve
  at the mirror point 2 K_o − K_r.

The major loop between ±K0 is exactly the tagawa2003 loop (same D, D1, α, K0, so a
material switches law by one line); inner loops differ. Unlike tagawa2003 and dahl, whose
offset depends on the total variation of the curvature history, H here depends only on
the reversal points still open, so it is continuous in the curvature path (sup norm) and
converges as the mesh and the step are refined (docs/model.md §15.6). An Iwan model (a
continuum of Jenkins elements with yield curvatures of density 2 α² D1 e^{−2ακ}) has
exactly this response, which the tests use as the reference.

Each hinge keeps its open reversal points in the shared ``reversal_memory`` of
:func:`~warpcloth.kernels.types.precision` (``points[0]`` is
the origin (K_o, 0), ``points[1..depth]`` the reversals). A reversal that finds the
memory full is not stored: the hinge retraces its current branch elastically until the
curvature passes the top point again (the smallest loop, the new one, dissipates
nothing); each such reversal is counted per strip in ``overflows`` and reported by the
runner, never silent. K0 sets only where the KES loop closes; it does not enter the
dynamics.

Per-hinge memory (the shared vector): H, the direction of the last change of curvature
times (depth + 1), and the curvature at the last force evaluation.
"""

import functools
from typing import Any

import warp as wp

from .bending_tagawa2003 import LOOP_PARAMETERS
from .law import BendingLaw, LawFunctions
from .types import precision

DEFAULT_CAPACITY = 128
"""Reversal points kept per hinge unless the run asks otherwise: the bundled swing opens at
most 43 in 3 s and 46 in 10 s at every h, the bundled sweep's variants up to 63 within
2.3 s (a decaying swing nests one loop per half-cycle and per ripple of its fast modes;
benchmarks/masing_convergence.py, benchmarks/numba_peer.py --law masing print the
deepest); twice that leaves room. A full memory is counted and reported."""

wp.set_module_options({"enable_backward": False})


def packed_parameters(bending_rigidity: float, d1: float, alpha: float, k0: float) -> tuple[float, ...]:
    """The per-strip parameter vector (D, D1, α, K0) from D (N·m), D1 (N), α (m), K0 (1/m) in SI."""
    return (bending_rigidity, d1, alpha, k0)


@functools.cache
def build(scalar: Any) -> LawFunctions:
    """The law's Warp functions for ``scalar``, on the shared parameter, memory and reversal types."""
    return masing_functions(scalar, growing=False)


def masing_functions(scalar: Any, growing: bool) -> LawFunctions:
    """Masing's rules on the paper's branch shape for ``scalar``; with ``growing``, the
    friction of every Jenkins element of the equivalent Iwan model grows with the distance
    from the hinge's origin K_o by g(K) = √(1 + (β (K − K_o))²), β the packed parameter
    after K0 (:mod:`.bending_masing_growing` says why and derives the branches). Without it
    g ≡ 1 and every expression reduces, bit for bit, to Masing's."""
    types = precision(scalar)
    Memory, Parameters, ReversalMemory, vec2 = types.law_memory, types.law_parameters, types.reversal_memory, types.vec2
    zero = scalar(0.0)
    one = scalar(1.0)
    half = scalar(0.5)
    two = scalar(2.0)

    @wp.func
    def growth(curvature: scalar, origin: scalar, p: Parameters):
        # g(K): the friction's scale at curvature K (1 without growth)
        if wp.static(growing):
            x = p[4] * (curvature - origin)
            return wp.sqrt(one + x * x)
        return one

    @wp.func
    def growth_slope(curvature: scalar, origin: scalar, p: Parameters):
        # dg/dK
        if wp.static(growing):
            x = p[4] * (curvature - origin)
            return p[4] * x / wp.sqrt(one + x * x)
        return zero

    @wp.func
    def shape(u: scalar, p: Parameters):
        # F(u) = ½ D1 (1 − e^{−2αu}), u ≥ 0: the virgin curve of the Iwan model without growth
        return half * p[1] * (one - wp.exp(-two * p[2] * u))

    @wp.func
    def shape_slope(u: scalar, p: Parameters):
        # F'(u) = α D1 e^{−2αu}
        return p[2] * p[1] * wp.exp(-two * p[2] * u)

    @wp.func
    def virgin(curvature: scalar, origin: scalar, p: Parameters):
        # H = g F(|y| / g) sgn y, y = K − K_o (F(|y|) sgn y without growth)
        y = curvature - origin
        g = growth(curvature, origin, p)
        return wp.sign(y) * g * shape(wp.abs(y) / g, p)

    @wp.func
    def branch(curvature: scalar, top: vec2, s: scalar, origin: scalar, p: Parameters):
        # H = H_r + s G F(s (K − K_r) / G), G = g(K) + g(K_r) (Masing's rule: G = 2)
        total = growth(curvature, origin, p) + growth(top[0], origin, p)
        return top[1] + s * total * shape(s * (curvature - top[0]) / total, p)

    @wp.func
    def slope(curvature: scalar, start: scalar, s: scalar, total: scalar, origin: scalar, p: Parameters):
        # d/dK of s G F(u), u = s (K − K_start) / G, with dG/dK = g'(K): s G' F(u) + F'(u) (1 − s u G')
        u = s * (curvature - start) / total
        rising = growth_slope(curvature, origin, p)
        return s * rising * shape(u, p) + shape_slope(u, p) * (one - s * u * rising)

    @wp.func
    def direction_from(top: scalar, below: scalar):
        # A branch leaves its reversal point opposite to the way the curvature came to it.
        if top > below:
            return -one
        return one

    @wp.func
    def open_point(history: ReversalMemory, depth: int, origin: scalar, hinge: int, strip: int):
        # The top open point (the origin on the virgin curve) and the curvature of the one below it.
        top = vec2(origin, zero)
        below = origin
        if depth > 0:
            top = history.points[depth, hinge, strip]
            if depth > 1:
                below = history.points[depth - 1, hinge, strip][0]
        return top, below

    @wp.func
    def fresh_memory(curvature: scalar, p: Parameters, history: ReversalMemory, hinge: int, strip: int):
        # A hinge that has never bent: on the virgin curve from its own curvature.
        if p[1] != zero:
            history.points[0, hinge, strip] = vec2(curvature, zero)
        return Memory(zero, one, curvature)

    @wp.func
    def follow(curvature: scalar, memory: Memory, p: Parameters, history: ReversalMemory, hinge: int, strip: int):
        previous = memory[2]
        change = curvature - previous
        if change == zero or p[1] == zero:
            return Memory(memory[0], memory[1], curvature)
        d = wp.sign(change)
        last = wp.sign(memory[1])
        depth = int(wp.abs(memory[1])) - 1
        capacity = history.points.shape[0] - 1
        origin = history.points[0, hinge, strip][0]
        top, below = open_point(history, depth, origin, hinge, strip)
        s = d  # on the virgin curve at its origin every direction loads
        if depth > 0:
            s = direction_from(top[0], below)
        elif previous != origin:
            s = wp.sign(previous - origin)
        if d != s and last != d:
            # The curvature reversed at the previous evaluation, against the current branch.
            if depth < capacity:
                below = top[0]
                depth += 1
                top = vec2(previous, memory[0])
                history.points[depth, hinge, strip] = top
                s = d
                if depth > history.deepest[strip]:
                    history.deepest[strip] = depth
            else:
                history.overflows[strip] = history.overflows[strip] + 1
        # Retracing after a reversal the full memory could not hold: passing the top point
        # closes that loop, and the hinge continues on the branch before it.
        while d != s and depth > 0 and s * (curvature - top[0]) <= zero:
            depth -= 1
            s = d
            top, below = open_point(history, depth, origin, hinge, strip)
        # Return-point memory: reaching the point below the top closes the inner loop.
        while d == s and depth > 0:
            target = below
            if depth == 1:
                # the first branch meets the virgin curve at the mirror point, with or without
                # growth: K_m − K_o = s y_r g(K_m) with y_r = |K_r − K_o| / g(K_r) solves to it
                target = two * origin - top[0]
            if s * (curvature - target) < zero:
                break
            depth = wp.max(depth - 2, 0)
            top, below = open_point(history, depth, origin, hinge, strip)
        h = virgin(curvature, origin, p)
        if depth > 0:
            h = branch(curvature, top, s, origin, p)
        return Memory(h, d * scalar(depth + 1), curvature)

    @wp.func
    def hysteretic_moment(curvature: scalar, memory: Memory, p: Parameters):
        return memory[0]

    @wp.func
    def tangent(curvature: scalar, memory: Memory, p: Parameters, history: ReversalMemory, hinge: int, strip: int):
        # dM/dK: D plus the slope of the virgin curve or of the current branch.
        if p[1] == zero:
            return p[0]
        depth = int(wp.abs(memory[1])) - 1
        origin = history.points[0, hinge, strip][0]
        if depth == 0:
            y = curvature - origin
            return p[0] + slope(curvature, origin, wp.sign(y), growth(curvature, origin, p), origin, p)
        top, below = open_point(history, depth, origin, hinge, strip)
        s = direction_from(top[0], below)
        total = growth(curvature, origin, p) + growth(top[0], origin, p)
        return p[0] + slope(curvature, top[0], s, total, origin, p)

    return LawFunctions(fresh_memory=fresh_memory, follow=follow, hysteretic_moment=hysteretic_moment, tangent=tangent)


LAW = BendingLaw(
    name="masing",
    summary="the paper's loop with return-point memory: converges in h and dt",
    parameters=LOOP_PARAMETERS,
    pack=packed_parameters,
    # H (N), the direction of the last change of curvature (+1 / −1) times (the number of
    # open reversal points + 1), K (1/m)
    memory=("hysteretic_moment", "direction_depth", "previous_curvature"),
    build=build,
    fitter="warpcloth.calibrate.kes.bending_masing:MASING",
    mesh_independent=True,  # continuous in the curvature path: converges in h and dt (docs/model.md §15.6)
    uses_reversal_memory=True,
    loop_closure="hysteresis_k0",
)
"""Masing's rules on the paper's loop, described once (kernels/law.py)."""
