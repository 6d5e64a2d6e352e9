"""What advances a batch of sheets: symplectic Euler in the fused sheet kernel, every sheet
through a chunk of output samples per launch (docs/model.md §17.5)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse
import scipy.sparse.linalg
import warp as wp

from warpcloth.core.divergence import sample_lost
from warpcloth.core.solver import FusedSolver
from warpcloth.kernels import STATUS_BUDGET, STATUS_FOLDED, STATUS_NONFINITE_ENERGY, STATUS_STRAIN
from warpcloth.kernels import sheet as sheet_kernels
from warpcloth.kernels.sheet_structs import WARP, WEFT
from warpcloth.kernels.status import STATUS_CELL_COLLAPSED

from .geometry import SheetGeometry
from .model import SheetControl, SheetModel, SheetState

SHEETS_PER_THREAD = 4
"""A CPU launch is split among threads only into ranges of at least this many sheets."""

QUANTITY = {
    STATUS_STRAIN: ("tensile strain", "segment"),
    STATUS_FOLDED: ("hinge chord |p1 + p2|/h (the line folded onto itself)", "hinge"),
    STATUS_CELL_COLLAPSED: ("shear angle (rad)", "cell"),
    STATUS_NONFINITE_ENERGY: ("total energy (not finite)", ""),
    STATUS_BUDGET: (
        "energy budget gain, in peak kinetic energies (at least 1e-3 of the sheet's weight times its length; "
        "the step is unstable)",
        "",
    ),
}


@dataclass(frozen=True)
class SheetDivergence:
    """Where and how one sheet stopped: its index, the step and time, the quantity, the
    element (segment, hinge or cell) and its value."""

    sheet: int
    code: int
    step: int
    time_s: float
    element: int
    value: float
    dt_s: float
    stable_step_s: float

    @property
    def body(self) -> int:
        """The sheet's index in the batch (the name every body's report shares)."""
        return self.sheet

    @property
    def sample_lost(self) -> bool:
        """Whether the sample at :attr:`step` is unusable (an energy not finite or off
        budget); a strain, a fold or a collapsed cell keeps it, as a strip's does."""
        return sample_lost(self.code)

    def as_dict(self) -> dict:
        """The report as a run directory's meta.json writes it."""
        return asdict(self) | {"quantity": QUANTITY[self.code][0], "message": self.describe()}

    def describe(self) -> str:
        """One sentence a user can act on."""
        quantity, kind = QUANTITY[self.code]
        where = f" at {kind} {self.element}" if kind else ""
        phase = "while settling before t = 0" if self.time_s < 0 else "after t = 0"
        return (
            f"sheet {self.sheet} diverged {phase}, at t = {self.time_s:.6g} s (step {self.step}): {quantity} = "
            f"{self.value:.4g}{where}; try a smaller integrator.dt_s (now {self.dt_s:g} s; the linearised "
            f"stability estimate is {self.stable_step_s:.3g} s)"
        )


INSIDE_WHOLE_CELLS = {"segment": 4.0, "hinge": 16.0, "cell": 16.0}
"""The largest eigenvalue of each kind of element's operator (:func:`_largest_mode`, in
cells) deep inside whole cells, where the stability estimate's terms are the stiffest
modes (stretching exactly; bending and the cells' shear and twist with room to spare): a
line's stretching 4 and bending 16 (the zigzag), the cells' 16 (the twist's checkerboard,
which also scales their shear). A rectangle's edges and corners never exceed them, so the
estimate changes only where a cut cell makes a node light against its elements (and by up
to 3 % where whole cells' lines end at an angle, ``oblique_ends``, their last hinge
carrying the end node)."""

LARGEST_MODE_DENSE = 400
"""Up to this many nodes the operator's spectrum is solved whole (LAPACK), beyond it by
Lanczos (ARPACK)."""


