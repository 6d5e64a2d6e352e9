"""The fused sheet kernel: every sheet of a batch through many substeps in one launch
(docs/model.md §17).

One GPU thread (or CPU task) advances one sheet: its internal forces
(:mod:`.sheet_forces`), symplectic Euler for every free node under those forces, damping
and gravity, the clamp's rigid motion in 3D, the work done (the energy budget of §10),
and the probes, markers and frames at each output step.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

from . import drives, sheet_forces, sheet_structs, tensile
from .status import STATUS_NONFINITE_ENERGY, STATUS_OK
from .types import precision

wp.set_module_options({"enable_backward": False})

SHEET_PROBE_FIELDS = (
    "clamp_angle",
    "clamp_displacement",
    "kinetic",
    "gravitational",
    "tensile",
    "elastic_work",
    "hysteresis_work",
    "damping_work",
    "drive_work",
    "cell_shear_angle",
    "cell_shear_force",
    "hinge_curvature",
    "hinge_moment",
)
"""What is recorded of every sheet at each output sample, in the probe buffer's order."""

SHEET_PROBE_UNITS = {
    "clamp_angle": "rad",
    "clamp_displacement": "m",
    "kinetic": "J",
    "gravitational": "J",
    "tensile": "J",
    "elastic_work": "J (against bending D K and shear G φ)",
    "hysteresis_work": "J (against the laws' hysteretic parts)",
    "damping_work": "J",
    "drive_work": "J (done by the clamp)",
    "cell_shear_angle": "rad (the probed cell)",
    "cell_shear_force": "N/m (shear force per width of the probed cell)",
    "hinge_curvature": "1/m (the probed hinge)",
    "hinge_moment": "N·m/m (moment per width of the probed hinge)",
}
"""SI unit of each sheet probe."""

