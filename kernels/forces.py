"""Internal forces of a strip: tension of every free segment and the bending couple of
every hinge (docs/model.md §3-5), accumulated in one pass down the chain.
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import geometry, integrators, structs, tensile
from .status import STATUS_FOLDED, STATUS_OK, STATUS_STRAIN
from .types import precision


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = ()) -> SimpleNamespace:
    """``accumulate_internal_forces`` for ``scalar`` (the structs of a model with force ``terms``)."""
    vec2, vec4 = precision(scalar).vec2, precision(scalar).vec4
    zero = scalar(0.0)
    one = scalar(1.0)
    strip = structs.build(scalar, terms)
    StripModel, StripState, law = strip.StripModel, strip.StripState, strip.law
    Stepping = integrators.build(scalar).Stepping
    tension = tensile.build(scalar).force_per_width
    geo = geometry.build(scalar)
    perp, signed_curvature = geo.perp, geo.signed_curvature

    @wp.func
    def segment_and_hinge(
        model: StripModel,
        stepping: Stepping,
        state: StripState,
        s: int,
        i: int,
        node: vec2,
        e1: vec2,
        inverse_l1: scalar,
        width: scalar,
        a: vec4,
        p: law.Parameters,
        edge_scale: scalar,
        inverse_l0: scalar,
    ):
        # Segment i (node i → i+1) and the hinge at node i, which share the segment's vector
        # and length; ``node`` is node i's position, ``e1`` the segment above it and
        # ``inverse_l1`` its reciprocal length, carried down the chain by the caller. Returns
        # a status code and its value, then node i+1's position, segment i and its
        # reciprocal length for the next hinge.
        first = model.n_clamped - 2
        l0 = model.rest_length
        following = state.position[i + 1, s]
        e2 = following - node
        l2 = wp.length(e2)
        inverse_l2 = one / l2
        strain = (l2 - l0) * inverse_l0  # l2 - l0 is exact near rest (Sterbenz)
        if not (wp.abs(strain) <= stepping.max_strain):  # also catches NaN
            return STATUS_STRAIN, strain, following, e2, inverse_l2
        f = tension(strain, a) * width * inverse_l2 * e2
        state.force_tensile[i, s] = state.force_tensile[i, s] + f
        state.force_tensile[i + 1, s] = vec2() - f
        h = i - first - 1
        curvature, chord = signed_curvature(e1, e2, inverse_l1, inverse_l2)
        if not (chord > scalar(1e-3) * l0):
            return STATUS_FOLDED, chord * inverse_l0, following, e2, inverse_l2
        if h == 0:
            # The clamp-edge hinge bends only the half segment below the built-in end
            # (docs/model.md §5.3): its curvature is the turning angle over h/2, twice
            # the chain's; the paper's model keeps h (scale 1, bitwise the same).
            curvature = curvature * edge_scale
        # Every law bends from the strip's natural curvature; the grip scales the hinge's
        # D and its hysteretic moment (docs/model.md §5.4; K_rest = 0 and factors 1 leave
        # every bit as it was).
        curvature = curvature - model.rest_curvature[h, s]
        grip = model.grip[h, s]
        memory = law.follow(curvature, state.hinge[h, s], p, state.history, h, s)
        state.hinge[h, s] = memory
        # τ = M·W acts on the turning angle φ; F = -τ ∇φ with ∇φ as below.
        grad_i = perp(e1) * (inverse_l1 * inverse_l1)
        grad_k = perp(e2) * (inverse_l2 * inverse_l2)
        tau_elastic = law.elastic_moment(curvature, p) * grip[0] * width
        tau_hysteretic = law.hysteretic_moment(curvature, memory, p) * grip[1] * width
        state.force_elastic[i - 1, s] = state.force_elastic[i - 1, s] - tau_elastic * grad_i
        state.force_elastic[i + 1, s] = vec2() - tau_elastic * grad_k
        state.force_elastic[i, s] = state.force_elastic[i, s] + tau_elastic * (grad_i + grad_k)
        state.force_hysteretic[i - 1, s] = state.force_hysteretic[i - 1, s] - tau_hysteretic * grad_i
        state.force_hysteretic[i + 1, s] = vec2() - tau_hysteretic * grad_k
        state.force_hysteretic[i, s] = state.force_hysteretic[i, s] + tau_hysteretic * (grad_i + grad_k)
        return STATUS_OK, zero, following, e2, inverse_l2

    @wp.func
    def accumulate_internal_forces(model: StripModel, stepping: Stepping, state: StripState, s: int):
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
        p = model.bending[s]
        edge_scale = model.edge_curvature_scale[s]
        # One pass down the strip: segment i (node i → i+1) and the hinge at node i share
        # the segment vector and length, so each is loaded and measured once. Segments
        # inside the clamp move rigidly: only the edge segment and below strain.
        node = state.position[first + 1, s]
        e1 = node - state.position[first, s]
        # Reciprocal lengths, each taken once and carried down the chain: a hinge costs one
        # division for its segment's length and one for its chord (docs/model.md §5.1).
        inverse_l1 = one / wp.length(e1)
        inverse_l0 = one / model.rest_length
        for i in range(first + 1, n - 1):
            code, value, node, e1, inverse_l1 = segment_and_hinge(
                model, stepping, state, s, i, node, e1, inverse_l1, width, a, p, edge_scale, inverse_l0
            )
            if code != STATUS_OK:
                return code, i, value
        return STATUS_OK, 0, zero

    return SimpleNamespace(accumulate_internal_forces=accumulate_internal_forces, segment_and_hinge=segment_and_hinge)