def _largest_mode(nodes: np.ndarray, weights: np.ndarray, pattern: np.ndarray, area: np.ndarray) -> float:
    # the largest eigenvalue of M^-½ K M^-½ for K = Σ w p pᵀ over each element's nodes (p
    # its linearised strain on them, ``pattern[element, k]``), M the nodes' areas (a held
    # node's infinite): each element kind's stiffest mode, exactly, as a light node beside
    # heavy ones really rings (a bound per element by its lightest node would take a
    # clipped cell's corner outside the cut, which weighs its little shape function, for
    # the whole element's)
    if not len(nodes):
        return 0.0
    scale = np.where(np.isfinite(area), 1.0 / np.sqrt(area), 0.0)
    n = nodes.shape[1]
    rows = np.repeat(nodes, n, axis=1).ravel()
    cols = np.tile(nodes, (1, n)).ravel()
    values = (weights[:, None, None] * pattern[:, :, None] * pattern[:, None, :]).ravel() * scale[rows] * scale[cols]
    operator = scipy.sparse.csr_matrix((values, (rows, cols)), shape=(len(area),) * 2)
    moving = np.flatnonzero(scale > 0)
    operator = operator[moving][:, moving]
    if len(moving) <= LARGEST_MODE_DENSE:
        return float(np.linalg.eigvalsh(operator.toarray())[-1])
    return float(scipy.sparse.linalg.eigsh(operator, k=1, which="LA", return_eigenvectors=False, tol=1e-10)[0])


def _excess(
    geometry: SheetGeometry,
    nodes: np.ndarray,
    weights: np.ndarray,
    pattern: tuple,
    area: np.ndarray,
    element: str,
    families: np.ndarray | None = None,
    moves: str = "normal",
) -> float:
    # how much stiffer than deep inside whole cells a kind of element's stiffest mode is,
    # each family's alone as the estimate's terms are (at rest the segments of the two
    # move the nodes along different lines; the bending term's 64 covers both zigzags).
    # An element reaching a ghost moves its master (docs/model.md §17.2): along the normal
    # a held or slaved ghost by r² times the master's displacement, in the plane a held one
    # by −r times it (a slaved one moves in the plane as its own forces take it)
    coefficients = np.broadcast_to(np.asarray(pattern, dtype=float), nodes.shape).copy()
    ghosts = np.arange(geometry.slaved_ghosts if moves == "in_plane" else 0, len(geometry.ghost_nodes))
    if len(ghosts):
        master, ratio = np.arange(len(area)), np.ones(len(area))
        r = geometry.ghost_ratios[ghosts]
        master[geometry.ghost_nodes[ghosts]] = geometry.ghost_masters[ghosts]
        ratio[geometry.ghost_nodes[ghosts]] = -r if moves == "in_plane" else r * r
        coefficients *= ratio[nodes]
        nodes = master[nodes]
    groups = [np.ones(len(nodes), dtype=bool)] if families is None else [families == f for f in (WARP, WEFT)]
    excess = (
        max(_largest_mode(nodes[g], weights[g], coefficients[g], area) for g in groups) / INSIDE_WHOLE_CELLS[element]
    )
    return 1.0 if excess < 1.0 + 1e-9 else excess  # a free end's zigzag is the inside's, but for round-off