SHEET_PROBE_INDEX = {name: i for i, name in enumerate(SHEET_PROBE_FIELDS)}


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
def build(scalar: Any) -> SheetKernels:
    """The sheet's types and kernels for ``scalar``."""
    types = precision(scalar)
    vec3, vec4 = types.vec3, types.vec4
    zero = scalar(0.0)
    half = scalar(0.5)
    one = scalar(1.0)
    two = scalar(2.0)
    sheet = sheet_structs.build(scalar)
    SheetModel, SheetState, SheetControl, SheetStepping = (
        sheet.SheetModel,
        sheet.SheetState,
        sheet.SheetControl,
        sheet.SheetStepping,
    )
    law = sheet.law
    piecewise_polynomial = drives.build(scalar).piecewise_polynomial
    forces = sheet_forces.build(scalar)
    accumulate_sheet_forces, shear_angle = forces.accumulate_sheet_forces, forces.shear_angle
    hinge_geometry, hinge_curvature, cell_sides = forces.hinge_geometry, forces.hinge_curvature, forces.cell_sides
    tensile_energy = tensile.build(scalar).energy_per_width
    slot = SHEET_PROBE_INDEX

    @wp.struct
    class SheetProbeSettings:
        """Where the recorder looks: the probed cell and hinge, the markers, the frame stride."""

        probe_cell: int
        probe_hinge: int
        markers: wp.array(dtype=int)  # nodes whose positions are recorded at every sample
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
    def work_on(state: SheetState, i: int, s: int, displacement: vec3):
        # Work done against the laws' forces at node i over the centred displacement
        # (x_{n+1} − x_{n−1}) / 2, as the strip tallies it (§10.3).
        return vec4(
            -wp.dot(state.force_elastic[i, s], displacement),
            -wp.dot(state.force_hysteretic[i, s], displacement),
            zero,
            zero,
        )

    @wp.func
    def advance_free_nodes(
        model: SheetModel, stepping: SheetStepping, state: SheetState, s: int, gamma: scalar, work: vec4
    ):
        dt = stepping.dt
        g = vec3(zero, -model.gravity, zero)
        rho = model.density[s]
        for i in range(model.n_nodes):
            if model.clamped[i] != 0:
                continue
            m = rho * model.node_area[i]
            v = state.velocity[i, s]
            f_damp = -gamma * m * v
            f = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
            f = f + f_damp + m * g
            v_new = v + f * (dt / m)
            sweep = (v + v_new) * (half * dt)
            work = work + work_on(state, i, s, sweep) + vec4(zero, zero, -wp.dot(f_damp, sweep), zero)
            state.position[i, s] = state.position[i, s] + v_new * dt
            state.velocity[i, s] = v_new
        return work

    @wp.func
    def move_clamp(
        model: SheetModel,
        control: SheetControl,
        stepping: SheetStepping,
        state: SheetState,
        s: int,
        t_next: scalar,
        work: vec4,
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
            f_int = state.force_tensile[i, s] + state.force_elastic[i, s] + state.force_hysteretic[i, s]
            work = work + work_on(state, i, s, sweep) + vec4(zero, zero, zero, -wp.dot(f_int, sweep))
            arm = x_new - control.centre[s] - d * direction
            state.position[i, s] = x_new
            state.velocity[i, s] = rate * wp.cross(axis, arm) + d_rate * direction
        return work

    @wp.func
    def substep(
        model: SheetModel, control: SheetControl, stepping: SheetStepping, state: SheetState, s: int, step: int
    ):
        code, index, value = accumulate_sheet_forces(model, stepping, state, s)
        if code != STATUS_OK:
            return code, index, value
        t_next = scalar(step + 1 - stepping.release_step) * stepping.dt
        gamma = model.damping[s]
        if step < stepping.release_step:
            gamma = control.settle_damping[s]
        work = advance_free_nodes(model, stepping, state, s, gamma, state.work[s])
        work = move_clamp(model, control, stepping, state, s, t_next, work)
        if step + 1 == stepping.release_step:
            work = vec4()  # the energy budget is reported from the release on
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
        markers: wp.array3d(dtype=vec3),
        k: int,
    ):
        # Writes sample k of sheet s; returns the energy budget's state-and-work sum.
        rho = model.density[s]
        kinetic = zero
        gravitational = zero
        for i in range(model.n_nodes):
            if model.clamped[i] == 0:
                m = rho * model.node_area[i]
                v = state.velocity[i, s]
                kinetic = kinetic + half * m * wp.dot(v, v)
                gravitational = gravitational + m * model.gravity * state.position[i, s][1]
        stretch = zero
        for e in range(model.edge_nodes.shape[0]):
            ends = model.edge_nodes[e]
            family = model.edge_family[e]
            l0 = model.spacing[family]
            strain = (wp.length(state.position[ends[1], s] - state.position[ends[0], s]) - l0) / l0
            stretch = stretch + tensile_energy(strain, model.tensile[family, s]) * model.edge_width[e] * l0
        t = scalar(step - stepping.release_step) * stepping.dt
        theta, _rate, d, _d_rate = clamp_pose(control, s, t)
        work = state.work[s]
        probes[k, wp.static(slot["clamp_angle"]), s] = theta
        probes[k, wp.static(slot["clamp_displacement"]), s] = d
        probes[k, wp.static(slot["kinetic"]), s] = kinetic
        probes[k, wp.static(slot["gravitational"]), s] = gravitational
        probes[k, wp.static(slot["tensile"]), s] = stretch
        probes[k, wp.static(slot["elastic_work"]), s] = work[0]
        probes[k, wp.static(slot["hysteresis_work"]), s] = work[1]
        probes[k, wp.static(slot["damping_work"]), s] = work[2]
        probes[k, wp.static(slot["drive_work"]), s] = work[3]
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
            markers[k, j, s] = state.position[settings.markers[j], s]
        return kinetic + gravitational + stretch + work[0] + work[1] + work[2]

    @wp.func
    def stop(state: SheetState, s: int, code: int, step: int, index: int, value: scalar):
        state.status[s] = code
        state.status_step[s] = step
        state.status_index[s] = index
        state.status_value[s] = value
        state.step[s] = step

    @wp.kernel(module="unique", enable_backward=False)
    def advance(
        model: SheetModel,
        control: SheetControl,
        stepping: SheetStepping,
        state: SheetState,
        settings: SheetProbeSettings,
        output_steps: wp.array(dtype=int),
        first_output: int,
        first_frame: int,
        probes: wp.array3d(dtype=scalar),
        markers: wp.array3d(dtype=vec3),
        frames: wp.array3d(dtype=vec3),
        first_sheet: int,
    ):
        """Advance sheets ``first_sheet`` … ``first_sheet + dim − 1`` to each output step in
        turn, recording probes, markers (and frames)."""
        s = first_sheet + wp.tid()
        if state.status[s] != STATUS_OK:
            return
        step = state.step[s]
        for k in range(output_steps.shape[0]):
            while step < output_steps[k]:
                code, index, value = substep(model, control, stepping, state, s, step)
                if code != STATUS_OK:
                    stop(state, s, code, step, index, value)
                    return
                step += 1
            energy = record_probes(model, control, stepping, state, settings, s, step, probes, markers, k)
            if not wp.isfinite(energy):
                stop(state, s, STATUS_NONFINITE_ENERGY, step, -1, energy)
                return
            output = first_output + k
            if output >= 0 and output % settings.probes_per_frame == 0 and frames.shape[0] > 0:
                f = output / settings.probes_per_frame - first_frame
                for i in range(model.n_nodes):
                    frames[f, i, s] = state.position[i, s]
        state.step[s] = step

    @wp.kernel(module="unique", enable_backward=False)
    def initialise_memory(model: SheetModel, state: SheetState):
        """Start every hinge and cell fresh at its current curvature and shear angle."""
        s = wp.tid()
        for h in range(model.hinge_nodes.shape[0]):
            _e1, _e2, _axis, _inverse_u, sine, _cosine, inverse_p1, inverse_p2, chord = hinge_geometry(
                model, state, h, s
            )
            curvature = hinge_curvature(model, h, sine, inverse_p1, inverse_p2, chord)
            state.hinge[h, s] = law.fresh_memory(
                curvature, model.bending[model.hinge_family[h], s], state.hinge_history, h, s
            )
        for c in range(model.cell_nodes.shape[0]):
            w, f = cell_sides(model, state, c, s)
            phi, _sn, _d_w, _d_f = shear_angle(w, f)
            state.cell[c, s] = law.fresh_memory(phi, model.shear[s], state.cell_history, c, s)

    @wp.kernel(module="unique", enable_backward=False)
    def internal_forces(model: SheetModel, stepping: SheetStepping, state: SheetState):
        """The internal forces at the current positions (the laws follow to them), without a
        step: what a static check or a test reads from ``force_*``."""
        s = wp.tid()
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
