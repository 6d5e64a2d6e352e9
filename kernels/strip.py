"""Warp kernels for a batch of hanging fabric strips (MODEL.md).

One GPU thread (or CPU task) advances one strip through many explicit substeps inside
a single launch, so a batch of strips costs one launch per output chunk, not one per
substep. Per-node arrays are laid out ``[node, strip]``: at a given node index the
threads of a warp read neighbouring strips, i.e. consecutive addresses (coalesced).

The kernels are generated per scalar type (float64 by default, float32 optional) by
:func:`build_kernels`; the same source serves both.
"""


import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

SEMI_IMPLICIT = 0
FORWARD = 1

# Divergence codes written to ``status``; 0 means the strip is healthy.
STATUS_OK = 0
STATUS_STRAIN = 1
STATUS_FOLDED = 2
STATUS_NONFINITE_ENERGY = 3

# Probe quantities, in the order of the probe buffer's second axis.
PROBE_FIELDS = (
    "tip_x",
    "tip_y",
    "tip_speed",
    "laser_x",
    "clamp_angle",
    "kinetic",
    "gravitational",
    "tensile",
    "bending_elastic_work",
    "hysteresis_work",
    "damping_work",
    "drive_work",
    "loop_curvature",
    "loop_moment",
)
PROBE_INDEX = {name: i for i, name in enumerate(PROBE_FIELDS)}

# Fraction of M0 kept between a hysteretic offset and its asymptote before the inverse
# branch takes a logarithm (MODEL.md: clamp H to (-M0, M0) strictly).
HYSTERESIS_MARGIN = {wp.float64: 1e-12, wp.float32: 1e-6}

# Forward simulation only: no adjoint code to generate, compile and carry.
wp.set_module_options({"enable_backward": False})


@dataclass(frozen=True)
class KernelSet:
    """The Warp types and kernels for one scalar precision."""

    scalar: Any
    vec2: Any
    vec4: Any
    vec5: Any
    StripModel: Any
    StripControl: Any
    StripState: Any
    advance: Any
    initialise_hysteresis: Any
    moment_along_path: Any