class SheetSolver(FusedSolver):
    """Symplectic Euler on every free node (velocities first, positions with the new
    velocity), the clamp's nodes on their prescribed motion, fixed ``dt``.

    A sheet stops, and is reported, when a segment's strain leaves ± ``divergence_strain``,
    a line folds onto itself, a cell's shear angle leaves ± ``divergence_shear`` (rad), or
    its energy is not finite.
    """

    label = "symplectic Euler"
    scheme = "semi_implicit"
    """The node update (kernels/integrators.py); a subclass names another."""
    bodies_per_thread = SHEETS_PER_THREAD

    def __init__(
        self, model: SheetModel, dt: float, divergence_strain: float = 0.25, divergence_shear: float = math.radians(60)
    ) -> None:
        super().__init__(model, dt)
        self.kernel = sheet_kernels.build(model.scalar, model.terms, self.scheme).advance
        self.divergence_strain = float(divergence_strain)
        self.divergence_shear = float(divergence_shear)

    def stable_step(self) -> float:
        """A linearised estimate of the longest stable dt (s): symplectic Euler needs
        ω_max dt < 2, and ω_max² is at most the sum of the stiffest stretching mode's
        4 (a1 + 2G)/(ρ_A h²), the stiffest bending mode's 64 (D + abs(D12)) s²/(ρ_A h⁴) (s the
        largest hinge curvature scale) and the twist's checkerboard 16 (4 D66)/(ρ_A h_w² h_f²)
        over the batch's materials and both directions, each times how much further than
        deep inside whole cells each kind of element's stiffest mode is on the cut
        (:data:`INSIDE_WHOLE_CELLS`: 1 on a rectangle; more where a cut cell leaves a
        corner node little fabric)."""
        g = self.model.geometry
        scale = float(g.hinge_curvature_scale.max()) if len(g.hinge_curvature_scale) else 1.0
        h_w, h_f = g.spacing
        # a free node's area in cells (1 inside, ½ on a side, ¼ at a corner); a held one never moves
        area = np.where(g.clamped, np.inf, g.node_area / (h_w * h_f))
        spacing = np.array(g.spacing)
        stretch_factor = _excess(
            g,
            g.edge_nodes,
            g.edge_width * spacing[g.edge_family] / (h_w * h_f),
            (1, -1),
            area,
            "segment",
            g.edge_family,
            "in_plane",
        )
        bend_factor = _excess(
            g,
            g.hinge_nodes,
            g.hinge_width * spacing[g.hinge_family] / (h_w * h_f),
            (1, -2, 1),
            area,
            "hinge",
            g.hinge_family,
        )
        cells = (g, g.cell_nodes, g.cell_area * g.cell_scale**2 / (h_w * h_f), (1, -1, -1, 1), area, "cell")
        cell_factor = max(_excess(*cells), _excess(*cells, moves="in_plane"))  # the twist's, the shear's
        worst = 0.0
        for spec in self.model.sheets:
            m = spec.material
            twist = 16 * m.twist_law()[0] / (m.density * h_w * h_w * h_f * h_f) * cell_factor
            for family, h in ((m.warp, h_w), (m.weft, h_f)):
                stretch = (
                    4 * (family.tensile[0] * stretch_factor + 2 * m.shear_rigidity * cell_factor) / (m.density * h * h)
                )
                rigidity = family.bending_rigidity + abs(m.poisson_coupling)
                bend = 64 * rigidity * scale * scale / (m.density * h**4) * bend_factor
                worst = max(worst, stretch + bend + twist)
        return 2.0 / math.sqrt(worst) if worst > 0 else math.inf

    def stepping(self, control: SheetControl) -> object:
        """The kernel's SheetStepping struct."""
        s = self.model.kernels.structs.SheetStepping()
        s.dt = self.model.scalar(self.dt)
        s.max_strain = self.model.scalar(self.divergence_strain)
        s.max_shear = self.model.scalar(self.divergence_shear)
        s.release_step = self.release_step(control)
        return s

    def divergence_report(self, state: SheetState, control: SheetControl, sheet: int) -> SheetDivergence | None:
        """Where and how ``sheet`` diverged, or None while it is healthy."""
        stopped = self.health(state, sheet)
        if stopped is None:
            return None
        code, step, element, value = stopped
        return SheetDivergence(
            sheet=sheet,
            code=code,
            step=step,
            time_s=(step - self.release_step(control)) * self.dt,
            element=element,
            value=value,
            dt_s=self.dt,
            stable_step_s=self.stable_step(),
        )

    def internal_forces(self, state: SheetState, control: SheetControl) -> dict[str, np.ndarray]:
        """The internal forces at the state's positions, ``[node, sheet, xyz]`` N, by kind
        (``tensile``, ``elastic``, ``hysteretic``); the laws' memory follows to them."""
        model = self.model
        wp.launch(
            model.kernels.internal_forces,
            dim=model.n_sheets,
            inputs=[model.struct, control.struct, self.stepping(control), state.struct],
            device=model.device,
        )
        s = state.struct
        return {
            "tensile": s.force_tensile.numpy(),
            "elastic": s.force_elastic.numpy(),
            "hysteretic": s.force_hysteretic.numpy(),
        }
