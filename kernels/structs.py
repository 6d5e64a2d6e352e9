"""What a batch of strips *is* (``StripModel``) and *is doing* (``StripState``), as Warp
structs for one precision.

Per-node arrays are laid out ``[node, strip]``: at a given node index the threads of a
GPU warp read neighbouring strips, i.e. consecutive addresses (coalesced).
"""

import functools
from types import SimpleNamespace
from typing import Any

import warp as wp

from . import fused, laws
from .types import precision

STRIP_CHANNELS = 4
"""The strip's own work channels: bending elastic, hysteresis, damping, drive (kernels/probes.py)."""


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = ()) -> SimpleNamespace:
    """``StripModel`` and ``StripState`` for ``scalar`` (every bending law: kernels/laws.py),
    with an energy tally channel for each force term of ``terms``."""
    types = precision(scalar)
    vec2, vec4 = types.vec2, types.vec4
    law = laws.build(scalar)
    tally = fused.tally_type(scalar, STRIP_CHANNELS + len(terms))

    @wp.struct
    class StripModel:
        """What the strips are: batch geometry and per-strip material (SI)."""

        n_nodes: int
        n_clamped: int
        rest_length: scalar
        gravity: scalar
        rest_position: wp.array2d(dtype=vec2)  # [node, strip]; clamp nodes rotate rigidly from these
        tensile: wp.array(dtype=vec4)  # a1..a4 of T(ε), N/m
        bending: wp.array(dtype=law.Parameters)  # each strip's bending law and its packed parameters
        width: wp.array(dtype=scalar)  # W, m
        node_mass: wp.array(dtype=scalar)  # ρ_A W h, kg (half at the free end)
        damping: wp.array(dtype=scalar)  # γ after release, 1/s
        edge_curvature_scale: wp.array(dtype=scalar)  # h / length of the clamp-edge hinge (docs/model.md §5.3)
        rest_curvature: wp.array2d(dtype=scalar)  # [hinge, strip], K_rest, 1/m (docs/model.md §5.4)
        grip: wp.array2d(dtype=vec2)  # [hinge, strip], factors on D and on the hysteretic moment (§5.4)

    @wp.struct
    class StripState:
        """What the strips are doing: nodes, hinge memory, work done, health."""

        position: wp.array2d(dtype=vec2)  # [node, strip]
        velocity: wp.array2d(dtype=vec2)
        force_tensile: wp.array2d(dtype=vec2)  # scratch, per substep
        force_elastic: wp.array2d(dtype=vec2)
        force_hysteretic: wp.array2d(dtype=vec2)
        correction: wp.array2d(dtype=vec2)  # scratch, imex: the implicit tension's force on each node
        elimination: wp.array2d(dtype=vec4)  # scratch, imex: [segment, strip] c', d' and the segment's direction
        hinge: wp.array2d(dtype=law.Memory)  # [hinge, strip], the bending law's memory
        history: law.History  # the open reversal points of a law with return-point memory
        work: wp.array(dtype=tally)  # the work channels of kernels/probes.py STRIP_PROBES (+ force terms'), J
        step: wp.array(dtype=int)  # substeps done so far
        status: wp.array(dtype=int)
        status_step: wp.array(dtype=int)
        status_index: wp.array(dtype=int)  # segment or hinge where it happened
        status_value: wp.array(dtype=scalar)

    return SimpleNamespace(StripModel=StripModel, StripState=StripState, law=law, tally=tally)
