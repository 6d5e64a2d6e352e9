"""What drives the strips: the clamp's rigid rotation θ(t) and the held free end
(docs/model.md §7-8).

θ(t) is a piecewise polynomial per strip (at most quartic pieces), held constant
outside its span; before the release the free end is carried along a polar path to
its hold target and held there.
"""

import functools
import math
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import geometry
from .types import precision

MAX_DEGREE = 4
"""Highest power of a clamp-motion piece θ = Σ c_k (t − start)^k."""


@functools.cache
def build(scalar: Any) -> SimpleNamespace:
    """The ``StripControl`` struct and the drive functions for ``scalar``."""
    types = precision(scalar)
    vec2, vec5, mat22 = types.vec2, types.vec5, types.mat22
    zero = scalar(0.0)
    one = scalar(1.0)
    # π in the kernel's precision, formed here: 2.0 * wp.pi inside a Warp function is a
    # float32 product.
    pi = scalar(math.pi)
    two_pi = scalar(2.0 * math.pi)
    perp = geometry.build(scalar).perp

    @wp.struct
    class StripControl:
        """What drives the strips: clamp rotation θ(t) and the held free end (SI)."""

        segment_start: wp.array2d(dtype=scalar)  # [segment, strip], s
        segment_end: wp.array2d(dtype=scalar)
        segment_coefficients: wp.array2d(dtype=vec5)  # θ = Σ c_k (t - start)^k, rad/s^k
        n_segments: wp.array(dtype=int)
        rotation_centre: wp.array(dtype=vec2)  # m, absolute
        hold_target: wp.array(dtype=vec2)  # free-end held position, m, absolute
        # where the carried path ends and its velocity there (``reach_hold``): the held end
        # after the carry, evaluated once, as the path's own arithmetic gives it
        held_position: wp.array(dtype=vec2)
        held_velocity: wp.array(dtype=vec2)
        settle_damping: wp.array(dtype=scalar)  # γ while held, 1/s
        hold_free_end: wp.array(dtype=int)  # 1: the free end is carried and held; 0: it settles freely

    @wp.func
    def piecewise_polynomial(
        segment_start: wp.array2d(dtype=scalar),
        segment_end: wp.array2d(dtype=scalar),
        segment_coefficients: wp.array2d(dtype=vec5),
        n: int,
        s: int,
        t: scalar,
    ):
        # Value and rate of body s's piecewise polynomial ([segment, body] arrays) at t;
        # held constant outside its span. Shared by the strip's clamp angle and the
        # sheet's clamp rotation and translation.
        if n == 0:
            return zero, zero
        lo = int(0)  # noqa: UP018 - Warp needs int() to make a loop-mutable variable
        hi = n - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if segment_start[mid, s] <= t:
                lo = mid
            else:
                hi = mid - 1
        start = segment_start[lo, s]
        end = segment_end[lo, s]
        tau = wp.clamp(t, start, end) - start
        moving = t >= start and t <= end
        c = segment_coefficients[lo, s]
        value = c[0] + tau * (c[1] + tau * (c[2] + tau * (c[3] + tau * c[4])))
        rate = zero
        if moving:
            rate = c[1] + tau * (scalar(2.0) * c[2] + tau * (scalar(3.0) * c[3] + tau * scalar(4.0) * c[4]))
        return value, rate

    @wp.func
    def clamp_angle(control: StripControl, s: int, t: scalar):
        # θ and dθ/dt of the piecewise polynomial; held constant outside its span.
        return piecewise_polynomial(
            control.segment_start, control.segment_end, control.segment_coefficients, control.n_segments[s], s, t
        )

    @wp.func
    def clamped_position(control: StripControl, rest: vec2, s: int, t: scalar):
        # Where a clamp node resting at ``rest`` is at time t: the rigid rotation about the
        # rotation centre, and exactly its rest position while θ = 0 (centre + (X − centre)
        # would move it by rounding).
        theta, _rate = clamp_angle(control, s, t)
        if theta == zero:
            return rest
        centre = control.rotation_centre[s]
        c = wp.cos(theta)
        sn = wp.sin(theta)
        return centre + mat22(c, -sn, sn, c) * (rest - centre)

    @wp.func
    def carried_free_end(control: StripControl, root: vec2, rest_tip: vec2, s: int, p: scalar, dp: scalar):
        # The free end is carried from its hanging position to the hold target along a
        # polar path about the clamp's lowest point (radius and angle blended by a C²
        # smootherstep p, its rate dp), so no segment is stretched on the way.
        start = rest_tip - root
        target = control.hold_target[s] - root
        r0 = wp.length(start)
        r1 = wp.length(target)
        a0 = wp.atan2(start[1], start[0])
        a1 = wp.atan2(target[1], target[0])
        turn = a1 - a0
        if turn > pi:  # the short way round, never through the clamp
            turn = turn - two_pi
        elif turn < -pi:
            turn = turn + two_pi
        r = r0 + (r1 - r0) * p
        a = a0 + turn * p
        radial = vec2(wp.cos(a), wp.sin(a))
        position = root + r * radial
        velocity = dp * ((r1 - r0) * radial + r * turn * perp(radial))
        return position, velocity

    @wp.func
    def held_free_end(
        control: StripControl, root: vec2, rest_tip: vec2, s: int, step: int, move_steps: int, dt: scalar
    ):
        # The free end at ``step`` of its carry, then held where the path ends: that point
        # is the path's at p = 1, stored once (two square roots, two arctangents, a cosine
        # and a sine at every step of the hold otherwise, three times a step under imex).
        if step < move_steps:
            x = scalar(step) / scalar(move_steps)
            p = x * x * x * (x * (x * scalar(6.0) - scalar(15.0)) + scalar(10.0))
            dp = scalar(30.0) * x * x * (x - one) * (x - one) / (scalar(move_steps) * dt)
            return carried_free_end(control, root, rest_tip, s, p, dp)
        return control.held_position[s], control.held_velocity[s]

    @wp.kernel(module="unique", enable_backward=False)
    def reach_hold(rest_position: wp.array2d(dtype=vec2), n_clamped: int, control: StripControl):
        """Store where each strip's carried path ends, and the velocity there (0, its
        zeros signed as the path's arithmetic signs them)."""
        s = wp.tid()
        n = rest_position.shape[0]
        x, v = carried_free_end(control, rest_position[n_clamped - 1, s], rest_position[n - 1, s], s, one, zero)
        control.held_position[s] = x
        control.held_velocity[s] = v

    @wp.func
    def starts_moving(control: StripControl, s: int, i: int, last: int, step: int, release_step: int):
        # Whether node i's velocity at this step is known at the step itself, not half a step
        # before it (kernels/integrators.py kick_mass): every node at the run's first step,
        # and the held free end (node ``last``) at its release.
        return step == 0 or (i == last and step == release_step and control.hold_free_end[s] != 0)

    return SimpleNamespace(
        StripControl=StripControl,
        starts_moving=starts_moving,
        piecewise_polynomial=piecewise_polynomial,
        clamp_angle=clamp_angle,
        clamped_position=clamped_position,
        held_free_end=held_free_end,
        reach_hold=reach_hold,
    )
