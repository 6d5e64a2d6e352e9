"""Internal forces of a strip: tension of every free segment and the bending couple of
every hinge (docs/model.md §3-5), accumulated in one pass down the chain.
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import exp_lanes, geometry, integrators, structs, tensile
from .status import STATUS_FOLDED, STATUS_OK, STATUS_STRAIN
from .types import LAW_MEMORY_SLOTS, precision


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = (), lanes: int = 1) -> SimpleNamespace:
    """``accumulate_internal_forces`` for ``scalar`` (the structs of a model with force
    ``terms``), following ``lanes`` hinges together (kernels/exp_lanes.py: their
    exponentials in one call; 1 on a GPU, bitwise a hinge at a time)."""
    types = precision(scalar)
    vec2, vec4 = types.vec2, types.vec4
    zero = scalar(0.0)
    one = scalar(1.0)
    strip = structs.build(scalar, terms)
    StripModel, StripState, law = strip.StripModel, strip.StripState, strip.law
    Stepping = integrators.build(scalar).Stepping
    tension = tensile.build(scalar).force_per_width
    geo = geometry.build(scalar)
    perp, signed_curvature = geo.perp, geo.signed_curvature

    @wp.func
    def segment_and_curvature(
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
        edge_scale: scalar,
        inverse_l0: scalar,
    ):
        # Segment i (node i → i+1) and the curvature of the hinge at node i, which share
        # the segment's vector and length; ``node`` is node i's position, ``e1`` the segment
        # above it and ``inverse_l1`` its reciprocal length, carried down the chain by the
        # caller. Applies the segment's tension and returns a status code and its value,
        # node i+1's position, segment i, its reciprocal length and the hinge's curvature
        # from its natural one.
        first = model.n_clamped - 2
        l0 = model.rest_length
        following = state.position[i + 1, s]
        e2 = following - node
        l2 = wp.length(e2)
        inverse_l2 = one / l2
        strain = (l2 - l0) * inverse_l0  # l2 - l0 is exact near rest (Sterbenz)
        if not (wp.abs(strain) <= stepping.max_strain):  # also catches NaN
            return STATUS_STRAIN, strain, following, e2, inverse_l2, zero
        f = tension(strain, a) * width * inverse_l2 * e2
        state.force_tensile[i, s] = state.force_tensile[i, s] + f
        state.force_tensile[i + 1, s] = vec2() - f
        h = i - first - 1
        curvature, chord = signed_curvature(e1, e2, inverse_l1, inverse_l2)
        if not (chord > scalar(1e-3) * l0):
            return STATUS_FOLDED, chord * inverse_l0, following, e2, inverse_l2, zero
        if h == 0:
            # The clamp-edge hinge bends only the half segment below the built-in end
            # (docs/model.md §5.3): its curvature is the turning angle over h/2, twice
            # the chain's; the paper's model keeps h (scale 1, bitwise the same).
            curvature = curvature * edge_scale
        # Every law bends from the strip's natural curvature (docs/model.md §5.4; K_rest = 0
        # leaves every bit as it was).
        return STATUS_OK, zero, following, e2, inverse_l2, curvature - model.rest_curvature[h, s]

    def couple_of(hysteretic_moment: Any) -> Any:
        @wp.func
        def hinge_couple(
            model: StripModel,
            state: StripState,
            s: int,
            i: int,
            h: int,
            curvature: scalar,
            memory: law.Memory,
            p: law.Parameters,
            width: scalar,
            e1: vec2,
            inverse_l1: scalar,
            e2: vec2,
            inverse_l2: scalar,
        ):
            # Hinge h at node i, its law followed to ``curvature`` (``memory``): stores the
            # memory and applies its couple to nodes i − 1, i, i + 1 (segments e1, e2 above
            # and below it). The grip scales the hinge's D and its hysteretic moment
            # (docs/model.md §5.4; factors 1 leave every bit as it was).
            state.hinge[h, s] = memory
            grip = model.grip[h, s]
            # τ = M·W acts on the turning angle φ; F = -τ ∇φ with ∇φ as below.
            grad_i = perp(e1) * (inverse_l1 * inverse_l1)
            grad_k = perp(e2) * (inverse_l2 * inverse_l2)
            tau_elastic = law.elastic_moment(curvature, p) * grip[0] * width
            tau_hysteretic = hysteretic_moment(curvature, memory, p) * grip[1] * width
            state.force_elastic[i - 1, s] = state.force_elastic[i - 1, s] - tau_elastic * grad_i
            state.force_elastic[i + 1, s] = vec2() - tau_elastic * grad_k
            state.force_elastic[i, s] = state.force_elastic[i, s] + tau_elastic * (grad_i + grad_k)
            state.force_hysteretic[i - 1, s] = state.force_hysteretic[i - 1, s] - tau_hysteretic * grad_i
            state.force_hysteretic[i + 1, s] = vec2() - tau_hysteretic * grad_k
            state.force_hysteretic[i, s] = state.force_hysteretic[i, s] + tau_hysteretic * (grad_i + grad_k)

        return hinge_couple

    def pass_of(index: int) -> Any:
        # The pass down the chain for strips of law ``index``, so that the law's branch is
        # taken once per strip, not once per hinge and function; a law without a decay of
        # its own takes its hinges one at a time, with no exponential to share.
        own = law.own[index]
        follow_before_decay, decay = own.follow_before_decay, own.decay
        hinge_couple = couple_of(own.hysteretic_moment)
        group_size = lanes if law.decays[index] else 1
        exp_of_lanes = exp_lanes.build(scalar, group_size)
        Lanes = wp.types.vector(group_size, dtype=scalar)  # one value per hinge of a group
        Segments = wp.types.vector(group_size + 1, dtype=scalar)  # one per segment, the one above the group first
        Memories = wp.types.matrix(shape=(group_size, LAW_MEMORY_SLOTS), dtype=scalar)  # a hinge's memory a row
        no_decay = Lanes(scalar(1.0))

        @wp.func
        def pass_down(
            model: StripModel,
            stepping: Stepping,
            state: StripState,
            s: int,
            p: law.Parameters,
            width: scalar,
            a: vec4,
            edge_scale: scalar,
        ):
            n = model.n_nodes
            first = model.n_clamped - 2  # clamped node above the clamp-edge hinge
            # One pass down the strip: segment i (node i → i+1) and the hinge at node i
            # share the segment vector and length, so each is loaded and measured once.
            # Segments inside the clamp move rigidly: only the edge segment and below strain.
            node = state.position[first + 1, s]
            e1 = node - state.position[first, s]
            # Reciprocal lengths, each taken once and carried down the chain: a hinge costs
            # one division for its segment's length and one for its chord (docs/model.md §5.1).
            inverse_l1 = one / wp.length(e1)
            inverse_l0 = one / model.rest_length
            # The hinges in groups of ``group_size``: each group's segments and curvatures first,
            # then its law's exponentials in one call, then its couples, in the order a
            # hinge at a time takes them (each node's force is written in the same order).
            group = first + 1
            while group < n - 1:
                segment_x = Segments()
                segment_y = Segments()
                segment_inverse = Segments()
                memories = Memories()  # each hinge's memory before its decay
                curvatures = Lanes()
                exponents = Lanes()
                segment_x[0] = e1[0]
                segment_y[0] = e1[1]
                segment_inverse[0] = inverse_l1
                for j in range(wp.static(group_size)):
                    i = group + j
                    if i < n - 1:
                        code, value, node, e1, inverse_l1, curvature = segment_and_curvature(
                            model, stepping, state, s, i, node, e1, inverse_l1, width, a, edge_scale, inverse_l0
                        )
                        if code != STATUS_OK:
                            return code, i, value
                        h = i - first - 1
                        memory, exponent = follow_before_decay(curvature, state.hinge[h, s], p, state.history, h, s)
                        memories[j] = memory
                        curvatures[j] = curvature
                        exponents[j] = exponent
                        segment_x[j + 1] = e1[0]
                        segment_y[j + 1] = e1[1]
                        segment_inverse[j + 1] = inverse_l1
                factors = no_decay
                if wp.dot(exponents, exponents) != zero:  # a group with nothing to decay makes no call
                    factors = exp_of_lanes(exponents)
                for j in range(wp.static(group_size)):
                    i = group + j
                    if i < n - 1:
                        hinge_couple(
                            model,
                            state,
                            s,
                            i,
                            i - first - 1,
                            curvatures[j],
                            decay(memories[j], factors[j], p),
                            p,
                            width,
                            vec2(segment_x[j], segment_y[j]),
                            segment_inverse[j],
                            vec2(segment_x[j + 1], segment_y[j + 1]),
                            segment_inverse[j + 1],
                        )
                group = group + wp.static(group_size)
            return STATUS_OK, 0, zero

        return pass_down

    def dispatch(index: int) -> Any:
        # One pass per law, each function naming its own law's pass and the next's (Warp
        # hashes what a function names: kernels/laws.py); an index past the list falls
        # back to the first law, as the laws' own dispatch does.
        head = passes[index]
        rest = dispatch(index + 1) if index + 1 < len(passes) else passes[0]

        @wp.func
        def pass_down(
            model: StripModel,
            stepping: Stepping,
            state: StripState,
            s: int,
            p: law.Parameters,
            width: scalar,
            a: vec4,
            edge_scale: scalar,
        ):
            if law.law_of(p) == wp.static(index):
                return head(model, stepping, state, s, p, width, a, edge_scale)
            return rest(model, stepping, state, s, p, width, a, edge_scale)

        return pass_down

    passes = [pass_of(index) for index in range(len(law.own))]
    pass_down = dispatch(0)

    @wp.func
    def accumulate_internal_forces(model: StripModel, stepping: Stepping, state: StripState, s: int):
        # Returns 0 when healthy, or a status code with the offending index and value.
        first = model.n_clamped - 2
        # Only the two nodes above the first hinge start from zero here; every node below is
        # first reached as node i + 1 of the pass and stored then (0 - f, bitwise the same
        # as zeroing first), which saves a sweep over three [node, strip] buffers.
        for i in range(first, first + 2):
            state.force_tensile[i, s] = vec2()
            state.force_elastic[i, s] = vec2()
            state.force_hysteretic[i, s] = vec2()
        return pass_down(
            model, stepping, state, s, model.bending[s], model.width[s], model.tensile[s], model.edge_curvature_scale[s]
        )

    return SimpleNamespace(
        accumulate_internal_forces=accumulate_internal_forces,
        segment_and_curvature=segment_and_curvature,
        hinge_couple=couple_of(law.hysteretic_moment),
    )
