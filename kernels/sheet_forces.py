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
    cell_sides: Any
    shear_angle: Any


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
        # φ = π/2 − the angle between the cell's mean warp w and mean weft f, with its
        # gradients with respect to w and f (docs/model.md §17.4).
        c = wp.dot(w, f)
        n = wp.cross(w, f)
        sn = wp.length(n)
        phi = wp.atan2(c, sn)
        inverse = one / (wp.dot(w, w) * wp.dot(f, f))  # = 1 / (c² + |n|²)
        unit = n / sn
        d_w = (sn * f - c * wp.cross(f, unit)) * inverse
        d_f = (sn * w - c * wp.cross(unit, w)) * inverse
        return phi, sn, d_w, d_f

    @wp.func
    def hinge_geometry(model: SheetModel, state: SheetState, h: int, s: int):
        # hinge h's two segments, its bending axis (and 1/|u|), and its turning angle's pieces
        nodes = model.hinge_nodes[h]
        across = model.hinge_axis_nodes[h]
        x1 = state.position[nodes[1], s]
        e1 = x1 - state.position[nodes[0], s]
        e2 = state.position[nodes[2], s] - x1
        u = state.position[across[1], s] - state.position[across[0], s]
        inverse_u = one / wp.length(u)
        axis = u * inverse_u
        sine, cosine, inverse_p1, inverse_p2, chord = turning_angle(e1, e2, axis)
        return e1, e2, axis, inverse_u, sine, cosine, inverse_p1, inverse_p2, chord

    @wp.func
    def hinge_curvature(model: SheetModel, h: int, sine: scalar, inverse_p1: scalar, inverse_p2: scalar, chord: scalar):
        # the strip's hinge curvature, 2 sin ψ / chord, in the projected plane (§5.1), times
        # the hinge's scale (2 at a clamp edge)
        return two * sine * inverse_p1 * inverse_p2 / chord * model.hinge_curvature_scale[h]

    @wp.func
    def cell_sides(model: SheetModel, state: SheetState, c: int, s: int):
        # cell c's mean warp and mean weft sides
        q = model.cell_nodes[c]
        x00 = state.position[q[0], s]
        x10 = state.position[q[1], s]
        x01 = state.position[q[2], s]
        x11 = state.position[q[3], s]
        return (x10 - x00 + x11 - x01) * half, (x01 - x00 + x11 - x10) * half

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
            add(state.force_tensile, ends[0], s, f)
            add(state.force_tensile, ends[1], s, vec3() - f)
        return STATUS_OK, 0, zero

    @wp.func
    def hinges(model: SheetModel, state: SheetState, s: int):
        for h in range(model.hinge_nodes.shape[0]):
            nodes = model.hinge_nodes[h]
            across = model.hinge_axis_nodes[h]
            family = model.hinge_family[h]
            e1, e2, axis, inverse_u, sine, cosine, inverse_p1, inverse_p2, chord = hinge_geometry(model, state, h, s)
            fold = scalar(1e-3) * model.spacing[family]
            # folded onto itself, or a segment turned onto the axis (no plane to bend in);
            # NaN fails every comparison and stops here too
            if not (chord > fold and inverse_p1 * fold < one and inverse_p2 * fold < one):
                return STATUS_FOLDED, h, chord / model.spacing[family]
            curvature = hinge_curvature(model, h, sine, inverse_p1, inverse_p2, chord)
            p = model.bending[family, s]
            memory = law.follow(curvature, state.hinge[h, s], p, state.hinge_history, h, s)
            state.hinge[h, s] = memory
            width = model.hinge_width[h]
            tau_elastic = law.elastic_moment(curvature, p) * width
            tau_hysteretic = law.hysteretic_moment(curvature, memory, p) * width
            # ∂ψ/∂x of the three line nodes, and of the axis's two nodes through a = u/|u|
            grad_0 = wp.cross(axis, e1) * (inverse_p1 * inverse_p1)
            grad_2 = wp.cross(axis, e2) * (inverse_p2 * inverse_p2)
            e1a = wp.dot(e1, axis)
            e2a = wp.dot(e2, axis)
            d_axis = (cosine * wp.cross(e1, e2) + sine * (e2a * e1 + e1a * e2)) * (
                inverse_p1 * inverse_p1 * inverse_p2 * inverse_p2
            )
            grad_u = (d_axis - wp.dot(d_axis, axis) * axis) * inverse_u
            add(state.force_elastic, nodes[0], s, vec3() - tau_elastic * grad_0)
            add(state.force_elastic, nodes[2], s, vec3() - tau_elastic * grad_2)
            add(state.force_elastic, nodes[1], s, tau_elastic * (grad_0 + grad_2))
            add(state.force_elastic, across[1], s, vec3() - tau_elastic * grad_u)
            add(state.force_elastic, across[0], s, tau_elastic * grad_u)
            add(state.force_hysteretic, nodes[0], s, vec3() - tau_hysteretic * grad_0)
            add(state.force_hysteretic, nodes[2], s, vec3() - tau_hysteretic * grad_2)
            add(state.force_hysteretic, nodes[1], s, tau_hysteretic * (grad_0 + grad_2))
            add(state.force_hysteretic, across[1], s, vec3() - tau_hysteretic * grad_u)
            add(state.force_hysteretic, across[0], s, tau_hysteretic * grad_u)
        return STATUS_OK, 0, zero

    @wp.func
    def cells(model: SheetModel, stepping: SheetStepping, state: SheetState, s: int):
        p = model.shear[s]
        for c in range(model.cell_nodes.shape[0]):
            q = model.cell_nodes[c]
            w, f = cell_sides(model, state, c, s)
            phi, sn, d_w, d_f = shear_angle(w, f)
            if not (wp.abs(phi) <= stepping.max_shear):  # also catches NaN
                return STATUS_CELL_COLLAPSED, c, phi
            memory = law.follow(phi, state.cell[c, s], p, state.cell_history, c, s)
            state.cell[c, s] = memory
            area = model.cell_area[c]
            tau_elastic = law.elastic_moment(phi, p) * area
            tau_hysteretic = law.hysteretic_moment(phi, memory, p) * area
            # w and f are means of the cell's edges: each corner moves them by ±½
            g00 = (d_w + d_f) * (-half)
            g10 = (d_w - d_f) * half
            g01 = (d_f - d_w) * half
            g11 = (d_w + d_f) * half
            add(state.force_elastic, q[0], s, vec3() - tau_elastic * g00)
            add(state.force_elastic, q[1], s, vec3() - tau_elastic * g10)
            add(state.force_elastic, q[2], s, vec3() - tau_elastic * g01)
            add(state.force_elastic, q[3], s, vec3() - tau_elastic * g11)
            add(state.force_hysteretic, q[0], s, vec3() - tau_hysteretic * g00)
            add(state.force_hysteretic, q[1], s, vec3() - tau_hysteretic * g10)
            add(state.force_hysteretic, q[2], s, vec3() - tau_hysteretic * g01)
            add(state.force_hysteretic, q[3], s, vec3() - tau_hysteretic * g11)
        return STATUS_OK, 0, zero

    @wp.func
    def accumulate_sheet_forces(model: SheetModel, stepping: SheetStepping, state: SheetState, s: int):
        # Returns 0 when healthy, or a status code with the offending element and value.
        for i in range(model.n_nodes):
            state.force_tensile[i, s] = vec3()
            state.force_elastic[i, s] = vec3()
            state.force_hysteretic[i, s] = vec3()
        code, index, value = segments(model, stepping, state, s)
        if code != STATUS_OK:
            return code, index, value
        code, index, value = hinges(model, state, s)
        if code != STATUS_OK:
            return code, index, value
        return cells(model, stepping, state, s)

    return SheetForces(
        accumulate_sheet_forces=accumulate_sheet_forces,
        hinge_geometry=hinge_geometry,
        hinge_curvature=hinge_curvature,
        cell_sides=cell_sides,
        shear_angle=shear_angle,
    )
