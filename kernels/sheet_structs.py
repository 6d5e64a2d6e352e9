"""What a batch of woven sheets *is* (``SheetModel``), *is doing* (``SheetState``) and what
drives it (``SheetControl``), as Warp structs for one precision (docs/model.md §17).

A sheet is a grid of mass points along warp and weft; its elements (the segments of
every warp and weft line, the hinges where a line turns, the cells where warp meets
weft) are index lists shared by every sheet of a batch, so sheets of one cut and spacing
differ only in material, damping and drive. Per-node arrays are laid out
``[node, sheet]``: at a given node the threads of a GPU warp read neighbouring sheets at
consecutive addresses (coalesced), while the shared index lists are one broadcast read.
"""

import functools
from dataclasses import dataclass
from typing import Any

import warp as wp

from . import fused, laws
from .types import precision

WARP, WEFT = 0, 1
"""The two yarn families, the first index of every per-direction array."""

SHEET_CHANNELS = 4
"""The sheet's own work channels: elastic, hysteresis, damping, drive (kernels/sheet.py)."""


@dataclass(frozen=True)
class SheetTypes:
    """The sheet's structs of one precision and the law dispatch they carry."""

    SheetModel: Any
    SheetState: Any
    SheetControl: Any
    SheetStepping: Any
    law: Any
    tally: Any


