"""The fused strip kernel: every strip of a batch through many substeps in one launch
(docs/model.md).

One GPU thread (or CPU task) advances one strip: internal forces (:mod:`.forces`),
the node update of the chosen scheme (:mod:`.integrators`), the drives
(:mod:`.drives`), the work done (§10), and the probes and frames at each output step
(:mod:`.probes`). A batch therefore costs one launch per output chunk, not one per
substep. Kernels are generated per (precision, scheme) by :func:`build`; every strip
runs its own bending law (kernels/laws.py).
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

from . import drives, force_terms, forces, fused, geometry, implicit_stretching, integrators, probes, structs
from .status import STATUS_OK
from .types import precision

# Forward simulation only: no adjoint code to generate, compile and carry. Each kernel
# is a Warp module of its own (module="unique"): its compiled binary is keyed by its own
# code alone, so a process that builds another precision or scheme later recompiles
# nothing it already has, and sweep workers load what the driver compiled.
wp.set_module_options({"enable_backward": False})


@dataclass(frozen=True)
class StripKernels:
    """The types and the fused ``advance`` kernel of one (precision, scheme)."""

    types: Any
    StripModel: Any
    StripControl: Any
    Stepping: Any
    StripState: Any
    ProbeSettings: Any
    law: Any
    advance: Any


@dataclass(frozen=True)
class HingeKernels:
    """The kernel that starts every hinge fresh (its law's ``fresh_memory``)."""

    initialise_hinges: Any


@functools.cache
def build(scalar: Any, scheme: str, terms: tuple[Any, ...] = (), lanes: int = 1) -> StripKernels:
    """Types and the ``advance`` kernel of one configuration (a model's force ``terms``
    included: kernels/force_terms.py), its force pass following ``lanes`` hinges together
    (:func:`.exp_lanes.lane_width` of the device)."""
    types = precision(scalar)
    vec2, mat22 = types.vec2, types.mat22
    zero = scalar(0.0)
    half = scalar(0.5)
    strip = structs.build(scalar, terms)
    StripModel, StripState, law, tally = strip.StripModel, strip.StripState, strip.law, strip.tally
    drive = drives.build(scalar)
    StripControl, clamp_angle, held_free_end = drive.StripControl, drive.clamp_angle, drive.held_free_end
    starts_moving = drive.starts_moving
    stepping_types = integrators.build(scalar)
    Stepping = stepping_types.Stepping
    update_node, kick_mass = stepping_types.schemes[scheme], stepping_types.kick_mass[scheme]
    accumulate_internal_forces = forces.build(scalar, terms, lanes).accumulate_internal_forces
    recorder = probes.build(scalar, terms)
    ProbeSettings, record_probes = recorder.ProbeSettings, recorder.record_probes
    perp = geometry.build(scalar).perp
    implicit = scheme in integrators.IMPLICIT_STRETCHING  # resolved when the kernel is generated (wp.static)
    stretching_corrections = implicit_stretching.build(
        scalar, terms, trapezoidal=scheme == "imex_trapezoidal"
    ).stretching_corrections
    channel = probes.STRIP_PROBES.channel
    work_on = fused.law_work(StripState, vec2, tally, channel("bending_elastic_work"), channel("hysteresis_work"))
    damping_work = fused.channel(scalar, tally, channel("damping_work"))
    drive_work = fused.channel(scalar, tally, channel("drive_work"))
    laws_force = fused.internal_forces(StripState)
    applied = force_terms.build(terms, scalar, vec2, tally, structs.STRIP_CHANNELS)

    @wp.func
    def internal_force(state: StripState, i: int, s: int):
        f = laws_force(state, i, s)
        if wp.static(implicit):
            f = f + state.correction[i, s]
        return f

    @wp.func
    def carry_held_end(
        model: StripModel, control: StripControl, stepping: Stepping, state: StripState, s: int, step: int, work: tally
    ):
        # The held free end moves as prescribed; the internal forces do work on it.
        i = model.n_nodes - 1
        x_new, v_new = held_free_end(
            control,
            model.rest_position[model.n_clamped - 1, s],
            model.rest_position[i, s],
            s,
            step + 1,
            stepping.move_steps,
            stepping.dt,
        )
        sweep = (state.velocity[i, s] + v_new) * (half * stepping.dt)
        f_int = internal_force(state, i, s)
        work = work + work_on(state, i, s, sweep) + drive_work(-wp.dot(f_int, sweep))
        state.position[i, s] = x_new
        state.velocity[i, s] = v_new
        return work

    @wp.func
    def advance_free_nodes(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        s: int,
        step: int,
        last: int,
        gamma: scalar,
        work: tally,
    ):
        # Nodes below the clamp, up to ``last``, by the scheme's node update under their
        # internal forces, damping, gravity and the model's force terms; the free end
        # carries half a node's mass.
        n = model.n_nodes
        dt = stepping.dt
        g = vec2(zero, -model.gravity)
        m_node = model.node_mass[s]
        for i in range(model.n_clamped, last + 1):
            x = state.position[i, s]
            m = m_node
            if i == n - 1:
                m = half * m_node
            v = state.velocity[i, s]
            f_damp = -gamma * m * v
            f = laws_force(state, i, s) + f_damp + m * g
            if wp.static(applied.present):
                f = f + applied.force(x, v, m)
            if wp.static(implicit):
                f = f + state.correction[i, s]
            x_new, v_new = update_node(
                x, v, f, kick_mass(m, starts_moving(control, s, i, n - 1, step, stepping.release_step)), dt
            )
            sweep = (v + v_new) * (half * dt)
            work = work + work_on(state, i, s, sweep) + damping_work(-wp.dot(f_damp, sweep))
            if wp.static(applied.present):
                work = work + applied.work(x, v, m, sweep)
            state.position[i, s] = x_new
            state.velocity[i, s] = v_new
        return work

    @wp.func
    def move_clamp(
        model: StripModel,
        control: StripControl,
        stepping: Stepping,
        state: StripState,
        s: int,
        t_next: scalar,
        work: tally,
    ):
        # Clamp nodes follow the rigid rotation; only the two above the edge carry forces.
        dt = stepping.dt
        theta, rate = clamp_angle(control, s, t_next)
        centre = control.rotation_centre[s]
        ca = wp.cos(theta)  # once per substep, not per clamp node
        sa = wp.sin(theta)
        rotation = mat22(ca, -sa, sa, ca)
        # The work of the forces at x_n on the clamp nodes uses their centred displacement
        # (x_{n+1} - x_{n-1}) / 2, as the free nodes' (v_n + v_{n+1}) dt / 2 is: the clamp's
        # positions are analytic, so x_{n-1} is its pose one step back (docs/model.md §10.3).
        theta_before, _rate_before = clamp_angle(control, s, t_next - scalar(2.0) * dt)
        cb = wp.cos(theta_before)
        sb = wp.sin(theta_before)
        rotation_before = mat22(cb, -sb, sb, cb)
        for i in range(model.n_clamped):
            arm = rotation * (model.rest_position[i, s] - centre)
            v_new = rate * perp(arm)
            if i >= model.n_clamped - 2:
                before = rotation_before * (model.rest_position[i, s] - centre)
                sweep = (arm - before) * half
                f_int = laws_force(state, i, s)
                if wp.static(implicit) and i == model.n_clamped - 1:
                    f_int = f_int + state.correction[i, s]  # the implicit tension on the clamp-edge node
                work = work + work_on(state, i, s, sweep) + drive_work(-wp.dot(f_int, sweep))
            if theta == zero:
                # A clamp at rest sits exactly on its rest positions, wherever its rotation
                # centre is: centre + (X - centre) would move it by rounding.
                state.position[i, s] = model.rest_position[i, s]
            else:
                state.position[i, s] = centre + arm
            state.velocity[i, s] = v_new
        return work

    @wp.func
    def substep(model: StripModel, control: StripControl, stepping: Stepping, state: StripState, s: int, step: int):
        # The passes of one step: internal forces at x_n, the implicit tension correction
        # (imex), the free nodes, the held end, the clamp, then the work tally.
        code, index, value = accumulate_internal_forces(model, stepping, state, s)
        if code != STATUS_OK:
            return code, index, value
        n = model.n_nodes
        t_next = scalar(step + 1 - stepping.release_step) * stepping.dt
        held = step < stepping.release_step
        gamma = model.damping[s]
        if held:
            gamma = control.settle_damping[s]
        holding = held and control.hold_free_end[s] != 0  # the free end prescribed, not free to settle
        if wp.static(implicit):
            stretching_corrections(model, control, stepping, state, s, step, holding, gamma, t_next)
        work = state.work[s]
        if holding:
            work = advance_free_nodes(model, control, stepping, state, s, step, n - 2, gamma, work)
            work = carry_held_end(model, control, stepping, state, s, step, work)
        else:
            work = advance_free_nodes(model, control, stepping, state, s, step, n - 1, gamma, work)
        work = move_clamp(model, control, stepping, state, s, t_next, work)
        if step + 1 == stepping.release_step:
            work = tally()  # the energy budget is reported from the release on
        state.work[s] = work
        return STATUS_OK, 0, zero

    advance = fused.build_advance(
        StripModel, StripControl, Stepping, StripState, ProbeSettings, scalar, vec2, substep, record_probes
    )

    return StripKernels(
        types=types,
        StripModel=StripModel,
        StripControl=StripControl,
        Stepping=Stepping,
        StripState=StripState,
        ProbeSettings=ProbeSettings,
        law=law,
        advance=advance,
    )


@functools.cache
def hinge_kernels(scalar: Any, terms: tuple[Any, ...] = ()) -> HingeKernels:
    """The ``initialise_hinges`` kernel for ``scalar`` (the structs of a model with ``terms``)."""
    strip = structs.build(scalar, terms)
    StripModel, StripState, law = strip.StripModel, strip.StripState, strip.law
    signed_curvature = geometry.build(scalar).signed_curvature
    one = scalar(1.0)

    @wp.kernel(module="unique", enable_backward=False)
    def initialise_hinges(model: StripModel, state: StripState):
        """Start every hinge fresh at its current curvature relative to its natural one (no
        hysteretic moment, loading up)."""
        s = wp.tid()
        first = model.n_clamped - 2
        p = model.bending[s]
        for j in range(first + 1, model.n_nodes - 1):
            e1 = state.position[j, s] - state.position[j - 1, s]
            e2 = state.position[j + 1, s] - state.position[j, s]
            curvature, chord = signed_curvature(e1, e2, one / wp.length(e1), one / wp.length(e2))
            if j == first + 1:
                curvature = curvature * model.edge_curvature_scale[s]  # as the force pass sees it
            curvature = curvature - model.rest_curvature[j - first - 1, s]
            state.hinge[j - first - 1, s] = law.fresh_memory(curvature, p, state.history, j - first - 1, s)

    return HingeKernels(initialise_hinges=initialise_hinges)
