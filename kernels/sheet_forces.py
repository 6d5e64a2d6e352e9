"""Internal forces of a woven sheet (docs/model.md §17.2-17.4): the tension of every warp
and weft segment, the bending couple of every hinge along a line, about the sheet's
in-plane axis across it, and the shear couple of every cell.

Each element is a function of its nodes' positions through one generalised coordinate
(strain, turning angle, shear angle); its force on each node is the coordinate's
gradient times the element's generalised force, so every element's forces sum to zero
and, the coordinates being invariant under rigid motion, so do their moments.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

from . import sheet_structs, tensile
from .status import STATUS_CELL_COLLAPSED, STATUS_FOLDED, STATUS_OK, STATUS_STRAIN
from .types import precision


@dataclass(frozen=True)
class SheetForces:
    """The force pass and the elements' coordinates, for one precision."""

    accumulate_sheet_forces: Any
    hinge_geometry: Any
    hinge_curvature: Any
    turning_angle: Any
    cell_corners: Any
    cell_twist: Any
    shear_angle: Any
    ghosts_seen: Any
    ghosts_back: Any
    weight_of: Any


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = ()) -> SheetForces:
    """``accumulate_sheet_forces`` for ``scalar`` (the structs of a model with force ``terms``)."""
    vec3 = precision(scalar).vec3
    zero = scalar(0.0)
    one = scalar(1.0)
    half = scalar(0.5)
    two = scalar(2.0)
    sheet = sheet_structs.build(scalar, terms)
    SheetModel, SheetState, SheetStepping, law = sheet.SheetModel, sheet.SheetState, sheet.SheetStepping, sheet.law
    tension = tensile.build(scalar).force_per_width

    @wp.func
    def add(forces: wp.array2d(dtype=vec3), i: int, s: int, f: vec3):
        forces[i, s] = forces[i, s] + f

    @wp.func
    def turning_angle(e1: vec3, e2: vec3, axis: vec3):
        # The line's two segments projected on the plane normal to the bending axis a:
        # sin, cos of the turning angle there (scaled by |p1||p2|), 1/|p1|, 1/|p2| and the
        # chord |p1 + p2| (docs/model.md §17.4). A line in the plane normal to a (the
        # strip's case) has p = e exactly, and these are the strip's numbers.
        e1a = wp.dot(e1, axis)
        e2a = wp.dot(e2, axis)
        sine = wp.dot(wp.cross(e1, e2), axis)
        cosine = wp.dot(e1, e2) - e1a * e2a
        inverse_p1 = one / wp.sqrt(wp.dot(e1, e1) - e1a * e1a)
        inverse_p2 = one / wp.sqrt(wp.dot(e2, e2) - e2a * e2a)
        chord = wp.length(e1 + e2 - (e1a + e2a) * axis)
        return sine, cosine, inverse_p1, inverse_p2, chord

    @wp.func
    def shear_angle(w: vec3, f: vec3):
        # φ = π/2 − the angle between the cell's mean warp w and mean weft f, the cell's unit
        # normal and φ's gradients with respect to w and f (docs/model.md §17.5)
        c = wp.dot(w, f)
        n = wp.cross(w, f)
        sn = wp.length(n)
        phi = wp.atan2(c, sn)
        inverse = one / (wp.dot(w, w) * wp.dot(f, f))  # = 1 / (c² + |n|²)
        unit = n / sn
        d_w = (sn * f - c * wp.cross(f, unit)) * inverse
        d_f = (sn * w - c * wp.cross(unit, w)) * inverse
        return phi, sn, unit, d_w, d_f

    @wp.func
    def hinge_geometry(model: SheetModel, state: SheetState, h: int, s: int):
        # hinge h's two segments and the difference u of its axis's nodes
        nodes = model.hinge_nodes[h]
        across = model.hinge_axis_nodes[h]
        x1 = state.position[nodes[1], s]
        e1 = x1 - state.position[nodes[0], s]
        e2 = state.position[nodes[2], s] - x1
        return e1, e2, state.position[across[1], s] - state.position[across[0], s]

    @wp.func
    def hinge_curvature(model: SheetModel, h: int, sine: scalar, inverse_p1: scalar, inverse_p2: scalar, chord: scalar):
        # the strip's hinge curvature, 2 sin ψ / chord, in the projected plane (§5.1), times
        # the hinge's scale (2 at a clamp edge)
        return two * sine * inverse_p1 * inverse_p2 / chord * model.hinge_curvature_scale[h]

    @wp.func
    def cell_corners(model: SheetModel, state: SheetState, c: int, s: int):
        # cell c's mean warp and mean weft sides, and its twist vector x00 − x10 − x01 + x11
        # (h_w h_f times the mixed second difference: zero when the cell is a parallelogram)
        q = model.cell_nodes[c]
        x00 = state.position[q[0], s]
        x10 = state.position[q[1], s]
        x01 = state.position[q[2], s]
        x11 = state.position[q[3], s]
        return (x10 - x00 + x11 - x01) * half, (x01 - x00 + x11 - x10) * half, x00 - x10 - x01 + x11

    @wp.func
    def cell_twist(model: SheetModel, d: vec3, unit: vec3):
        # κ12, the twist: the twist vector's part along the cell's normal over the rest area
        return wp.dot(d, unit) / (model.spacing[0] * model.spacing[1])

    @wp.func
    def segments(model: SheetModel, stepping: SheetStepping, state: SheetState, s: int):
        for e in range(model.edge_nodes.shape[0]):
            ends = model.edge_nodes[e]
            family = model.edge_family[e]
            d = state.position[ends[1], s] - state.position[ends[0], s]
            length = wp.length(d)
            l0 = model.spacing[family]
            strain = (length - l0) / l0
            if not (wp.abs(strain) <= stepping.max_strain):  # also catches NaN
                return STATUS_STRAIN, e, strain
            f = tension(strain, model.tensile[family, s]) * model.edge_width[e] / length * d
            if strain < zero:
                f = f * model.compression  # a yarn buckles under far less than it bears
            add(state.force_tensile, ends[0], s, f)
            add(state.force_tensile, ends[1], s, vec3() - f)
        return STATUS_OK, 0, zero

    @wp.func
    def bend(model: SheetModel, h: int, e1: vec3, e2: vec3, u: vec3):
        # hinge h's curvature and the gradients of its turning angle ψ (docs/model.md §17.4)
        # from its segments e1, e2 and axis vector u: of its line's end nodes and of its
        # axis's upper node (the others follow by balance); healthy false when the line
        # folded onto itself or a segment turned onto the axis (no plane to bend in), or is
        # NaN, with the chord over h
        family = model.hinge_family[h]
        inverse_u = one / wp.length(u)
        axis = u * inverse_u
        sine, cosine, inverse_p1, inverse_p2, chord = turning_angle(e1, e2, axis)
        fold = scalar(1e-3) * model.spacing[family]
        healthy = chord > fold and inverse_p1 * fold < one and inverse_p2 * fold < one
        curvature = hinge_curvature(model, h, sine, inverse_p1, inverse_p2, chord)
        grad_0 = wp.cross(axis, e1) * (inverse_p1 * inverse_p1)
        grad_2 = wp.cross(axis, e2) * (inverse_p2 * inverse_p2)
        e1a = wp.dot(e1, axis)
        e2a = wp.dot(e2, axis)
        d_axis = (cosine * wp.cross(e1, e2) + sine * (e2a * e1 + e1a * e2)) * (
            inverse_p1 * inverse_p1 * inverse_p2 * inverse_p2
        )
        grad_u = (d_axis - wp.dot(d_axis, axis) * axis) * inverse_u
        return healthy, chord / model.spacing[family], curvature, grad_0, grad_2, grad_u

    @wp.func
    def add_couple(
        forces: wp.array2d(dtype=vec3),
        model: SheetModel,
        h: int,
        s: int,
        tau: scalar,
        grad_0: vec3,
        grad_2: vec3,
        grad_u: vec3,
    ):
        # −τ ∂ψ/∂x on the hinge's line nodes and its axis's nodes
        nodes = model.hinge_nodes[h]
        across = model.hinge_axis_nodes[h]
        add(forces, nodes[0], s, vec3() - tau * grad_0)
        add(forces, nodes[2], s, vec3() - tau * grad_2)
        add(forces, nodes[1], s, tau * (grad_0 + grad_2))
        add(forces, across[1], s, vec3() - tau * grad_u)
        add(forces, across[0], s, tau * grad_u)

    @wp.func
    def hinge_couple(
        model: SheetModel,
        state: SheetState,
        h: int,
        s: int,
        curvature: scalar,
        coupling: scalar,
        grad_0: vec3,
        grad_2: vec3,
        grad_u: vec3,
    ):
        # the hinge's law followed to its curvature, its moment (plus the Poisson coupling
        # D12 K of the other line through its node, elastic) times its width as a couple
        p = model.bending[model.hinge_family[h], s]
        memory = law.follow(curvature, state.hinge[h, s], p, state.hinge_history, h, s)
        state.hinge[h, s] = memory
        width = model.hinge_width[h]
        tau_elastic = (law.elastic_moment(curvature, p) + coupling) * width
        tau_hysteretic = law.hysteretic_moment(curvature, memory, p) * width
        add_couple(state.force_elastic, model, h, s, tau_elastic, grad_0, grad_2, grad_u)
        add_couple(state.force_hysteretic, model, h, s, tau_hysteretic, grad_0, grad_2, grad_u)

    @wp.func
    def hinges(model: SheetModel, state: SheetState, s: int):
        # the node pairs first: a warp and a weft hinge at one node, whose energy has the
        # plate's Poisson term D12 κ11 κ22 besides each line's own (§17.4)
        d12 = model.poisson[s]
        for k in range(model.hinge_pairs):
            # a pair's five nodes, read once: the warp line a, b, c is the weft hinge's axis
            # and the weft line d, b, e the warp hinge's
            warp = 2 * k
            line = model.hinge_nodes[warp]
            across = model.hinge_axis_nodes[warp]
            xb = state.position[line[1], s]
            warp_1 = xb - state.position[line[0], s]
            warp_2 = state.position[line[2], s] - xb
            weft_1 = xb - state.position[across[0], s]
            weft_2 = state.position[across[1], s] - xb
            healthy, chord, curvature, grad_0, grad_2, grad_u = bend(model, warp, warp_1, warp_2, weft_1 + weft_2)
            if not healthy:
                return STATUS_FOLDED, warp, chord
            weft_healthy, weft_chord, weft_curvature, weft_0, weft_2, weft_u = bend(
                model, warp + 1, weft_1, weft_2, warp_1 + warp_2
            )
            if not weft_healthy:
                return STATUS_FOLDED, warp + 1, weft_chord
            # a bend towards one side of the sheet turns its warp and weft hinges with opposite
            # signs (each measures ψ about its own axis, the other yarn): the energy is
            # −D12 K_warp K_weft over the area either hinge carries (its node's, and a line
            # end's beside it, where only one line goes on: hinge_coupling is that area over
            # each hinge's own)
            couple = -d12 * model.hinge_coupling[warp] * weft_curvature
            hinge_couple(model, state, warp, s, curvature, couple, grad_0, grad_2, grad_u)
            couple = -d12 * model.hinge_coupling[warp + 1] * curvature
            hinge_couple(model, state, warp + 1, s, weft_curvature, couple, weft_0, weft_2, weft_u)
        for h in range(2 * model.hinge_pairs, model.hinge_nodes.shape[0]):
            e1, e2, u = hinge_geometry(model, state, h, s)
            healthy, chord, curvature, grad_0, grad_2, grad_u = bend(model, h, e1, e2, u)
            if not healthy:
                return STATUS_FOLDED, h, chord
            hinge_couple(model, state, h, s, curvature, zero, grad_0, grad_2, grad_u)
        return STATUS_OK, 0, zero

    @wp.func
    def cells(model: SheetModel, stepping: SheetStepping, state: SheetState, s: int):
        p = model.shear[s]
        p_twist = model.twist[s]
        for c in range(model.cell_nodes.shape[0]):
            q = model.cell_nodes[c]
            w, f, d = cell_corners(model, state, c, s)
            phi, sn, unit, d_w, d_f = shear_angle(w, f)
            if not (wp.abs(phi) <= stepping.max_shear):  # also catches NaN
                return STATUS_CELL_COLLAPSED, c, phi
            # a cell astride a clamp edge shears its free half by twice its mean
            scale = model.cell_scale[c]
            shear = scale * phi
            memory = law.follow(shear, state.cell[c, s], p, state.cell_history, c, s)
            state.cell[c, s] = memory
            area = model.cell_area[c] * scale
            tau_elastic = law.elastic_moment(shear, p) * area
            tau_hysteretic = law.hysteretic_moment(shear, memory, p) * area
            # w and f are means of the cell's edges: each corner moves them by ±½
            g00 = (d_w + d_f) * (-half)
            g10 = (d_w - d_f) * half
            g01 = (d_f - d_w) * half
            g11 = (d_w + d_f) * half
            # the twist κ12 = d·n / (h_w h_f) (§17.5): its energy A ∫ M12 dκ12 is the plate's
            # 2 D66 κ12² per area for an elastic law. ∂(d·n)/∂x: the twist vector's ±1 at the
            # corners along n, and the normal's turn, through w and f, against d's in-plane part
            kappa = scale * cell_twist(model, d, unit)
            per_twist = model.twist_area[c] / (model.spacing[0] * model.spacing[1])
            twist_elastic = law.elastic_moment(kappa, p_twist) * per_twist
            twist_hysteretic = zero
            if model.twist_elastic[s] == 0:  # a twist without hysteresis has no memory to follow
                twist_memory = law.follow(kappa, state.twist[c, s], p_twist, state.twist_history, c, s)
                state.twist[c, s] = twist_memory
                twist_hysteretic = law.hysteretic_moment(kappa, twist_memory, p_twist) * per_twist
            in_plane = d - wp.dot(d, unit) * unit
            t_w = wp.cross(f, in_plane) / sn
            t_f = wp.cross(in_plane, w) / sn
            t00 = unit - (t_w + t_f) * half
            t10 = (t_w - t_f) * half - unit
            t01 = (t_f - t_w) * half - unit
            t11 = unit + (t_w + t_f) * half
            add(state.force_elastic, q[0], s, vec3() - tau_elastic * g00 - twist_elastic * t00)
            add(state.force_elastic, q[1], s, vec3() - tau_elastic * g10 - twist_elastic * t10)
            add(state.force_elastic, q[2], s, vec3() - tau_elastic * g01 - twist_elastic * t01)
            add(state.force_elastic, q[3], s, vec3() - tau_elastic * g11 - twist_elastic * t11)
            add(state.force_hysteretic, q[0], s, vec3() - tau_hysteretic * g00 - twist_hysteretic * t00)
            add(state.force_hysteretic, q[1], s, vec3() - tau_hysteretic * g10 - twist_hysteretic * t10)
            add(state.force_hysteretic, q[2], s, vec3() - tau_hysteretic * g01 - twist_hysteretic * t01)
            add(state.force_hysteretic, q[3], s, vec3() - tau_hysteretic * g11 - twist_hysteretic * t11)
        return STATUS_OK, 0, zero

    @wp.func
    def ghosts_seen(model: SheetModel, state: SheetState, s: int):
        # every element sees each held ghost where its master's field puts it
        # (state.ghost_offset, docs/model.md §17.2). A slaved ghost is already where its
        # master puts it along the normal, and in the plane where its own forces take it
        # (kernels/sheet.py).
        for k in range(model.slaved_ghosts, model.ghost_nodes.shape[0]):
            g = model.ghost_nodes[k]
            held = state.position[g, s]
            state.ghost_held[k, s] = held
            state.position[g, s] = held + state.ghost_offset[k, s]

    @wp.func
    def weight_of(model: SheetModel, s: int, i: int):
        # node i's weight, N
        return vec3(zero, -model.gravity, zero) * (model.density[s] * model.node_area[i])

    @wp.func
    def on_master(forces: wp.array2d(dtype=vec3), m: int, s: int, f: vec3, weight: scalar, normal: vec3, r: scalar):
        # a ghost's force f on its master, which moves the ghost along the normal by the
        # weight r² times its own displacement there and, a held ghost, in the plane by −r
        # times it (a slaved one: r = 0, its place in the plane its own)
        out = wp.dot(normal, f)
        add(forces, m, s, (weight * out) * normal - r * (f - out * normal))

    @wp.func
    def ghosts_back(model: SheetModel, state: SheetState, s: int):
        # each held ghost back in the clamp, where ghosts_seen found it
        for k in range(model.slaved_ghosts, model.ghost_nodes.shape[0]):
            state.position[model.ghost_nodes[k], s] = state.ghost_held[k, s]

    @wp.func
    def ghosts_held(model: SheetModel, state: SheetState, s: int):
        # every ghost's forces in the elements on its master, and a slaved one's weight
        # (its normal coordinate is its master's, its place in the plane its own: along the
        # normal only); each held ghost back in the clamp
        normal = state.clamp_normal[s]
        for k in range(model.ghost_nodes.shape[0]):
            g = model.ghost_nodes[k]
            m = model.ghost_masters[k]
            r = model.ghost_ratios[k]
            weight = r * r
            tensile = state.force_tensile[g, s]
            in_plane = zero
            if k < model.slaved_ghosts:
                tensile = tensile + weight_of(model, s, g)
            else:
                in_plane = r
            on_master(state.force_tensile, m, s, tensile, weight, normal, in_plane)
            on_master(state.force_elastic, m, s, state.force_elastic[g, s], weight, normal, in_plane)
            on_master(state.force_hysteretic, m, s, state.force_hysteretic[g, s], weight, normal, in_plane)
        ghosts_back(model, state, s)

    @wp.func
    def accumulate_sheet_forces(model: SheetModel, stepping: SheetStepping, state: SheetState, s: int):
        # Returns 0 when healthy, or a status code with the offending element and value.
        for i in range(model.n_nodes):
            state.force_tensile[i, s] = vec3()
            state.force_elastic[i, s] = vec3()
            state.force_hysteretic[i, s] = vec3()
        ghosts = model.ghost_nodes.shape[0] > 0
        if ghosts:
            ghosts_seen(model, state, s)
        code, index, value = segments(model, stepping, state, s)
        if code == STATUS_OK:
            code, index, value = hinges(model, state, s)
        if code == STATUS_OK:
            code, index, value = cells(model, stepping, state, s)
        if ghosts:
            ghosts_held(model, state, s)
        return code, index, value

    return SheetForces(
        accumulate_sheet_forces=accumulate_sheet_forces,
        hinge_geometry=hinge_geometry,
        hinge_curvature=hinge_curvature,
        turning_angle=turning_angle,
        cell_corners=cell_corners,
        cell_twist=cell_twist,
        shear_angle=shear_angle,
        ghosts_seen=ghosts_seen,
        ghosts_back=ghosts_back,
        weight_of=weight_of,
    )