@functools.cache
def build(scalar: Any, terms: tuple[Any, ...] = ()) -> SheetTypes:
    """``SheetModel``, ``SheetState`` and ``SheetControl`` for ``scalar``, with an energy
    tally channel for each force term of ``terms``."""
    types = precision(scalar)
    vec3, vec4, vec5 = types.vec3, types.vec4, types.vec5
    law = laws.build(scalar)
    tally = fused.tally_type(scalar, SHEET_CHANNELS + len(terms))

    @wp.struct
    class SheetModel:
        """What the sheets are: the shared grid of elements and per-sheet material (SI)."""

        n_nodes: int
        gravity: scalar  # along −y, m/s²
        compression: scalar  # a yarn's stiffness in compression over its quartic's in tension (1: mirrored)
        rest_position: wp.array2d(dtype=vec3)  # [node, sheet]; clamped nodes move rigidly from these
        clamped: wp.array(dtype=int)  # [node]: 1 where the clamp holds the node
        slaved: wp.array(dtype=int)  # [node]: 1 where its master moves it out of the plane (§17.2)
        node_area: wp.array(dtype=scalar)  # [node]: the fabric area the node carries, m²
        density: wp.array(dtype=scalar)  # [sheet]: ρ_A, kg/m²
        damping: wp.array(dtype=scalar)  # [sheet]: γ after release, 1/s
        spacing: wp.array(dtype=scalar)  # [family]: rest segment length along warp, weft, m
        edge_nodes: wp.array(dtype=wp.vec2i)  # [segment]: its two nodes
        edge_family: wp.array(dtype=int)
        edge_width: wp.array(dtype=scalar)  # the width of fabric the segment's yarns stand for, m
        hinge_nodes: wp.array(dtype=wp.vec3i)  # [hinge]: three consecutive nodes of a line
        hinge_axis_nodes: wp.array(dtype=wp.vec2i)  # the cross-direction nodes whose difference is the bending axis
        hinge_family: wp.array(dtype=int)
        hinge_width: wp.array(dtype=scalar)  # m
        hinge_curvature_scale: wp.array(dtype=scalar)  # h / length the hinge bends (2 at a clamp edge, §5.3)
        hinge_pairs: int  # hinges 2k (warp) and 2k + 1 (weft) share node k's curvatures: the Poisson pairs first
        hinge_coupling: wp.array(dtype=scalar)  # [hinge]: the pair's Poisson area over the hinge's own
        cell_nodes: wp.array(dtype=wp.vec4i)  # [cell]: corners (i, j), (i+1, j), (i, j+1), (i+1, j+1)
        cell_area: wp.array(dtype=scalar)  # m² of free fabric the cell stands for
        cell_scale: wp.array(dtype=scalar)  # its shear over the free part (2 astride a clamp edge)
        twist_area: wp.array(dtype=scalar)  # m² of free fabric the cell's twist stands for
        rest_normal: vec3  # the sheet's rest plane's unit normal
        ghost_nodes: wp.array(dtype=int)  # [ghost]: slaved nodes, then held ones the bending sees moved
        ghost_masters: wp.array(dtype=int)  # [ghost]: the free node each ghost follows
        ghost_ratios: wp.array(dtype=scalar)  # [ghost]: |ξ_ghost| / ξ_master
        slaved_ghosts: int  # how many of the ghosts, first, are slaved nodes (docs/model.md §17.2)
        tensile: wp.array2d(dtype=vec4)  # [family, sheet]: a1..a4 of T(ε), N/m
        bending: wp.array2d(dtype=law.Parameters)  # [family, sheet]: the bending law of each direction
        shear: wp.array(dtype=law.Parameters)  # [sheet]: the shear law on the shear angle (G for D)
        twist: wp.array(dtype=law.Parameters)  # [sheet]: the twist law on a cell's twist κ12 (4 D66 for D)
        twist_elastic: wp.array(dtype=int)  # [sheet]: 1 where the twist law has no hysteresis (M12 = 4 D66 κ12)
        poisson: wp.array(dtype=scalar)  # [sheet]: D12, the bending Poisson coupling, N·m

    @wp.struct
    class SheetState:
        """What the sheets are doing: nodes, the laws' memory, the work done, health."""

        position: wp.array2d(dtype=vec3)  # [node, sheet]
        velocity: wp.array2d(dtype=vec3)
        force_tensile: wp.array2d(dtype=vec3)  # scratch, per substep
        force_elastic: wp.array2d(dtype=vec3)  # bending and shear, the laws' D K and G φ
        force_hysteretic: wp.array2d(dtype=vec3)  # bending and shear, the laws' hysteretic part
        hinge: wp.array2d(dtype=law.Memory)  # [hinge, sheet]
        cell: wp.array2d(dtype=law.Memory)  # [cell, sheet]: the shear law's
        twist: wp.array2d(dtype=law.Memory)  # [cell, sheet]: the twist law's
        hinge_history: law.History  # reversal points of hinges whose law has return-point memory
        cell_history: law.History
        twist_history: law.History
        ghost_offset: wp.array2d(dtype=vec3)  # [ghost, sheet]: out of the plane, from the clamp's place, m
        ghost_held: wp.array2d(dtype=vec3)  # [ghost, sheet]: scratch, the held place while the bending sees the ghost
        clamp_normal: wp.array(dtype=vec3)  # [sheet]: the rest normal as the clamp has turned it
        work: wp.array(dtype=tally)  # the work channels of kernels/sheet.py SHEET_PROBES (+ force terms'), J
        step: wp.array(dtype=int)
        status: wp.array(dtype=int)
        status_step: wp.array(dtype=int)
        status_index: wp.array(dtype=int)  # segment, hinge or cell where it happened
        status_value: wp.array(dtype=scalar)

    @wp.struct
    class SheetControl:
        """The clamp's rigid motion: a rotation θ(t) about ``axis`` through ``centre`` and a
        translation d(t) along ``direction`` (piecewise polynomials, SI), and the settling
        damping before the release."""

        rotation_start: wp.array2d(dtype=scalar)  # [segment, sheet], s
        rotation_end: wp.array2d(dtype=scalar)
        rotation_coefficients: wp.array2d(dtype=vec5)  # θ = Σ c_k (t − start)^k, rad/s^k
        rotation_segments: wp.array(dtype=int)
        translation_start: wp.array2d(dtype=scalar)
        translation_end: wp.array2d(dtype=scalar)
        translation_coefficients: wp.array2d(dtype=vec5)  # d = Σ c_k (t − start)^k, m/s^k
        translation_segments: wp.array(dtype=int)
        axis: wp.array(dtype=vec3)  # [sheet], unit
        centre: wp.array(dtype=vec3)  # [sheet], m, absolute
        direction: wp.array(dtype=vec3)  # [sheet], unit
        settle_damping: wp.array(dtype=scalar)  # γ while held, 1/s

    @wp.struct
    class SheetStepping:
        """How the solver steps: dt, the divergence limits, where t = 0 falls."""

        dt: scalar
        max_strain: scalar  # |ε| beyond which a sheet counts as diverged
        max_shear: scalar  # |φ| (rad) beyond which a cell counts as collapsed
        release_step: int  # step index of t = 0; the clamp settles before it

    return SheetTypes(
        SheetModel=SheetModel,
        SheetState=SheetState,
        SheetControl=SheetControl,
        SheetStepping=SheetStepping,
        law=law,
        tally=tally,
    )
