"""The fused sheet kernel: every sheet of a batch through many substeps in one launch
(docs/model.md §17).

One GPU thread (or CPU task) advances one sheet: its internal forces
(:mod:`.sheet_forces`), the node update of its scheme (:mod:`.integrators`, symplectic
Euler by default) for every free node under those forces, damping, gravity and the
model's force terms, the clamp's rigid motion in 3D, the work done (the energy budget of §10),
and the probes, markers and frames at each output step.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

from . import drives, force_terms, fused, integrators, sheet_forces, sheet_structs, tensile
from .probe_set import STORED, WORK_AGAINST, WORK_BY, Probe, ProbeSet
from .status import STATUS_OK
from .types import precision

wp.set_module_options({"enable_backward": False})

SHEET_PROBES = ProbeSet(
    (
        Probe("clamp_angle", "rad"),
        Probe("clamp_displacement", "m"),
        Probe("kinetic", "J", STORED),
        Probe("gravitational", "J", STORED),
        Probe("tensile", "J", STORED),
        Probe("elastic_work", "J (against bending D K and shear G φ)", WORK_AGAINST),
        Probe("hysteresis_work", "J (against the laws' hysteretic parts)", WORK_AGAINST),
        Probe("damping_work", "J", WORK_AGAINST),
        Probe("drive_work", "J (done by the clamp)", WORK_BY),
        Probe("cell_shear_angle", "rad (the probed cell)"),
        Probe("cell_shear_force", "N/m (shear force per width of the probed cell)"),
        Probe("hinge_curvature", "1/m (the probed hinge)"),
        Probe("hinge_moment", "N·m/m (moment per width of the probed hinge)"),
    )
)
"""What a sheet records at each output sample, in the probe buffer's order, with each
quantity's place in the energy budget; a model's force terms append their channels."""

SHEET_PROBE_FIELDS = SHEET_PROBES.fields
"""Probe quantities of a sheet without force terms, in buffer order."""

SHEET_PROBE_UNITS = SHEET_PROBES.units
"""SI unit of each sheet probe."""

SHEET_PROBE_INDEX = SHEET_PROBES.index
"""Slot of each sheet probe."""


@dataclass(frozen=True)
class SheetKernels:
    """The types and kernels of the sheet for one precision."""

    types: Any
    structs: Any
    SheetProbeSettings: Any
    advance: Any
    initialise_memory: Any
    internal_forces: Any


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = (), scheme: str = "semi_implicit") -> SheetKernels:
    """The sheet's types and kernels for ``scalar``, the model's force ``terms`` and the node
    update of ``scheme`` (kernels/integrators.py)."""
    types = precision(scalar)
    vec3 = types.vec3
    zero = scalar(0.0)
    half = scalar(0.5)
    one = scalar(1.0)
    two = scalar(2.0)
    sheet = sheet_structs.build(scalar, terms)
    SheetModel, SheetState, SheetControl, SheetStepping = (
        sheet.SheetModel,
        sheet.SheetState,
        sheet.SheetControl,
        sheet.SheetStepping,
    )
    law, tally = sheet.law, sheet.tally
    piecewise_polynomial = drives.build(scalar).piecewise_polynomial
    forces = sheet_forces.build(scalar, terms)
    accumulate_sheet_forces, shear_angle = forces.accumulate_sheet_forces, forces.shear_angle
    ghosts_seen, ghosts_back, weight_of = forces.ghosts_seen, forces.ghosts_back, forces.weight_of
    hinge_geometry, hinge_curvature, turning_angle = forces.hinge_geometry, forces.hinge_curvature, forces.turning_angle
    cell_corners, cell_twist = forces.cell_corners, forces.cell_twist
    tensile_energy = tensile.build(scalar).energy_per_width
    slot = SHEET_PROBE_INDEX
    probe_set = SHEET_PROBES.with_terms(terms)
    record_work = fused.tally_recorder(scalar, tally, probe_set.channel_slots, probe_set.channel_signs)
    work_on = fused.law_work(
        SheetState, vec3, tally, SHEET_PROBES.channel("elastic_work"), SHEET_PROBES.channel("hysteresis_work")
    )
    damping_work = fused.channel(scalar, tally, SHEET_PROBES.channel("damping_work"))
    drive_work = fused.channel(scalar, tally, SHEET_PROBES.channel("drive_work"))
    internal_force = fused.internal_forces(SheetState)
    applied = force_terms.build(terms, scalar, vec3, tally, sheet_structs.SHEET_CHANNELS)
    stepping_types = integrators.build(scalar, 3)
    update_node, kick_mass = stepping_types.schemes[scheme], stepping_types.kick_mass[scheme]

    @wp.struct
    class SheetProbeSettings:
        """Where the recorder looks: the probed cell and hinge, the markers, the frame stride."""

        probe_cell: int
        probe_hinge: int
        markers: wp.array(dtype=int)  # nodes whose positions are recorded at every sample
        marker_positions: wp.array3d(dtype=vec3)  # [sample of the launch, marker, sheet], m
        probes_per_frame: int

    @wp.func
    def clamp_pose(control: SheetControl, s: int, t: scalar):
        theta, rate = piecewise_polynomial(
            control.rotation_start,
            control.rotation_end,
            control.rotation_coefficients,
            control.rotation_segments[s],
            s,
            t,
        )
        d, d_rate = piecewise_polynomial(
            control.translation_start,
            control.translation_end,
            control.translation_coefficients,
            control.translation_segments[s],
            s,
            t,
        )
        return theta, rate, d, d_rate

    @wp.func
    def rotated(v: vec3, axis: vec3, c: scalar, sn: scalar):
        # Rodrigues: about a unit axis, by the angle whose cosine and sine are c, sn.
        return v * c + wp.cross(axis, v) * sn + axis * (wp.dot(axis, v) * (one - c))

    @wp.func
    def clamped_position(model: SheetModel, control: SheetControl, s: int, i: int, theta: scalar, d: scalar):
        rest = model.rest_position[i, s]
        if theta == zero and d == zero:
            return rest  # a clamp at rest sits exactly on its rest positions
        centre = control.centre[s]
        arm = rotated(rest - centre, control.axis[s], wp.cos(theta), wp.sin(theta))
        return centre + arm + d * control.direction[s]

    @wp.func
    def turned_normal(model: SheetModel, control: SheetControl, s: int, theta: scalar):
        # the sheet's rest normal as the clamp at angle θ has turned it
        if theta == zero:
            return model.rest_normal
        return rotated(model.rest_normal, control.axis[s], wp.cos(theta), wp.sin(theta))

    @wp.func
    def place_ghosts(model: SheetModel, control: SheetControl, state: SheetState, s: int, theta: scalar, d: scalar):
        # each held ghost's offset from its clamp place for the force pass (kernels/sheet_forces.py
        # ghosts_seen), from its master's displacement from the master's clamp place at the
        # pose (θ, d): along the rest normal as the clamp has turned it r² times the master's
        # (the bending's ξ²), in the plane −r times it (the membrane's ξ, which changes sign
        # at the edge; docs/model.md §17.2)
        normal = turned_normal(model, control, s, theta)
        state.clamp_normal[s] = normal
        for k in range(model.slaved_ghosts, model.ghost_nodes.shape[0]):
            m = model.ghost_masters[k]
            away = state.position[m, s] - clamped_position(model, control, s, m, theta, d)
            r = model.ghost_ratios[k]
            out = wp.dot(normal, away)
            state.ghost_offset[k, s] = (r * r * out) * normal - r * (away - out * normal)

    @wp.func
    def follow_masters(model: SheetModel, control: SheetControl, state: SheetState, s: int, theta: scalar, d: scalar):
        # each slaved node's coordinate along the normal: its clamp place's (the pose θ, d)
        # plus r² times its master's displacement from the master's clamp place, as near a
        # clamp the fabric leaves its plane as ξ² (docs/model.md §17.2). In the plane it moves
        # as its own forces take it; along the normal it has no inertia, and its velocity
        # keeps only its part in the plane (so that the normal's turn feeds it nothing).
        normal = turned_normal(model, control, s, theta)
        for k in range(model.slaved_ghosts):
            g = model.ghost_nodes[k]
            m = model.ghost_masters[k]
            weight = model.ghost_ratios[k] * model.ghost_ratios[k]
            away = state.position[m, s] - clamped_position(model, control, s, m, theta, d)
            held = clamped_position(model, control, s, g, theta, d)
            out = wp.dot(normal, held - state.position[g, s]) + weight * wp.dot(normal, away)
            state.position[g, s] = state.position[g, s] + out * normal
            v = state.velocity[g, s]
            state.velocity[g, s] = v - wp.dot(normal, v) * normal

    @wp.func
    def advance_free_nodes(
        model: SheetModel, stepping: SheetStepping, state: SheetState, s: int, step: int, gamma: scalar, work: tally
    ):
        # every free node under its internal forces, damping, gravity and the model's force terms
        # (a slaved node in the plane only: its master moves it along the normal, §17.2)
        dt = stepping.dt
        g = vec3(zero, -model.gravity, zero)
        rho = model.density[s]
        normal = vec3()
        if model.slaved_ghosts > 0:
            normal = state.clamp_normal[s]
        for i in range(model.n_nodes):
            if model.clamped[i] != 0:
                continue
            m = rho * model.node_area[i]
            x = state.position[i, s]
            v = state.velocity[i, s]
            f_damp = -gamma * m * v
            slaved = False
            if model.slaved_ghosts > 0:
                slaved = model.slaved[i] != 0
            if slaved:
                f_damp = f_damp - wp.dot(normal, f_damp) * normal
            f = internal_force(state, i, s) + f_damp + m * g
            if wp.static(applied.present):
                f = f + applied.force(x, v, m)
            x_new, v_new = update_node(x, v, f, kick_mass(m, step == 0), dt)  # every node starts at step 0
            sweep = (v + v_new) * (half * dt)
            if slaved:
                sweep = sweep - wp.dot(normal, sweep) * normal
            work = work + work_on(state, i, s, sweep) + damping_work(-wp.dot(f_damp, sweep))
            if wp.static(applied.present):
                work = work + applied.work(x, v, m, sweep)
            state.position[i, s] = x_new
            state.velocity[i, s] = v_new
        return work

    @wp.func
    def ghosts_driven(
        model: SheetModel,
        control: SheetControl,
        state: SheetState,
        s: int,
        theta: scalar,
        d: scalar,
        theta_before: scalar,
        d_before: scalar,
        work: tally,
    ):
        # A ghost's coordinate along the normal is its clamp place's plus r² times its
        # master's displacement from the master's clamp place, a: its master's motion moves
        # it there, whose forces hold its own (kernels/sheet_forces.py ghosts_held), and the
        # clamp moves it, through the clamp places and the normal's turn: that part of its
        # forces' work is the drive's (a held ghost's own clamp place's sweep is move_clamp's;
        # a slaved one moves in the plane as its own forces take it)
        normal = state.clamp_normal[s]
        turn = (turned_normal(model, control, s, theta) - turned_normal(model, control, s, theta_before)) * half
        for k in range(model.ghost_nodes.shape[0]):
            g = model.ghost_nodes[k]
            m = model.ghost_masters[k]
            r = model.ghost_ratios[k]
            master_held = clamped_position(model, control, s, m, theta, d)
            away = state.position[m, s] - master_held
            held_sweep = (master_held - clamped_position(model, control, s, m, theta_before, d_before)) * half
            moved = state.force_elastic[g, s] + state.force_hysteretic[g, s]
            master_part = wp.dot(turn, away) - wp.dot(normal, held_sweep)
            if k < model.slaved_ghosts:  # along the normal only: in the plane it moves as its forces take it
                held = clamped_position(model, control, s, g, theta, d)
                own_sweep = (held - clamped_position(model, control, s, g, theta_before, d_before)) * half
                out = wp.dot(normal, own_sweep) - wp.dot(turn, state.position[g, s] - held) + r * r * master_part
                clamp_moved = out * normal
                moved = moved + state.force_tensile[g, s] + weight_of(model, s, g)
            else:  # out of the plane r² times the master's, in it −r times: both as the clamp moves them
                swept = turn * wp.dot(normal, away) + normal * master_part
                clamp_moved = (r * r) * swept + r * (held_sweep + swept)
                moved = moved + state.force_tensile[g, s]
            work = work + work_on(state, g, s, clamp_moved) + drive_work(-wp.dot(moved, clamp_moved))
        return work

    @wp.func
    def move_clamp(
        model: SheetModel,
        control: SheetControl,
        stepping: SheetStepping,
        state: SheetState,
        s: int,
        t_next: scalar,
        work: tally,
    ):
        theta, rate, d, d_rate = clamp_pose(control, s, t_next)
        theta_before, _rate, d_before, _d_rate = clamp_pose(control, s, t_next - two * stepping.dt)
        axis = control.axis[s]
        direction = control.direction[s]
        for i in range(model.n_nodes):
            if model.clamped[i] == 0:
                continue
            x_new = clamped_position(model, control, s, i, theta, d)
            sweep = (x_new - clamped_position(model, control, s, i, theta_before, d_before)) * half
            f_int = internal_force(state, i, s)
            work = work + work_on(state, i, s, sweep) + drive_work(-wp.dot(f_int, sweep))
            arm = x_new - control.centre[s] - d * direction
            state.position[i, s] = x_new
            state.velocity[i, s] = rate * wp.cross(axis, arm) + d_rate * direction
        if model.ghost_nodes.shape[0] > 0:
            work = ghosts_driven(model, control, state, s, theta, d, theta_before, d_before, work)
            follow_masters(model, control, state, s, theta, d)
        return work

    @wp.func
    def substep(
        model: SheetModel, control: SheetControl, stepping: SheetStepping, state: SheetState, s: int, step: int
    ):
        if model.ghost_nodes.shape[0] > 0:
            theta, _rate, d, _d_rate = clamp_pose(control, s, scalar(step - stepping.release_step) * stepping.dt)
            place_ghosts(model, control, state, s, theta, d)
        code, index, value = accumulate_sheet_forces(model, stepping, state, s)
        if code != STATUS_OK:
            return code, index, value
        t_next = scalar(step + 1 - stepping.release_step) * stepping.dt
        gamma = model.damping[s]
        if step < stepping.release_step:
            gamma = control.settle_damping[s]
        work = advance_free_nodes(model, stepping, state, s, step, gamma, state.work[s])
        work = move_clamp(model, control, stepping, state, s, t_next, work)
        if step + 1 == stepping.release_step:
            work = tally()  # the energy budget is reported from the release on
        state.work[s] = work
        return STATUS_OK, 0, zero

    @wp.func
    def record_probes(
        model: SheetModel,
        control: SheetControl,
        stepping: SheetStepping,
        state: SheetState,
        settings: SheetProbeSettings,
        s: int,
        step: int,
        probes: wp.array3d(dtype=scalar),
        k: int,
    ):
        # Writes sample k of sheet s; returns the energy budget's state-and-work sum.
        t = scalar(step - stepping.release_step) * stepping.dt
        theta, _rate, d, _d_rate = clamp_pose(control, s, t)
        ghosts = model.ghost_nodes.shape[0] > 0
        if ghosts:  # the normal at this pose, as the next step's follow_masters takes it
            place_ghosts(model, control, state, s, theta, d)
        rho = model.density[s]
        kinetic = zero
        gravitational = zero
        for i in range(model.n_nodes):
            if model.clamped[i] == 0:
                m = rho * model.node_area[i]
                v = state.velocity[i, s]
                if model.slaved_ghosts > 0 and model.slaved[i] != 0:  # along the normal its master moves it
                    v = v - wp.dot(state.clamp_normal[s], v) * state.clamp_normal[s]
                kinetic = kinetic + half * m * wp.dot(v, v)
                gravitational = gravitational + m * model.gravity * state.position[i, s][1]
        if ghosts:  # the segments' energy with each held ghost where their forces saw it
            ghosts_seen(model, state, s)
        stretch = zero
        for e in range(model.edge_nodes.shape[0]):
            ends = model.edge_nodes[e]
            family = model.edge_family[e]
            l0 = model.spacing[family]
            strain = (wp.length(state.position[ends[1], s] - state.position[ends[0], s]) - l0) / l0
            energy = tensile_energy(strain, model.tensile[family, s]) * model.edge_width[e] * l0
            if strain < zero:
                energy = energy * model.compression
            stretch = stretch + energy
        if ghosts:
            ghosts_back(model, state, s)
        probes[k, wp.static(slot["clamp_angle"]), s] = theta
        probes[k, wp.static(slot["clamp_displacement"]), s] = d
        probes[k, wp.static(slot["kinetic"]), s] = kinetic
        probes[k, wp.static(slot["gravitational"]), s] = gravitational
        probes[k, wp.static(slot["tensile"]), s] = stretch
        # a sheet without cells or hinges (a single line) has nothing there to probe
        probes[k, wp.static(slot["cell_shear_angle"]), s] = scalar(wp.nan)
        probes[k, wp.static(slot["cell_shear_force"]), s] = scalar(wp.nan)
        probes[k, wp.static(slot["hinge_curvature"]), s] = scalar(wp.nan)
        probes[k, wp.static(slot["hinge_moment"]), s] = scalar(wp.nan)
        if model.cell_nodes.shape[0] > 0:
            memory = state.cell[settings.probe_cell, s]
            p = model.shear[s]
            phi = law.last_curvature(memory)
            probes[k, wp.static(slot["cell_shear_angle"]), s] = phi
            probes[k, wp.static(slot["cell_shear_force"]), s] = law.elastic_moment(phi, p) + law.hysteretic_moment(
                phi, memory, p
            )
        if model.hinge_nodes.shape[0] > 0:
            memory = state.hinge[settings.probe_hinge, s]
            p = model.bending[model.hinge_family[settings.probe_hinge], s]
            curvature = law.last_curvature(memory)
            probes[k, wp.static(slot["hinge_curvature"]), s] = curvature
            probes[k, wp.static(slot["hinge_moment"]), s] = law.elastic_moment(curvature, p) + law.hysteretic_moment(
                curvature, memory, p
            )
        for j in range(settings.markers.shape[0]):
            settings.marker_positions[k, j, s] = state.position[settings.markers[j], s]
        return record_work(probes, k, s, state.work[s], kinetic + gravitational + stretch)

    stop = fused.stopper(SheetState, scalar)
    advance = fused.build_advance(
        SheetModel, SheetControl, SheetStepping, SheetState, SheetProbeSettings, scalar, vec3, substep, record_probes
    )

    @wp.kernel(module="unique", enable_backward=False)
    def initialise_memory(model: SheetModel, control: SheetControl, state: SheetState):
        """Start every hinge and cell fresh at its current curvature, shear angle and twist
        (ghosts at the clamp's rest pose, where a run starts)."""
        s = wp.tid()
        follow_masters(model, control, state, s, zero, zero)
        place_ghosts(model, control, state, s, zero, zero)
        ghosts_seen(model, state, s)
        for h in range(model.hinge_nodes.shape[0]):
            e1, e2, u = hinge_geometry(model, state, h, s)
            sine, _cosine, inverse_p1, inverse_p2, chord = turning_angle(e1, e2, u / wp.length(u))
            curvature = hinge_curvature(model, h, sine, inverse_p1, inverse_p2, chord)
            state.hinge[h, s] = law.fresh_memory(
                curvature, model.bending[model.hinge_family[h], s], state.hinge_history, h, s
            )
        for c in range(model.cell_nodes.shape[0]):
            w, f, d = cell_corners(model, state, c, s)
            phi, _sn, unit, _d_w, _d_f = shear_angle(w, f)
            scale = model.cell_scale[c]
            state.cell[c, s] = law.fresh_memory(scale * phi, model.shear[s], state.cell_history, c, s)
            kappa = scale * cell_twist(model, d, unit)
            state.twist[c, s] = law.fresh_memory(kappa, model.twist[s], state.twist_history, c, s)
        for k in range(model.slaved_ghosts, model.ghost_nodes.shape[0]):
            state.position[model.ghost_nodes[k], s] = state.ghost_held[k, s]

    @wp.kernel(module="unique", enable_backward=False)
    def internal_forces(model: SheetModel, control: SheetControl, stepping: SheetStepping, state: SheetState):
        """The internal forces at the current positions (the laws follow to them), without a
        step: what a static check or a test reads from ``force_*``."""
        s = wp.tid()
        theta, _rate, d, _d_rate = clamp_pose(control, s, scalar(state.step[s] - stepping.release_step) * stepping.dt)
        place_ghosts(model, control, state, s, theta, d)
        code, index, value = accumulate_sheet_forces(model, stepping, state, s)
        if code != STATUS_OK:
            stop(state, s, code, state.step[s], index, value)

    return SheetKernels(
        types=types,
        structs=sheet,
        SheetProbeSettings=SheetProbeSettings,
        advance=advance,
        initialise_memory=initialise_memory,
        internal_forces=internal_forces,
    )
