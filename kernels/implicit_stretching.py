"""Stretching taken implicitly, for the ``imex`` and ``imex_trapezoidal`` schemes
(docs/model.md §9.5, §9.5.1).

The stiffest motion of a strip is the stretching of its segments (ω ≈ 4e4 1/s at
h = 5 mm), which bounds an explicit step at ~5e-5 s while no 60 fps measurement resolves
it. Here the *axial* part of the tensile stiffness is taken by linearised backward Euler;
bending, the transverse (geometric) part of the tension, damping, gravity and the
hysteresis stay explicit. Per segment i (nodes i, i + 1, unit direction u_i and axial
stiffness k_i = W T'(ε_i) / l0 at the step's start) an extra tension ΔT_i acts over the
step, set by the stretching rate at its end:

    ΔT_i = k_i dt u_i · (v_{i+1} − v_i)^{n+1},      v^{n+1} = v* + (dt / m) F^corr,

with v* the explicit semi-implicit velocity (or a kinematic node's prescribed one) and
F^corr_j = ΔT_j u_j − ΔT_{j−1} u_{j−1}. Eliminating v^{n+1} leaves, per strip, one
symmetric, diagonally dominant tridiagonal system in the ΔT (one unknown per free
segment):

    (1/(k_i dt²) + w_i + w_{i+1}) ΔT_i − (u_{i−1}·u_i) w_i ΔT_{i−1} − (u_i·u_{i+1}) w_{i+1} ΔT_{i+1}
        = u_i · (v*_{i+1} − v*_i) / dt,

w_j = 1/m_j (0 for the clamp-edge node and for the held free end), solved in the strip's
own thread by the Thomas algorithm (no pivoting needed). The corrections are stored per
node and added to the explicit forces of the node update.

``imex_trapezoidal`` takes the same stiffness by the trapezoidal rule (Newmark's average
acceleration, β = 1/4): the correction is −¼ K (x^{n+1} − 2x^n + x^{n−1}) =
−¼ K dt (v^{n+1} − v^n), v^n = (x^n − x^{n−1}) / dt, so the system above holds with k_i → k_i/4
and v* → v* − v^n. It is second order and dissipates no stretching energy, where backward
Euler damps the stretching modes within milliseconds.
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import drives, force_terms, fused, integrators, structs, tensile
from .types import precision


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = (), trapezoidal: bool = False) -> SimpleNamespace:
    """``stretching_corrections`` for ``scalar`` and the model's force ``terms``: linearised
    backward Euler (``imex``), or with ``trapezoidal`` the trapezoidal rule
    (``imex_trapezoidal``)."""
    types = precision(scalar)
    vec2, vec4 = types.vec2, types.vec4
    zero = scalar(0.0)
    one = scalar(1.0)
    quarter = scalar(0.25)
    half = scalar(0.5)
    strip = structs.build(scalar, terms)
    StripModel, StripState = strip.StripModel, strip.StripState
    drive = drives.build(scalar)
    StripControl, clamped_position, held_free_end = drive.StripControl, drive.clamped_position, drive.held_free_end
    starts_moving = drive.starts_moving
    stepping_types = integrators.build(scalar)
    Stepping, kick_mass = stepping_types.Stepping, stepping_types.kick_mass["imex"]
    stiffness = tensile.build(scalar).stiffness_per_width
    internal_force = fused.internal_forces(StripState)
    applied = force_terms.build(terms, scalar, vec2, strip.tally, structs.STRIP_CHANNELS)

    @wp.func
    def node_mass(model: StripModel, i: int, s: int):
        m = model.node_mass[s]
        if i == model.n_nodes - 1:
            m = m * scalar(0.5)  # the free end carries half a segment
        return m

    @wp.func
    def inverse_mass(
        model: StripModel, control: StripControl, stepping: Stepping, s: int, i: int, step: int, held: bool
    ):
        # 1 / the mass the step's kick divides by; 0 for a node whose motion is prescribed:
        # the clamp-edge node and the held free end
        n = model.n_nodes
        if i < model.n_clamped or (held and i == n - 1):
            return zero
        return one / kick_mass(node_mass(model, i, s), starts_moving(control, s, i, n - 1, step, stepping.release_step))

    @wp.func
    def held_end(model: StripModel, control: StripControl, stepping: Stepping, s: int, level: int):
        # the held free end's position at step ``level`` of its carried path
        x, _v = held_free_end(
            control,
            model.rest_position[model.n_clamped - 1, s],
            model.rest_position[model.n_nodes - 1, s],
            s,
            level,
            stepping.move_steps,
            stepping.dt,
        )
        return x

    @wp.func
    def end_velocity(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        s: int,
        i: int,
        step: int,
        held: bool,
        gamma: scalar,
        t_next: scalar,
    ):
        # The node's velocity at the step's end without the corrections: explicit
        # semi-implicit for a free node, the prescribed displacement over dt for the
        # clamp-edge node and the held free end.
        dt = stepping.dt
        n = model.n_nodes
        x = state.position[i, s]
        if i < model.n_clamped:
            return (clamped_position(control, model.rest_position[i, s], s, t_next) - x) / dt
        if held and i == n - 1:
            return (held_end(model, control, stepping, s, step + 1) - x) / dt
        m = node_mass(model, i, s)
        v = state.velocity[i, s]
        f = internal_force(state, i, s) - gamma * m * v + m * vec2(zero, -model.gravity)
        if wp.static(applied.present):
            f = f + applied.force(x, v, m)
        return v + f * (dt / kick_mass(m, starts_moving(control, s, i, n - 1, step, stepping.release_step)))

    @wp.func
    def start_velocity(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        s: int,
        i: int,
        step: int,
        held: bool,
        t_next: scalar,
    ):
        # v_{n-1/2} = (x_n - x_{n-1}) / dt: a free node's stored velocity, a prescribed node's
        # displacement over the step before (at the first step, the held end's stored one).
        dt = stepping.dt
        x = state.position[i, s]
        if i < model.n_clamped:
            return (x - clamped_position(control, model.rest_position[i, s], s, t_next - scalar(2.0) * dt)) / dt
        if held and i == model.n_nodes - 1 and step > 0:
            return (x - held_end(model, control, stepping, s, step - 1)) / dt
        return state.velocity[i, s]

    @wp.func
    def segment(state: StripState, i: int, s: int):
        # segment i's unit direction and length
        e = state.position[i + 1, s] - state.position[i, s]
        length = wp.length(e)
        return e / length, length

    @wp.func
    def stretching_corrections(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        s: int,
        step: int,
        held: bool,
        gamma: scalar,
        t_next: scalar,
    ):
        """Store each node's implicit tension correction F^corr in ``state.correction``."""
        n = model.n_nodes
        first = model.n_clamped - 1  # the clamp-edge node: segment `first` is the first free one
        dt = stepping.dt
        l0 = model.rest_length
        axial = model.width[s] / l0
        a = model.tensile[s]
        # Forward elimination, segment by segment down the chain; row i couples ΔT_{i-1}, ΔT_i, ΔT_{i+1}.
        u, length = segment(state, first, s)
        w_start = end_velocity(model, control, stepping, state, s, first, step, held, gamma, t_next)
        # Newmark's start (step 0, every node's velocity known at t_0): its correction is
        # −½ K (x¹ − x⁰), which is this system with k/2 and v* itself; −¼ K (x¹ − x⁰) would
        # start a strip that is not in equilibrium with its stretching modes up to 3.7× too
        # large, and nothing here damps them.
        starting = step == 0
        if wp.static(trapezoidal) and not starting:
            w_start = w_start - start_velocity(model, control, stepping, state, s, first, step, held, t_next)
        inv_start = inverse_mass(model, control, stepping, s, first, step, held)
        previous_c = zero  # c'_{i-1}
        previous_d = zero  # d'_{i-1}
        lower = zero  # coefficient of ΔT_{i-1} in row i
        for i in range(first, n - 1):
            w_end = end_velocity(model, control, stepping, state, s, i + 1, step, held, gamma, t_next)
            if wp.static(trapezoidal) and not starting:
                w_end = w_end - start_velocity(model, control, stepping, state, s, i + 1, step, held, t_next)
            inv_end = inverse_mass(model, control, stepping, s, i + 1, step, held)
            k = axial * stiffness((length - l0) / l0, a)
            if wp.static(trapezoidal):
                k = k * wp.where(starting, half, quarter)  # Newmark's average acceleration, β = 1/4
            upper = zero
            u_next = u
            length_next = length
            if i + 1 < n - 1:
                u_next, length_next = segment(state, i + 1, s)  # each segment measured once per pass
                upper = -wp.dot(u, u_next) * inv_end
            diagonal = one / (k * dt * dt) + inv_start + inv_end
            rhs = wp.dot(u, w_end - w_start) / dt
            pivot = diagonal - lower * previous_c
            previous_c = upper / pivot
            previous_d = (rhs - lower * previous_d) / pivot
            state.elimination[i, s] = vec4(previous_c, previous_d, u[0], u[1])  # u: the back pass's too
            lower = upper  # the matrix is symmetric: row i+1's lower is row i's upper
            u = u_next
            length = length_next
            w_start = w_end
            inv_start = inv_end
        # Back substitution up the chain, turning each ΔT into forces on its two nodes.
        tension_below = zero  # ΔT_{i+1}
        u_below = vec2()
        for step_up in range(n - 1 - first):
            i = n - 2 - step_up
            row = state.elimination[i, s]
            tension = row[1] - row[0] * tension_below
            u = vec2(row[2], row[3])
            state.correction[i + 1, s] = tension_below * u_below - tension * u
            tension_below = tension
            u_below = u
        state.correction[first, s] = tension_below * u_below

    return SimpleNamespace(stretching_corrections=stretching_corrections)
