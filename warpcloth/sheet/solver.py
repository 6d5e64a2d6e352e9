"""What advances a batch of sheets: symplectic Euler in the fused sheet kernel, every sheet
through a chunk of output samples per launch (docs/model.md §17.5)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
import warp as wp

from warpcloth.core.divergence import sample_lost
from warpcloth.core.solver import FusedSolver
from warpcloth.kernels import STATUS_BUDGET, STATUS_FOLDED, STATUS_NONFINITE_ENERGY, STATUS_STRAIN
from warpcloth.kernels import sheet as sheet_kernels
from warpcloth.kernels.status import STATUS_CELL_COLLAPSED

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


WHOLE_CELL_EXCESS = {"segment": 2.0, "hinge": 2.0, "cell": 4.0}
"""The most an element's width (a cell's area) exceeds its lightest free node's area on a
cut of whole cells, in cells: a side's segment or hinge at a corner node (½ over ¼), a
corner cell (1 over ¼). The stability estimate's bounds hold there, so only what a cut
cell adds beyond it shortens the step."""


def _excess(ratios: np.ndarray, element: str) -> float:
    # how much further than on whole cells an element's stiffness outweighs its lightest free node
    return max(1.0, float(ratios.max(initial=0.0)) / WHOLE_CELL_EXCESS[element])


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
        on whole cells the cut's element widths outweigh their lightest free node
        (:data:`WHOLE_CELL_EXCESS`: 1 on a whole-cell cut; more where a cut cell leaves a
        corner node little fabric)."""
        g = self.model.geometry
        scale = float(g.hinge_curvature_scale.max()) if len(g.hinge_curvature_scale) else 1.0
        h_w, h_f = g.spacing
        # a free node's area in cells (1 inside, ½ on a side, ¼ at a corner); a held one never moves
        area = np.where(g.clamped, np.inf, g.node_area / (h_w * h_f))
        spacing = np.array(g.spacing)
        stretch_factor = _excess(
            g.edge_width * spacing[g.edge_family] / (h_w * h_f) / area[g.edge_nodes].min(axis=1), "segment"
        )
        five = np.concatenate([g.hinge_nodes, g.hinge_axis_nodes], axis=1)
        bend_factor = _excess(g.hinge_width * spacing[g.hinge_family] / (h_w * h_f) / area[five].min(axis=1), "hinge")
        cell_factor = _excess(g.cell_area * g.cell_scale**2 / (h_w * h_f) / area[g.cell_nodes].min(axis=1), "cell")
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