@functools.cache
def build_kernels(scalar: Any) -> KernelSet:
    """Build (once per precision) the structs and kernels for ``scalar`` (wp.float64/32)."""
    vec2 = wp.types.vector(2, dtype=scalar)
    vec4 = wp.types.vector(4, dtype=scalar)
    vec5 = wp.types.vector(5, dtype=scalar)
    mat22 = wp.types.matrix(shape=(2, 2), dtype=scalar)
    zero = scalar(0.0)
    one = scalar(1.0)
    half = scalar(0.5)
    margin = scalar(HYSTERESIS_MARGIN[scalar])

    @wp.struct
    class StripModel:
        """What the strips are: batch geometry and per-strip material (SI)."""

        n_nodes: int
        n_clamped: int
        rest_length: scalar
        gravity: scalar
        tensile: wp.array(dtype=vec4)  # a1..a4 of T(ε), N/m
        bending_rigidity: wp.array(dtype=scalar)  # D, N·m
        hysteresis_d1: wp.array(dtype=scalar)  # D1, N
        hysteresis_alpha: wp.array(dtype=scalar)  # α, m
        hysteresis_k0: wp.array(dtype=scalar)  # K0, 1/m
        hysteresis_m0: wp.array(dtype=scalar)  # M0 = ½ D1 (1 + e^{-2αK0}), N
        width: wp.array(dtype=scalar)  # W, m
        node_mass: wp.array(dtype=scalar)  # ρ_A W h, kg (half at the free end)
        damping: wp.array(dtype=scalar)  # γ after release, 1/s

    @wp.struct
    class StripControl:
        """What drives the strips: clamp rotation θ(t) and the held free end."""

        segment_start: wp.array2d(dtype=scalar)  # [segment, strip], s
        segment_end: wp.array2d(dtype=scalar)
        segment_coefficients: wp.array2d(dtype=vec5)  # θ = Σ c_k (t - start)^k, rad/s^k
        n_segments: wp.array(dtype=int)
        rotation_centre: wp.array(dtype=vec2)  # m, absolute
        hold_target: wp.array(dtype=vec2)  # free-end held position, m, absolute
        settle_damping: wp.array(dtype=scalar)  # γ while held, 1/s
        release_step: int  # step index of t = 0 (release); the hold lasts before it
        move_steps: int  # steps spent carrying the free end to the hold target
        dt: scalar
        integrator: int
        max_strain: scalar

    @wp.struct
    class StripState:
        """What the strips are doing: nodes, hinge hysteresis memory, work, health."""

        position: wp.array2d(dtype=vec2)  # [node, strip]
        velocity: wp.array2d(dtype=vec2)
        rest_position: wp.array2d(dtype=vec2)  # clamp nodes rotate rigidly from these
        force_tensile: wp.array2d(dtype=vec2)  # scratch, per substep
        force_elastic: wp.array2d(dtype=vec2)
        force_hysteretic: wp.array2d(dtype=vec2)
        branch: wp.array2d(dtype=scalar)  # [hinge, strip], +1 rising / -1 falling
        loop_centre: wp.array2d(dtype=scalar)  # c, 1/m
        previous_curvature: wp.array2d(dtype=scalar)  # K at the last substep, 1/m
        work: wp.array(dtype=vec4)  # (bending elastic, hysteresis, damping, drive), J
        step: wp.array(dtype=int)  # substeps done so far
        status: wp.array(dtype=int)
        status_step: wp.array(dtype=int)
        status_index: wp.array(dtype=int)  # segment or hinge where it happened
        status_value: wp.array(dtype=scalar)

    @wp.func
    def tensile_force_per_width(strain: scalar, a: vec4):
        # Quartic fit of the KES-FB1 loading branch, odd-extended so compression is stiff.
        e = wp.abs(strain)
        t = e * (a[0] + e * (a[1] + e * (a[2] + e * a[3])))
        return wp.sign(strain) * t

    @wp.func
    def tensile_energy_per_width(strain: scalar, a: vec4):
        e = wp.abs(strain)
        q = scalar(1.0 / 3.0)
        return e * e * (half * a[0] + e * (q * a[1] + e * (scalar(0.25) * a[2] + e * scalar(0.2) * a[3])))

    @wp.func
    def hysteretic_offset(u: scalar, branch: scalar, d1: scalar, alpha: scalar, k0: scalar, m0: scalar):
        # h₊ / h₋ of MODEL.md, with u = K − c measured from the loop centre. Without
        # hysteresis (D1 = 0, so M0 = 0) both branches are exactly 0: skip the exponential,
        # the largest single cost of a hinge (elastic sweep variants run ~25 % faster).
        if d1 == zero:
            return zero
        if branch > zero:
            return m0 - d1 * wp.exp(-alpha * (k0 + u))
        return -m0 + d1 * wp.exp(-alpha * (k0 - u))

    @wp.func
    def loop_centre_through(
        curvature: scalar, offset: scalar, branch: scalar, d1: scalar, alpha: scalar, k0: scalar, m0: scalar
    ):
        # Centre c that puts the point (curvature, offset) on the given branch, so the
        # moment stays continuous when the branch is entered there.
        if d1 <= zero:
            return curvature
        limit = m0 * (one - margin)
        h = wp.clamp(offset, -limit, limit)
        # c = K - u with u = h₊⁻¹(H) or h₋⁻¹(H) (MODEL.md)
        if branch > zero:
            return curvature + k0 + wp.log((m0 - h) / d1) / alpha
        return curvature - k0 - wp.log((h + m0) / d1) / alpha

    @wp.func
    def follow_hysteresis(
        curvature: scalar,
        previous: scalar,
        branch: scalar,
        centre: scalar,
        d1: scalar,
        alpha: scalar,
        k0: scalar,
        m0: scalar,
    ):
        # A reversal happens at the previous curvature; the loop is translated along
        # M = D K so that the offset there is unchanged on the new branch.
        b = branch
        c = centre
        if (curvature - previous) * branch < zero:
            offset = hysteretic_offset(previous - centre, branch, d1, alpha, k0, m0)
            b = -branch
            c = loop_centre_through(previous, offset, b, d1, alpha, k0, m0)
        return b, c

    @wp.func
    def clamp_angle(control: StripControl, s: int, t: scalar):
        # θ and dθ/dt of the piecewise polynomial; held constant outside its span.
        n = control.n_segments[s]
        if n == 0:
            return zero, zero
        lo = int(0)  # noqa: UP018 - Warp needs int() to make a loop-mutable variable
        hi = n - 1
        while lo < hi:
            mid = (lo + hi + 1) // 2
            if control.segment_start[mid, s] <= t:
                lo = mid
            else:
                hi = mid - 1
        start = control.segment_start[lo, s]
        end = control.segment_end[lo, s]
        tau = wp.clamp(t, start, end) - start
        moving = t >= start and t <= end
        c = control.segment_coefficients[lo, s]
        theta = c[0] + tau * (c[1] + tau * (c[2] + tau * (c[3] + tau * c[4])))
        rate = zero
        if moving:
            rate = c[1] + tau * (scalar(2.0) * c[2] + tau * (scalar(3.0) * c[3] + tau * scalar(4.0) * c[4]))
        return theta, rate

    @wp.func
    def perp(v: vec2):
        return vec2(-v[1], v[0])

    @wp.func
    def signed_curvature(e1: vec2, e2: vec2, l1: scalar, l2: scalar):
        # Curvature of the circle through the three nodes (segments e1, e2 of lengths
        # l1, l2), and the chord |e1 + e2|.
        chord = wp.length(e1 + e2)
        cross = e1[0] * e2[1] - e1[1] * e2[0]
        return scalar(2.0) * cross / (l1 * l2 * chord), chord

    @wp.func
    def held_free_end(control: StripControl, root: vec2, rest_tip: vec2, s: int, step: int):
        # The free end is carried from its hanging position to the hold target along a
        # polar path about the clamp's lowest point (radius and angle blended by a C²
        # smootherstep), so no segment is stretched on the way; then it stays there.
        start = rest_tip - root
        target = control.hold_target[s] - root
        r0 = wp.length(start)
        r1 = wp.length(target)
        a0 = wp.atan2(start[1], start[0])
        a1 = wp.atan2(target[1], target[0])
        p = one
        dp = zero
        if step < control.move_steps:
            x = scalar(step) / scalar(control.move_steps)
            p = x * x * x * (x * (x * scalar(6.0) - scalar(15.0)) + scalar(10.0))
            dp = scalar(30.0) * x * x * (x - one) * (x - one) / (scalar(control.move_steps) * control.dt)
        turn = a1 - a0
        if turn > wp.pi:  # the short way round, never through the clamp
            turn = turn - scalar(2.0 * wp.pi)
        elif turn < -wp.pi:
            turn = turn + scalar(2.0 * wp.pi)
        r = r0 + (r1 - r0) * p
        a = a0 + turn * p
        radial = vec2(wp.cos(a), wp.sin(a))
        position = root + r * radial
        velocity = dp * ((r1 - r0) * radial + r * turn * perp(radial))
        return position, velocity

    @wp.func
    def accumulate_internal_forces(model: StripModel, control: StripControl, state: StripState, s: int):
        # Returns 0 when healthy, or a status code with the offending index and value.
        n = model.n_nodes
        first = model.n_clamped - 2  # clamped node above the clamp-edge hinge
        # Only the two nodes above the first hinge start from zero here; every node below is
        # first reached as node i + 1 of the pass and stored then (0 - f, bitwise the same
        # as zeroing first), which saves a sweep over three [node, strip] buffers.
        for i in range(first, first + 2):
            state.force_tensile[i, s] = vec2()
            state.force_elastic[i, s] = vec2()
            state.force_hysteretic[i, s] = vec2()
        width = model.width[s]
        a = model.tensile[s]
        l0 = model.rest_length
        rigidity = model.bending_rigidity[s]
        d1 = model.hysteresis_d1[s]
        alpha = model.hysteresis_alpha[s]
        k0 = model.hysteresis_k0[s]
        m0 = model.hysteresis_m0[s]
        # One pass down the strip: segment i (node i → i+1) and the hinge at node i share
        # the segment vector and length, so each is loaded and measured once. Segments
        # inside the clamp move rigidly: only the edge segment and below strain.
        node = state.position[first + 1, s]
        e1 = node - state.position[first, s]
        l1 = wp.length(e1)
        for i in range(first + 1, n - 1):
            following = state.position[i + 1, s]
            e2 = following - node
            l2 = wp.length(e2)
            strain = (l2 - l0) / l0
            if not (wp.abs(strain) <= control.max_strain):  # also catches NaN
                return STATUS_STRAIN, i, strain
            f = tensile_force_per_width(strain, a) * width / l2 * e2
            state.force_tensile[i, s] = state.force_tensile[i, s] + f
            state.force_tensile[i + 1, s] = vec2() - f
            h = i - first - 1
            curvature, chord = signed_curvature(e1, e2, l1, l2)
            if not (chord > scalar(1e-3) * l0):
                return STATUS_FOLDED, i, chord / l0
            b, c = follow_hysteresis(
                curvature, state.previous_curvature[h, s], state.branch[h, s], state.loop_centre[h, s],
                d1, alpha, k0, m0,
            )
            state.branch[h, s] = b
            state.loop_centre[h, s] = c
            state.previous_curvature[h, s] = curvature
            # τ = M·W acts on the turning angle φ; F = -τ ∇φ with ∇φ as below.
            grad_i = perp(e1) / (l1 * l1)
            grad_k = perp(e2) / (l2 * l2)
            tau_elastic = rigidity * curvature * width
            tau_hysteretic = hysteretic_offset(curvature - c, b, d1, alpha, k0, m0) * width
            state.force_elastic[i - 1, s] = state.force_elastic[i - 1, s] - tau_elastic * grad_i
            state.force_elastic[i + 1, s] = vec2() - tau_elastic * grad_k
            state.force_elastic[i, s] = state.force_elastic[i, s] + tau_elastic * (grad_i + grad_k)
            state.force_hysteretic[i - 1, s] = state.force_hysteretic[i - 1, s] - tau_hysteretic * grad_i
            state.force_hysteretic[i + 1, s] = vec2() - tau_hysteretic * grad_k
            state.force_hysteretic[i, s] = state.force_hysteretic[i, s] + tau_hysteretic * (grad_i + grad_k)
            node = following
            e1 = e2
            l1 = l2
        return STATUS_OK, 0, zero

    @wp.func
    def work_on(state: StripState, i: int, s: int, displacement: vec2):
        # Work done *against* the bending forces at node i. Callers pass the centred
        # displacement (v_n + v_{n+1}) dt / 2 = (x_{n+1} - x_{n-1}) / 2 for semi-implicit
        # Euler: the left-point F_n·(x_{n+1} - x_n) would add ½ΔxᵀHΔx every step, a
        # systematic O(dt) drift of the budget; the centred rule does not.
        return vec4(
            -wp.dot(state.force_elastic[i, s], displacement),
            -wp.dot(state.force_hysteretic[i, s], displacement),
            zero,
            zero,
        )

    @wp.func
    def substep(model: StripModel, control: StripControl, state: StripState, s: int, step: int):
        code, index, value = accumulate_internal_forces(model, control, state, s)
        if code != STATUS_OK:
            return code, index, value
        dt = control.dt
        n = model.n_nodes
        t_next = scalar(step + 1 - control.release_step) * dt
        held = step < control.release_step
        gamma = model.damping[s]
        if held:
            gamma = control.settle_damping[s]
        g = vec2(zero, -model.gravity)
        m_node = model.node_mass[s]
        work = state.work[s]
        for i in range(model.n_clamped, n):
            x = state.position[i, s]
            if held and i == n - 1:
                x_new, v_new = held_free_end(
                    control, state.rest_position[model.n_clamped - 1, s], state.rest_position[i, s], s, step + 1
                )
                sweep = (state.velocity[i, s] + v_new) * (half * dt)
                f_int = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
                work = work + work_on(state, i, s, sweep) + vec4(zero, zero, zero, -wp.dot(f_int, sweep))
                state.position[i, s] = x_new
                state.velocity[i, s] = v_new
            else:
                m = m_node
                if i == n - 1:
                    m = half * m_node
                v = state.velocity[i, s]
                f_damp = -gamma * m * v
                f = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
                f = f + f_damp + m * g
                v_new = v + f * (dt / m)
                dx = v_new * dt
                if control.integrator == FORWARD:
                    dx = v * dt
                sweep = (v + v_new) * (half * dt)
                work = work + work_on(state, i, s, sweep) + vec4(zero, zero, -wp.dot(f_damp, sweep), zero)
                state.position[i, s] = x + dx
                state.velocity[i, s] = v_new
        # Clamp nodes follow the rigid rotation; only the two above the edge carry forces.
        theta, rate = clamp_angle(control, s, t_next)
        centre = control.rotation_centre[s]
        ca = wp.cos(theta)  # once per substep, not per clamp node
        sa = wp.sin(theta)
        rotation = mat22(ca, -sa, sa, ca)
        for i in range(model.n_clamped):
            arm = rotation * (state.rest_position[i, s] - centre)
            v_new = rate * perp(arm)
            if i >= model.n_clamped - 2:
                sweep = (state.velocity[i, s] + v_new) * (half * dt)
                f_int = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
                work = work + work_on(state, i, s, sweep) + vec4(zero, zero, zero, -wp.dot(f_int, sweep))
            state.position[i, s] = centre + arm
            state.velocity[i, s] = v_new
        if step + 1 == control.release_step:
            work = vec4()  # the energy budget is reported from the release on
        state.work[s] = work
        return STATUS_OK, 0, zero

    @wp.func
    def laser_crossing(model: StripModel, state: StripState, s: int, height: scalar):
        # x where the strip first crosses y = height, searching down from the clamp edge.
        for i in range(model.n_clamped - 1, model.n_nodes - 1):
            p = state.position[i, s]
            q = state.position[i + 1, s]
            if (p[1] - height) * (q[1] - height) <= zero and p[1] != q[1]:
                return p[0] + (q[0] - p[0]) * (height - p[1]) / (q[1] - p[1])
        return scalar(wp.nan)

    @wp.func
    def record_probes(
        model: StripModel,
        control: StripControl,
        state: StripState,
        s: int,
        step: int,
        laser_height: scalar,
        loop_hinge: int,
        probes: wp.array3d(dtype=scalar),
        k: int,
    ):
        n = model.n_nodes
        t = scalar(step - control.release_step) * control.dt
        m_node = model.node_mass[s]
        kinetic = zero
        gravitational = zero
        for i in range(model.n_clamped, n):
            m = m_node
            if i == n - 1:
                m = half * m_node
            v = state.velocity[i, s]
            kinetic = kinetic + half * m * wp.dot(v, v)
            gravitational = gravitational + m * model.gravity * state.position[i, s][1]
        tensile = zero
        a = model.tensile[s]
        for i in range(model.n_clamped - 1, n - 1):
            length = wp.length(state.position[i + 1, s] - state.position[i, s])
            strain = (length - model.rest_length) / model.rest_length
            tensile = tensile + tensile_energy_per_width(strain, a) * model.width[s] * model.rest_length
        theta, rate = clamp_angle(control, s, t)
        tip = state.position[n - 1, s]
        work = state.work[s]
        probes[k, 0, s] = tip[0]
        probes[k, 1, s] = tip[1]
        probes[k, 2, s] = wp.length(state.velocity[n - 1, s])
        probes[k, 3, s] = laser_crossing(model, state, s, laser_height)
        probes[k, 4, s] = theta
        probes[k, 5, s] = kinetic
        probes[k, 6, s] = gravitational
        probes[k, 7, s] = tensile
        probes[k, 8, s] = work[0]
        probes[k, 9, s] = work[1]
        probes[k, 10, s] = work[2]
        probes[k, 11, s] = work[3]
        # The loop hinge's curvature at the last force evaluation and the moment per
        # width there, read back from its hysteresis memory (no extra force pass).
        curvature = state.previous_curvature[loop_hinge, s]
        offset = hysteretic_offset(
            curvature - state.loop_centre[loop_hinge, s], state.branch[loop_hinge, s], model.hysteresis_d1[s],
            model.hysteresis_alpha[s], model.hysteresis_k0[s], model.hysteresis_m0[s],
        )
        probes[k, 12, s] = curvature
        probes[k, 13, s] = model.bending_rigidity[s] * curvature + offset
        return kinetic + gravitational + tensile + work[0] + work[1] + work[2]

    @wp.kernel
    def advance(
        model: StripModel,
        control: StripControl,
        state: StripState,
        output_steps: wp.array(dtype=int),
        first_output: int,
        first_frame: int,
        probes_per_frame: int,
        laser_height: scalar,
        loop_hinge: int,
        probes: wp.array3d(dtype=scalar),
        frames: wp.array3d(dtype=vec2),
    ):
        """Advance every strip to each output step in turn, recording probes (and frames)."""
        s = wp.tid()
        if state.status[s] != STATUS_OK:
            return
        step = state.step[s]
        for k in range(output_steps.shape[0]):
            while step < output_steps[k]:
                code, index, value = substep(model, control, state, s, step)
                if code != STATUS_OK:
                    state.status[s] = code
                    state.status_step[s] = step
                    state.status_index[s] = index
                    state.status_value[s] = value
                    state.step[s] = step
                    return
                step += 1
            energy = record_probes(model, control, state, s, step, laser_height, loop_hinge, probes, k)
            if not wp.isfinite(energy):
                state.status[s] = STATUS_NONFINITE_ENERGY
                state.status_step[s] = step
                state.status_index[s] = -1
                state.status_value[s] = energy
                state.step[s] = step
                return
            output = first_output + k
            if output >= 0 and output % probes_per_frame == 0 and frames.shape[0] > 0:
                f = output / probes_per_frame - first_frame
                for i in range(model.n_nodes):
                    frames[f, i, s] = state.position[i, s]
        state.step[s] = step

    @wp.kernel
    def initialise_hysteresis(model: StripModel, state: StripState):
        """Start every hinge fresh at its current curvature: rising branch, no offset."""
        s = wp.tid()
        first = model.n_clamped - 2
        for j in range(first + 1, model.n_nodes - 1):
            h = j - first - 1
            e1 = state.position[j, s] - state.position[j - 1, s]
            e2 = state.position[j + 1, s] - state.position[j, s]
            curvature, chord = signed_curvature(e1, e2, wp.length(e1), wp.length(e2))
            state.branch[h, s] = one
            state.previous_curvature[h, s] = curvature
            state.loop_centre[h, s] = loop_centre_through(
                curvature, zero, one, model.hysteresis_d1[s], model.hysteresis_alpha[s],
                model.hysteresis_k0[s], model.hysteresis_m0[s],
            )

    @wp.kernel
    def moment_along_path(
        curvature_path: wp.array2d(dtype=scalar),
        elastic: wp.array(dtype=scalar),
        d1: wp.array(dtype=scalar),
        alpha: wp.array(dtype=scalar),
        k0: wp.array(dtype=scalar),
        m0: wp.array(dtype=scalar),
        moment: wp.array2d(dtype=scalar),
        work: wp.array(dtype=scalar),
    ):
        """Moment per width M along prescribed curvature paths ``[sample, hinge]``.

        Uses exactly the hinge logic of the strip kernel; ``work`` accumulates
        Σ M_n (K_{n+1} − K_n), the bending work per width with the strip kernel's
        left-point rule.
        """
        s = wp.tid()
        k_start = curvature_path[0, s]
        b = one
        c = loop_centre_through(k_start, zero, one, d1[s], alpha[s], k0[s], m0[s])
        previous = k_start
        w = zero
        for n in range(curvature_path.shape[0]):
            k = curvature_path[n, s]
            b, c = follow_hysteresis(k, previous, b, c, d1[s], alpha[s], k0[s], m0[s])
            m = elastic[s] * k + hysteretic_offset(k - c, b, d1[s], alpha[s], k0[s], m0[s])
            moment[n, s] = m
            if n + 1 < curvature_path.shape[0]:
                w = w + m * (curvature_path[n + 1, s] - k)
            previous = k
        work[s] = w

    return KernelSet(
        scalar=scalar,
        vec2=vec2,
        vec4=vec4,
        vec5=vec5,
        StripModel=StripModel,
        StripControl=StripControl,
        StripState=StripState,
        advance=advance,
        initialise_hysteresis=initialise_hysteresis,
        moment_along_path=moment_along_path,
    )
