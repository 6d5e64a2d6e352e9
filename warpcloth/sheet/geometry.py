"""Where a batch's sheets lie and how their nodes connect (docs/model.md §17.2).

A sheet is cut from a lattice of mass points, node (i, j) the i-th along the warp and the
j-th along the weft, at rest at ``origin + i h_warp d_warp + j h_weft d_weft``. The cut is
the set of lattice cells it keeps; from it follow the nodes (every corner of a kept
cell), the segments (every side of a kept cell), the hinges (every node where a warp or
weft line goes on through two segments) and what each carries, all from each node's share
of each kept cell around it (a quarter of a whole cell; of a cell the cut clips, the
integral of the node's bilinear shape function over the part kept): a node the mass of
its shares, a segment the width of its two ends' shares of each cell beside it (half a
whole cell), a hinge its node's shares. These are the row sums of the clipped cell's
consistent mass and stiffness, which keep its area and centroid, so where the fabric
lies is where it weighs and bends. A one-cell-wide sheet is the strip: two lines of half
its width, each node half its row's mass.

Coordinates are the strip's (warpcloth/scene/geometry.py): x out of the sheet's rest plane,
y up, z across it, the origin at the middle of the clamp edge.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from warpcloth.errors import ArgumentError
from warpcloth.kernels.sheet_structs import WARP, WEFT

EDGE_HINGES = ("second_order", "paper")
"""How a hinge at the clamp edge bends: over h/2 (second order in h, the strip's default)
or over h (the paper's model), docs/model.md §5.3."""


@dataclass(frozen=True)
class SheetGeometry:
    """The shared grid of a batch of sheets: nodes, their rest positions, and the element
    lists the kernels loop over (indices into the nodes)."""

    lattice: np.ndarray  # [node, (i, j)]
    rest_positions: np.ndarray  # [node, xyz], m
    clamped: np.ndarray  # [node], bool: held by the clamp
    node_area: np.ndarray  # [node], m²
    spacing: tuple[float, float]  # (h_warp, h_weft), m
    edge_nodes: np.ndarray  # [segment, 2]
    edge_family: np.ndarray  # [segment]: WARP or WEFT
    edge_width: np.ndarray  # [segment], m
    hinge_nodes: np.ndarray  # [hinge, 3]
    hinge_axis_nodes: np.ndarray  # [hinge, 2]
    hinge_family: np.ndarray  # [hinge]
    hinge_width: np.ndarray  # [hinge], m
    hinge_curvature_scale: np.ndarray  # [hinge]
    hinge_pairs: int  # hinges 2k, 2k + 1 are the warp and weft hinge of one node (the plate's Poisson pair)
    hinge_coupling: np.ndarray  # [hinge]: a paired hinge's Poisson area over its own, A_pair / (h w_h); 0 unpaired
    cell_nodes: np.ndarray  # [cell, 4]: (i, j), (i+1, j), (i, j+1), (i+1, j+1)
    cell_area: np.ndarray  # [cell], m² of free fabric it stands for
    cell_scale: np.ndarray  # [cell]: 2 for a cell astride the clamp edge with one corner free, else 1
    twist_area: np.ndarray  # [cell], m² of free fabric the cell's twist stands for
    rest_normal: np.ndarray  # [xyz]: the unit normal of the sheet's rest plane
    slaved: np.ndarray  # [node], bool: free near a clamp edge between nodes; its master moves it off the plane
    ghost_nodes: np.ndarray  # [ghost]: slaved nodes, then held ones the bending sees extrapolated
    ghost_masters: np.ndarray  # [ghost]: the free node each ghost follows
    ghost_ratios: np.ndarray  # [ghost]: |ξ_ghost| / ξ_master
    slaved_ghosts: int  # how many of the ghosts, first, are slaved nodes

    @property
    def n_nodes(self) -> int:
        """How many nodes a sheet has."""
        return len(self.rest_positions)

    def _reach(self) -> str:
        # where the lattice's nodes lie, for an error about one it does not have
        top = self.lattice.max(axis=0)
        return f"its lattice reaches i ≤ {top[0]}, j ≤ {top[1]}, where the cut keeps cells"

    def node(self, i: int, j: int) -> int:
        """The index of lattice node (i, j); an ArgumentError naming ``(i, j)`` if the cut
        does not keep it."""
        hits = np.flatnonzero((self.lattice[:, 0] == i) & (self.lattice[:, 1] == j))
        if not len(hits):
            raise ArgumentError("(i, j)", f"the sheet has no node at lattice (i, j) = ({i}, {j}); {self._reach()}")
        return int(hits[0])

    def cell(self, i: int, j: int) -> int:
        """The index of the cell whose first corner is lattice node (i, j); an ArgumentError
        naming ``(i, j)`` if there is no free one."""
        first = self.node(i, j)
        hits = np.flatnonzero(self.cell_nodes[:, 0] == first)
        if not len(hits):
            raise ArgumentError(
                "(i, j)",
                f"the sheet has no free cell at lattice (i, j) = ({i}, {j}) (a cell wholly inside the clamp "
                f"is not free); {self._reach()}",
            )
        return int(hits[0])

    def hinge(self, family: int, i: int, j: int) -> int:
        """The index of the ``family`` (WARP or WEFT) hinge at lattice node (i, j); an
        ArgumentError naming ``family`` or ``(i, j)`` if there is no free one."""
        if family not in (WARP, WEFT):
            raise ArgumentError("family", f"must be WARP ({WARP}) or WEFT ({WEFT}), got {family!r}")
        centre = self.node(i, j)
        hits = np.flatnonzero((self.hinge_nodes[:, 1] == centre) & (self.hinge_family == family))
        if not len(hits):
            raise ArgumentError(
                "(i, j)",
                f"the sheet has no free {('warp', 'weft')[family]} hinge at lattice ({i}, {j}) (a hinge needs "
                f"three nodes along its line and fabric of its own that bends); {self._reach()}",
            )
        return int(hits[0])


def grid_geometry(
    kept_cells: np.ndarray,
    spacing: tuple[float, float],
    origin: np.ndarray,
    warp_direction: np.ndarray,
    weft_direction: np.ndarray,
    is_clamped: Callable[[np.ndarray], np.ndarray],
    edge_hinge: str = "second_order",
    oblique_ends: bool = False,
    clamp_edge: tuple[np.ndarray, np.ndarray] | None = None,
    corner_shares: np.ndarray | None = None,
) -> SheetGeometry:
    """The geometry of the cut ``kept_cells`` (``[i, j]`` over the lattice's cells: bool, or
    the part of each cell's area the cut keeps, which weighs everything the cell carries:
    0 to 1, or to 2 where a cut lends a cell its neighbour's sliver), nodes at
    ``origin + i h_warp d_warp + j h_weft d_weft`` and clamped where
    ``is_clamped(rest_positions)`` is true. ``oblique_ends``: the cut's free edges cross
    the lines at an angle, and a line's last hinge carries the area of the node where it
    ends (on a cut along the lattice its moment vanishes there). Elements wholly inside the clamp move rigidly
    and are left out; a hinge with two clamped nodes and one free bends over h/2 under
    ``edge_hinge = "second_order"`` (scale 2), over h under ``"paper"``. ``clamp_edge``
    (a point on the clamp's edge and the unit vector in the sheet's plane from it into the
    free fabric) closes a clamp edge that crosses the lattice's lines between nodes through
    ghost nodes instead (docs/model.md §17.2): every hinge and twist carries only its
    fabric below the edge, free nodes within a spacing of it are slaved along the normal,
    and each held or slaved node an element reaches follows a free master there
    (:func:`_ghosts`). ``corner_shares`` (``[i, j, 4]``, corners 00, 10, 01, 11, summing to
    each cell's kept part) is how much of each cell its corners carry: their mass, their
    hinges' bending and their segments' widths (a segment, its two ends' shares); a
    quarter each by default; :func:`bias_strip` gives a clipped cell's shape-function
    integrals over its part."""
    if edge_hinge not in EDGE_HINGES:
        raise ArgumentError("edge_hinge", f"must be one of {', '.join(EDGE_HINGES)}, got {edge_hinge!r}")
    weight = np.asarray(kept_cells, dtype=float)
    if not ((weight >= 0) & (weight <= 2)).all():
        raise ArgumentError("kept_cells", "each cell's kept part must lie in [0, 2]")
    kept = weight > 0
    if not kept.any():
        raise ArgumentError("kept_cells", "the cut keeps no cell")
    h_warp, h_weft = spacing
    n_i, n_j = kept.shape[0] + 1, kept.shape[1] + 1
    padded = np.zeros((n_i + 1, n_j + 1))  # padded[i + 1, j + 1] = the kept part of cell (i, j)
    padded[1:-1, 1:-1] = weight

    def cell_kept(i: np.ndarray | int, j: np.ndarray | int) -> np.ndarray:
        return padded[np.asarray(i) + 1, np.asarray(j) + 1]

    ii, jj = np.meshgrid(np.arange(n_i), np.arange(n_j), indexing="ij")
    around = cell_kept(ii - 1, jj - 1) + cell_kept(ii - 1, jj) + cell_kept(ii, jj - 1) + cell_kept(ii, jj)
    active = around > 0
    # each node's share of each cell around it (four times, so a whole cell counts 1): a
    # quarter of each, or where the cut clips a cell its part's integral of the corner's
    # bilinear shape function: the row sums of the part's consistent mass and of its
    # consistent stiffness along a line, which lump the mass, the segments and the hinges
    quarter = np.repeat(weight[..., None] / 4.0, 4, axis=-1)
    shares = _at_nodes(4.0 * (quarter if corner_shares is None else corner_shares))
    index = np.full((n_i, n_j), -1)
    index[active] = np.arange(active.sum())
    lattice = np.column_stack([ii[active], jj[active]])
    rest = (
        np.asarray(origin, dtype=float)[None, :]
        + lattice[:, :1] * h_warp * np.asarray(warp_direction, dtype=float)[None, :]
        + lattice[:, 1:] * h_weft * np.asarray(weft_direction, dtype=float)[None, :]
    )
    clamped = np.asarray(is_clamped(rest), dtype=bool)
    if clamped.all() or not clamped.any():
        raise ArgumentError("is_clamped", "the clamp must hold some of the sheet's nodes and leave some free")
    carried = shares.sum(axis=-1)  # the cells' parts around each node: its mass, and what its bending stands on
    node_area = carried[active] * (h_warp * h_weft / 4.0)
    slaved = np.zeros(len(rest), dtype=bool)
    if clamp_edge is not None:
        point, inward = (np.asarray(v, dtype=float) for v in clamp_edge)
        below = (rest - point) @ inward  # ξ: how far below the clamp edge each node is at rest
        tolerance = 1e-9 * max(h_warp, h_weft)
        if (below[clamped] > tolerance).any() or (below[~clamped] <= tolerance).any():
            raise ArgumentError("clamp_edge", "the held nodes must be those at or above the clamp edge it gives")
        # the slaved (a node within round-off of a spacing is not, nor its mirror image)
        slaved = ~clamped & (below < SLAVED_DEPTH * max(h_warp, h_weft) - tolerance)
        below_grid = np.zeros((n_i, n_j))
        below_grid[active] = below
        # a hinge by its node's share of each cell (shape functions), a cell's twist by the
        # quarters of it below the edge
        parts = _quarters_below(below_grid, weight > 0)
        quarters = parts * _at_nodes(4.0 * quarter)
        carried = (parts * shares).sum(axis=-1)
    carried_area = carried[active] * (h_warp * h_weft / 4.0)

    def free(*nodes: np.ndarray) -> np.ndarray:
        return ~np.logical_and.reduce([clamped[n] for n in nodes])

    edges, families, widths = [], [], []
    for family, (di, dj), cross in ((WARP, (1, 0), h_weft), (WEFT, (0, 1), h_warp)):
        for i, j in zip(*np.nonzero(active), strict=True):
            k, m = i + di, j + dj
            if k >= n_i or m >= n_j or not active[k, m]:
                continue
            # the cells on either side of the segment, each by its two ends' shares of it (a
            # half of a whole cell: the side of a clipped cell nearer its part stretches more)
            if family == WARP:  # the cells (i, j − 1) and (i, j): the ends their corners 01, 11 and 00, 10
                ends = shares[i, j, 2] + shares[k, m, 0] + shares[i, j, 3] + shares[k, m, 1]
            else:  # the cells (i − 1, j) and (i, j): the ends their corners 10, 11 and 00, 01
                ends = shares[i, j, 1] + shares[k, m, 0] + shares[i, j, 3] + shares[k, m, 2]
            if ends > 0:
                edges.append((index[i, j], index[k, m]))
                families.append(family)
                widths.append(ends * cross / 4.0)
    edges_a = np.array(edges, dtype=np.int32).reshape(-1, 2)
    families_a = np.array(families, dtype=np.int32)
    widths_a = np.array(widths)
    segment = {(int(a), int(b)) for a, b in edges_a}
    keep = free(edges_a[:, 0], edges_a[:, 1])
    if clamp_edge is not None:  # a segment across the edge stretches only below it, as its ghost end sees
        depth = below[edges_a]
        across = (depth.min(axis=1) < 0) & (depth.max(axis=1) > 0)
        widths_a[across] *= depth[across].max(axis=1) / np.ptp(depth[across], axis=1)

    hinges, axes, h_families, h_widths, scales = [], [], [], [], []
    for family, (di, dj), cross in ((WARP, (1, 0), h_weft), (WEFT, (0, 1), h_warp)):
        ci, cj = dj, di  # the cross direction
        for i, j in zip(*np.nonzero(active), strict=True):
            before, after = (i - di, j - dj), (i + di, j + dj)
            if min(before) < 0 or after[0] >= n_i or after[1] >= n_j:
                continue
            a, b, c = index[before], index[i, j], index[after]
            if a < 0 or c < 0 or (a, b) not in segment or (b, c) not in segment:
                continue
            lower, upper = (i - ci, j - cj), (i + ci, j + cj)
            lo = index[lower] if min(lower) >= 0 and (index[lower], b) in segment else -1
            hi = index[upper] if upper[0] < n_i and upper[1] < n_j and (b, index[upper]) in segment else -1
            if lo < 0 and hi < 0:
                continue
            axis = (lo if lo >= 0 else b, hi if hi >= 0 else b)
            hinges.append((a, b, c))
            axes.append(axis)
            h_families.append(family)
            h_widths.append(carried[i, j] * cross / 4.0)
            at_edge = (clamped[a] and clamped[b] and not clamped[c]) or (clamped[c] and clamped[b] and not clamped[a])
            scales.append(2.0 if at_edge and edge_hinge == "second_order" and clamp_edge is None else 1.0)
    hinges_a = np.array(hinges, dtype=np.int32).reshape(-1, 3)
    if clamp_edge is not None:  # a hinge is kept where fabric below the edge bends at its node
        h_keep = np.array(h_widths) > 0
    else:
        h_keep = free(hinges_a[:, 0], hinges_a[:, 1], hinges_a[:, 2]) if len(hinges_a) else np.zeros(0, dtype=bool)
    order, pairs = _paired_first(hinges_a[:, 1], np.array(h_families, dtype=np.int32), h_keep)
    if oblique_ends:
        h_widths = _line_ends_carried(
            hinges_a, np.array(h_families), np.array(h_widths), h_keep, carried_area, clamped, spacing
        )

    ci_, cj_ = np.nonzero(kept)
    cells = np.column_stack(
        [index[ci_, cj_], index[ci_ + 1, cj_], index[ci_, cj_ + 1], index[ci_ + 1, cj_ + 1]]
    ).astype(np.int32)
    c_keep = free(cells[:, 0], cells[:, 1], cells[:, 2], cells[:, 3])
    if clamp_edge is not None:  # the part of each cell below the edge, its four quarters'
        corners = (ci_ + 1, cj_ + 1, 0), (ci_ + 1, cj_, 1), (ci_, cj_ + 1, 2), (ci_, cj_, 3)
        cell_below = sum(quarters[i, j, k] for i, j, k in corners) / 4.0
        c_keep |= cell_below > 0  # held and slaved corners may still twist fabric below the edge
    # A cell whose one free corner lies below a clamp edge through its other three (a
    # diamond of a bias cut) is half held: its free half shears and twists over half the
    # cell, as the clamp-edge hinge bends over h/2 (docs/model.md §17.5)
    astride = (clamped[cells].sum(axis=1) == 3) & (edge_hinge == "second_order") & (clamp_edge is None)
    cell_weight = weight[ci_, cj_] * np.where(astride, 0.5, 1.0)
    cell_scale = np.where(astride, 2.0, 1.0)
    # with ghosts, the shear and twist of the fields they extrapolate over the cell's part below the edge
    cell_part = cell_weight if clamp_edge is None else cell_below
    widths = np.array(h_widths)[order]
    lengths = np.array(spacing)[np.array(h_families, dtype=np.int64)[order]]
    normal = np.cross(warp_direction, weft_direction)
    normal = normal / np.linalg.norm(normal)
    ghost_nodes, ghost_masters, ghost_ratios = np.zeros(0, dtype=np.int32), np.zeros(0, dtype=np.int32), np.zeros(0)
    if clamp_edge is not None:
        reached = np.unique(
            np.concatenate(
                [hinges_a[order].ravel(), np.array(axes, dtype=np.int32).reshape(-1, 2)[order].ravel()]
                + [cells[c_keep].ravel()]
            )
        )
        ghost_nodes, ghost_masters, ghost_ratios = _ghosts(
            reached, below, (rest - point) @ np.cross(normal, inward), clamped, slaved, max(h_warp, h_weft)
        )
    return SheetGeometry(
        lattice=lattice,
        rest_positions=rest,
        clamped=clamped,
        node_area=node_area,
        spacing=(float(h_warp), float(h_weft)),
        edge_nodes=edges_a[keep],
        edge_family=families_a[keep],
        edge_width=widths_a[keep],
        hinge_nodes=hinges_a[order],
        hinge_axis_nodes=np.array(axes, dtype=np.int32).reshape(-1, 2)[order],
        hinge_family=np.array(h_families, dtype=np.int32)[order],
        hinge_width=widths,
        hinge_curvature_scale=np.array(scales)[order],
        hinge_pairs=pairs,
        hinge_coupling=_pair_coupling(widths * lengths, carried_area[hinges_a[order][:, 1]], pairs),
        cell_nodes=cells[c_keep],
        cell_area=cell_part[c_keep] * (h_warp * h_weft),
        cell_scale=cell_scale[c_keep],
        twist_area=(cell_part * cell_scale)[c_keep] * (h_warp * h_weft),
        rest_normal=normal,
        ghost_nodes=ghost_nodes,
        ghost_masters=ghost_masters,
        slaved=slaved,
        ghost_ratios=ghost_ratios,
        slaved_ghosts=int((~clamped[ghost_nodes]).sum()),
    )


def _at_nodes(per_corner: np.ndarray) -> np.ndarray:
    # [i, j, 4] over the nodes from [i, j, 4] over the cells (their corners 00, 10, 01, 11):
    # for each node, its value in the cells (i−1, j−1), (i−1, j), (i, j−1), (i, j) around it,
    # where it is their corner 11, 10, 01, 00 (0 beyond the lattice)
    n_i, n_j = per_corner.shape[0] + 1, per_corner.shape[1] + 1
    out = np.zeros((n_i, n_j, 4))
    for k, (a, b) in enumerate(((1, 1), (1, 0), (0, 1), (0, 0))):
        out[a : a + n_i - 1, b : b + n_j - 1, k] = per_corner[..., a + 2 * b]
    return out


def _quarters_below(below: np.ndarray, kept: np.ndarray) -> np.ndarray:
    # [i, j, 4] as :func:`_at_nodes`: the part of the quarter of each kept cell at each node
    # that lies below the clamp edge (ξ ≥ 0): ξ is affine over a cell, so the part is a
    # clipped square's area
    n_i, n_j = below.shape
    out = np.zeros((n_i, n_j, 4))
    for ci, cj in zip(*np.nonzero(kept), strict=True):
        corner = below[ci : ci + 2, cj : cj + 2]  # ξ at (ci + a, cj + b)
        for k, (a, b) in enumerate(((1, 1), (1, 0), (0, 1), (0, 0))):
            # the quarter at corner (a, b) spans u, v from the corner to the cell's middle
            u = np.array([a, 0.5, 0.5, a])
            v = np.array([b, b, 0.5, 0.5])
            xi = corner[0, 0] + u * (corner[1, 0] - corner[0, 0]) + v * (corner[0, 1] - corner[0, 0])
            out[ci + a, cj + b, k] = _part_where_nonnegative(xi)
    return out


def _part_where_nonnegative(values: np.ndarray) -> float:
    # the part of a parallelogram where an affine function, ``values`` at its four corners in
    # order round it, is ≥ 0 (clipped in its unit square's coordinates)
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    if (values >= 0).all():
        return 1.0
    points = []
    for k in range(4):
        p, q, fp, fq = square[k], square[(k + 1) % 4], values[k], values[(k + 1) % 4]
        if fp >= 0:
            points.append(p)
        if (fp >= 0) != (fq >= 0):
            points.append(p + fp / (fp - fq) * (q - p))
    return _area(np.array(points)) if len(points) >= 3 else 0.0


def _ghosts(
    reached: np.ndarray, below: np.ndarray, along: np.ndarray, held: np.ndarray, slaved: np.ndarray, spacing: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # A clamp holds the fabric at ξ = 0 with its slope: near it the displacement out of the
    # plane is w ≈ A(η) ξ². Each held or slaved node an element reaches (ξ_g ≠ 0) follows,
    # out of the plane, a master (free, not slaved) at ξ_m ≥ |ξ_g|, the ratio |ξ_g| / ξ_m at
    # most 1, the nearest by (η_m − η_g)² + (ξ_m − |ξ_g|)², ties (a cut and its mirror image)
    # to the master nearer the strip's middle: the slaved first
    free = np.flatnonzero(~held & ~slaved)
    if not len(free):
        raise ArgumentError("kept_cells", "no node hangs more than a spacing below the clamp edge")
    nodes, masters, ratios = [], [], []
    tolerance = 1e-9 * spacing
    for g in reached[held[reached] | slaved[reached]]:
        depth = abs(below[g])
        if depth <= tolerance:
            continue  # on the edge: its place is the clamp's
        candidates = free[below[free] >= depth - tolerance]
        if not len(candidates):  # a strip shorter than its ghosts reach: the deepest free node
            candidates = free[below[free] == below[free].max()]
        cost = ((along[candidates] - along[g]) ** 2 + (below[candidates] - depth) ** 2) / spacing**2
        order = np.lexsort((candidates, np.round(np.abs(along[candidates]) / spacing, 9), np.round(cost, 9)))
        m = candidates[order[0]]
        nodes.append(g)
        masters.append(m)
        ratios.append(depth / below[m])
    first = np.argsort(below[nodes] < 0, kind="stable")  # the slaved (below the edge) first
    return np.array(nodes, dtype=np.int32)[first], np.array(masters, dtype=np.int32)[first], np.array(ratios)[first]


def _line_ends_carried(
    hinges: np.ndarray,
    families: np.ndarray,
    widths: np.ndarray,
    keep: np.ndarray,
    node_area: np.ndarray,
    clamped: np.ndarray,
    spacing: tuple[float, float],
) -> np.ndarray:
    # A line's bending stands on its hinges, each over its node's area; a free node where a
    # line ends has none. Where the line meets a free edge square, its moment vanishes
    # there and so may its hinge; where it meets one at an angle (a bias cut's side) the
    # fabric there bends as the line's last hinge does: that hinge carries the end node's
    # area too, so the line bends over its whole length (docs/model.md §17.4).
    widths = widths.copy()
    centred = {(int(f), int(b)) for (_a, b, _c), f, k in zip(hinges, families, keep, strict=True) if k}
    for h in np.flatnonzero(keep):
        family = int(families[h])
        for end in (hinges[h, 0], hinges[h, 2]):
            if not clamped[end] and (family, int(end)) not in centred:
                widths[h] += node_area[end] / spacing[family]
    return widths


def _pair_coupling(carried: np.ndarray, centre_area: np.ndarray, pairs: int) -> np.ndarray:
    # the Poisson term −D12 K_warp K_weft acts over the area either hinge of a pair carries
    # (its node's, and a line end's beside it: A_pair = A_warp + A_weft − A_node); each
    # hinge's couple is that over its own area (docs/model.md §17.4)
    coupling = np.zeros(len(carried))
    warp, weft = np.arange(0, 2 * pairs, 2), np.arange(1, 2 * pairs, 2)
    shared = carried[warp] + carried[weft] - centre_area[warp]
    coupling[warp] = shared / carried[warp]
    coupling[weft] = shared / carried[weft]
    return coupling


def _paired_first(centres: np.ndarray, families: np.ndarray, keep: np.ndarray) -> tuple[np.ndarray, int]:
    # the kept hinges' order: a warp and a weft hinge at one node as neighbours 2k, 2k + 1
    # (the kernel pairs them for the Poisson term), then the unpaired in their own order
    kept = np.flatnonzero(keep)
    weft_at = {int(centres[h]): h for h in kept if families[h] == WEFT}
    paired = [(h, weft_at[int(centres[h])]) for h in kept if families[h] == WARP and int(centres[h]) in weft_at]
    first = [h for pair in paired for h in pair]
    taken = set(first)
    return np.array(first + [h for h in kept if h not in taken], dtype=np.int64), len(paired)


def rectangle(
    free_length: float,
    width: float,
    clamp_length: float,
    spacing: tuple[float, float],
    edge_hinge: str = "second_order",
) -> SheetGeometry:
    """A rectangular sheet hanging from a clamp along its top edge: warp down (−y), weft
    across (+z), ``clamp_length`` of it held above the clamp edge (y = 0), ``free_length``
    below, ``width`` across, centred on z = 0 (m; lengths whole multiples of the spacing)."""
    h_warp, h_weft = spacing
    rows = _cells(free_length + clamp_length, h_warp, argument="free_length", of="free_length + clamp_length = ")
    columns = _cells(width, h_weft, argument="width")
    clamp_rows = _cells(clamp_length, h_warp, argument="clamp_length")
    if clamp_rows < 1:
        raise ArgumentError("clamp_length", f"{clamp_length:g} m must hold at least one row of cells")
    return grid_geometry(
        np.ones((rows, columns), dtype=bool),
        spacing,
        origin=np.array([0.0, clamp_length, -width / 2.0]),
        warp_direction=np.array([0.0, -1.0, 0.0]),
        weft_direction=np.array([0.0, 0.0, 1.0]),
        is_clamped=lambda x: x[:, 1] >= -1e-9 * h_warp,
        edge_hinge=edge_hinge,
    )


def bias_strip(
    free_length: float,
    width: float,
    clamp_length: float,
    spacing: float,
    edge_hinge: str = "second_order",
    angle: float = math.pi / 4,
    is_clamped: Callable[[np.ndarray], np.ndarray] | None = None,
) -> SheetGeometry:
    """A strip cut with its length at ``angle`` (rad) to the warp, hanging from its top
    edge: the lattice turned by ``angle`` in the sheet's plane about the middle of the
    clamp edge, a node there, and every cell the strip's rectangle (``width`` across z,
    from ``free_length`` below the clamp edge to ``clamp_length`` above it) overlaps kept
    with the part of its area inside, which weighs its mass, widths, shear and twist
    (:func:`grid_geometry`). Its area is the rectangle's to round-off. On the 45° bias
    with a width of whole cell diagonals h√2 the sides run through nodes and the cut
    cells are halves; a row of nodes lies on the clamp edge whenever the angle is 0, 45°
    or 90°; at any other angle the clamp closes through ghost nodes (:func:`grid_geometry`'s
    ``clamp_edge``), unless ``edge_hinge`` is ``"paper"`` or ``is_clamped`` is given. Nodes at
    or above the clamp edge are clamped, or where ``is_clamped(rest positions)`` says (a
    free-free strip pinned at its mode's nodes, say)."""
    h = float(spacing)
    c, s = math.cos(angle), math.sin(angle)
    warp_direction = np.array([0.0, -c, s])
    weft_direction = np.array([0.0, -s, -c])
    # the lattice's index range over the rectangle's corners, a cell's margin round it
    corners = np.array([[y, z] for y in (clamp_length, -free_length) for z in (-width / 2, width / 2)])
    along = (corners @ warp_direction[1:]) / h
    across = (corners @ weft_direction[1:]) / h
    i0, j0 = math.floor(along.min()) - 1, math.floor(across.min()) - 1
    n_i, n_j = math.ceil(along.max()) + 1 - i0, math.ceil(across.max()) + 1 - j0
    origin = i0 * h * warp_direction + j0 * h * weft_direction
    ii, jj = np.meshgrid(np.arange(n_i), np.arange(n_j), indexing="ij")
    corner = origin[1:] + ii[..., None] * h * warp_direction[1:] + jj[..., None] * h * weft_direction[1:]
    quads = np.stack(
        [
            corner,
            corner + h * warp_direction[1:],
            corner + h * (warp_direction + weft_direction)[1:],
            corner + h * weft_direction[1:],
        ],
        axis=-2,
    )  # [i, j, corner, (y, z)], counter-clockwise or clockwise alike
    bounds = ((0, -1.0, -clamp_length), (0, 1.0, -free_length), (1, -1.0, -width / 2), (1, 1.0, -width / 2))
    # each cell's part inside, and that part lumped on its corners (00, 10, 01, 11) by their shape functions
    parts = [[_corner_shares(q, bounds, h, warp_direction[1:], weft_direction[1:]) for q in row] for row in quads]
    kept, shares = _slivers_lent(
        np.array([[part for part, _ in row] for row in parts]),
        np.array([[lumped for _, lumped in row] for row in parts]),
    )
    # a clamp edge through a row of nodes (the angle a multiple of 45°) closes there; one
    # between the nodes, through ghosts
    on_nodes = math.isclose(math.remainder(angle, math.pi / 4), 0.0, abs_tol=1e-12)
    ghosts = is_clamped is None and edge_hinge == "second_order" and not on_nodes
    return grid_geometry(
        kept,
        (h, h),
        origin=origin,
        warp_direction=warp_direction,
        weft_direction=weft_direction,
        is_clamped=is_clamped or (lambda x: x[:, 1] >= -1e-9 * h),
        edge_hinge=edge_hinge,
        oblique_ends=not (math.isclose(angle, 0.0, abs_tol=1e-12) or math.isclose(angle, math.pi / 2)),
        clamp_edge=(np.zeros(3), np.array([0.0, -1.0, 0.0])) if ghosts else None,
        corner_shares=shares,
    )


SLAVED_DEPTH = 1.0
"""How far below a clamp edge between the nodes (in spacings) a free node is slaved to the
clamped quadratic along the normal: there its master's displacement times (ξ / ξ_m)², in the
plane its own (docs/model.md §17.2). A node much nearer the edge than a spacing has hinges
that barely hold it out of the plane, and it would ring alone against the clamp; slaved
within h/2, the 22.5° cantilever's first mode converged at order 1.6, within h at 1.85
(−1.42 %, −0.39 % at 5 and 2.5 mm; with the clipped cells lumped on their corners by
their shape functions, at 2.05: −0.87 %, −0.21 %)."""

SLIVER = 0.25
"""A cut cell keeping less than this part of its area lends it to its fullest neighbour: a
node carrying only a sliver would be light against the elements of its neighbours and
shorten the stable step without bound (the cut's area is kept; where the fabric lies moves
by less than a cell)."""


def _slivers_lent(kept: np.ndarray, shares: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # the smallest sliver's area to its fullest neighbour, until none is left (a corner's
    # slivers gather into one cell), a quarter of it on each of the neighbour's corners (its
    # centroid then moves by up to half a cell: on a 20 mm strip at 22.5° the bending's
    # centroid by 0.02 mm, against 1e-14 mm without lending)
    kept, shares = kept.copy(), shares.copy()
    n_i, n_j = kept.shape
    while True:
        slivers = np.flatnonzero((kept > 0) & (kept < SLIVER))
        if not len(slivers):
            return kept, shares
        i, j = divmod(int(slivers[np.argmin(kept.flat[slivers])]), n_j)
        around = [(a, b) for a, b in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)) if 0 <= a < n_i and 0 <= b < n_j]
        a, b = max(around, key=lambda ab: kept[ab])
        if kept[a, b] <= 0:
            return kept, shares  # a lone sliver: nothing beside it to lend to (no cut makes one)
        kept[a, b] += kept[i, j]
        shares[a, b] += kept[i, j] / 4.0
        kept[i, j] = 0.0
        shares[i, j] = 0.0


def _corner_shares(
    quad: np.ndarray, bounds: tuple, h: float, warp: np.ndarray, weft: np.ndarray
) -> tuple[float, np.ndarray]:
    # the part of the cell ``quad`` [(y, z)] (corners 00, 10, 11, 01; side h) within
    # ``bounds``, in cell areas, and the integrals over it of its corners' bilinear shape
    # functions (00, 10, 01, 11): the row sums of its consistent mass, which keep the
    # part's area and centroid (a quarter each for a whole cell)
    points, area, whole = _inside(quad, bounds)
    part = area / (h * h)
    if area == 0.0 or area == whole:
        return part, np.full(4, part / 4.0)
    uv = (np.asarray(points) - quad[0]) @ np.column_stack([warp, weft]) / h
    shares = np.zeros(4)
    for k in range(1, len(uv) - 1):  # a fan of triangles, each by its edges' midpoints (exact for uv)
        a, b, c = uv[0], uv[k], uv[k + 1]
        triangle = 0.5 * abs((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
        for u, v in ((a + b) / 2, (b + c) / 2, (c + a) / 2):
            shares += triangle / 3.0 * np.array([(1 - u) * (1 - v), u * (1 - v), (1 - u) * v, u * v])
    return part, shares * (part / shares.sum())


def _inside(polygon: np.ndarray, bounds: tuple) -> tuple[list, float, float]:
    # the part of a convex polygon [(y, z)] within the half-planes sign·coordinate ≥ offset
    # (Sutherland-Hodgman), its area (a part smaller than 1e-9 of the polygon's taken as
    # none, one within 1e-12 of it as whole) and the polygon's
    whole = _area(polygon)
    points = list(polygon)
    for axis, sign, offset in bounds:
        inside = [sign * p[axis] >= offset for p in points]
        if all(inside):
            continue
        if not any(inside):
            return [], 0.0, whole
        clipped = []
        for k, p in enumerate(points):
            q = points[(k + 1) % len(points)]
            if inside[k]:
                clipped.append(p)
            if inside[k] != inside[(k + 1) % len(points)]:
                t = (offset - sign * p[axis]) / (sign * (q[axis] - p[axis]))
                clipped.append(p + t * (q - p))
        points = clipped
    area = _area(np.array(points))
    return points, 0.0 if area < 1e-9 * whole else (whole if area > (1 - 1e-12) * whole else area), whole


def _area(polygon: np.ndarray) -> float:
    y, z = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(float(np.dot(y, np.roll(z, -1)) - np.dot(z, np.roll(y, -1))))


def _cells(length: float, h: float, argument: str, of: str = "") -> int:
    # how many cells of h `length` is, or an ArgumentError naming `argument` (`of`: the
    # sum the length is, when it is not the argument alone)
    count = round(length / h)
    if count < 1 or abs(count * h - length) > 1e-9 * length:
        raise ArgumentError(argument, f"{of}{length:g} m is not a whole number of cells of {h:g} m")
    return int(count)


def quad_shear_angles(positions: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """The shear angle φ (rad) of each of ``quads`` ``[quad, 4]`` (corners (i, j), (i+1, j),
    (i+1, j+1), (i, j+1), as a run's mesh faces) with its nodes at ``positions``
    ``[..., node, xyz]``: ``[..., quad]``. φ = π/2 − the angle between the quad's mean warp
    and weft sides, zero at rest, positive as the warp leans toward the weft: the kernels'
    ``shear_angle`` of a cell (docs/model.md §17.5), in NumPy for what reads a run back."""
    x00, x10, x11, x01 = (positions[..., quads[:, k], :] for k in range(4))
    warp, weft = (x10 - x00 + x11 - x01) / 2, (x01 - x00 + x11 - x10) / 2
    return np.arctan2((warp * weft).sum(axis=-1), np.linalg.norm(np.cross(warp, weft), axis=-1))
