"""What a batch of sheets *is* (:class:`SheetModel`), *is doing* (:class:`SheetState`) and
what drives it (:class:`SheetControl`), built by :class:`SheetBuilder` (SI arrays only)."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
import warp as wp

from warpcloth.core.terms import checked_terms
from warpcloth.errors import ArgumentError
from warpcloth.kernels import bending_law
from warpcloth.kernels import sheet as sheet_kernels
from warpcloth.kernels.bending_masing import DEFAULT_CAPACITY
from warpcloth.kernels.drives import MAX_DEGREE
from warpcloth.kernels.sheet import SHEET_PROBES
from warpcloth.strip.builder import ClampMotion
from warpcloth.strip.model import PRECISIONS, machine_device
from warpcloth.strip.state import allocate_reversal_memory

from .geometry import SheetGeometry
from .material import SheetMaterialSI


def _unit(name: str, vector: object) -> np.ndarray:
    v = np.asarray(vector, dtype=float)
    norm = float(np.linalg.norm(v)) if v.shape == (3,) else 0.0
    if not norm > 0 or not np.isfinite(v).all():
        raise ArgumentError(name, f"must be a non-zero vector of 3 finite numbers, got {vector!r}")
    return v / norm


@dataclass(frozen=True)
class SheetClampMotion:
    """The clamp's rigid motion: a rotation θ(t) (rad) about the unit ``axis`` through
    ``centre`` (m, absolute) and then a translation d(t) (m) along the unit ``direction``,
    each as pieces of polynomials in t (:class:`~warpcloth.strip.ClampMotion`); no pieces:
    the clamp stands still."""

    rotation: ClampMotion = field(default_factory=ClampMotion)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)
    translation: ClampMotion = field(default_factory=ClampMotion)
    direction: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass(frozen=True)
class SheetSpec:
    """One sheet of a batch as :meth:`SheetBuilder.add_sheet` recorded it (SI)."""

    material: SheetMaterialSI
    damping: float
    settle_damping: float
    clamp: SheetClampMotion


class SheetBuilder:
    """Collects a batch of sheets cut alike (``geometry``), then :meth:`finalize` makes
    the :class:`SheetModel`. ``release_time`` > 0 lets the sheets settle for that long
    under ``settle_damping`` before t = 0 (the clamp's motion starts at t = 0).
    ``reversal_memory``: open reversal points per hinge and cell of a law with return-point
    memory (masing). ``compression_fraction``: a segment in compression is that part as stiff
    as its tensile quartic mirrored (1: as stiff; docs/model.md §17.3)."""

    def __init__(
        self,
        geometry: SheetGeometry,
        gravity: float = 9.80665,
        release_time: float = 0.0,
        reversal_memory: int = DEFAULT_CAPACITY,
        compression_fraction: float = 1.0,
    ) -> None:
        if not release_time >= 0:
            raise ArgumentError("release_time", f"must be ≥ 0 s, got {release_time!r}")
        if not 0 <= compression_fraction <= 1:
            raise ArgumentError(
                "compression_fraction", f"must lie in [0, 1] (of the tension's stiffness), got {compression_fraction!r}"
            )
        self.compression_fraction = float(compression_fraction)
        self.geometry = geometry
        self.gravity = float(gravity)
        self.release_time = float(release_time)
        self.reversal_memory = int(reversal_memory)
        self.sheets: list[SheetSpec] = []

    def add_sheet(
        self,
        material: SheetMaterialSI,
        *,
        damping: float = 0.0,
        settle_damping: float = 0.0,
        clamp: SheetClampMotion | None = None,
    ) -> int:
        """Add one sheet; returns its index in the batch."""
        clamp = clamp or SheetClampMotion()
        _unit("clamp.axis", clamp.axis)
        _unit("clamp.direction", clamp.direction)
        self.sheets.append(SheetSpec(material, float(damping), float(settle_damping), clamp))
        return len(self.sheets) - 1

    def finalize(self, device: str | None = None, precision: str = "float64", terms: tuple = ()) -> SheetModel:
        """The :class:`SheetModel` of every sheet added, on ``device`` in ``precision``, with
        the force ``terms`` (kernels/force_terms.py) acting on every free node."""
        if not self.sheets:
            raise ArgumentError("sheets", "a batch needs at least one sheet")
        if precision not in PRECISIONS:
            raise ArgumentError("precision", f"must be one of {', '.join(PRECISIONS)}, got {precision!r}")
        return SheetModel(self, device, precision, terms)


class SheetModel:
    """Static description of B sheets sharing one geometry and gravity; material, damping
    and drive per sheet (made by :meth:`SheetBuilder.finalize`)."""

    body = "sheet"
    """The body these are (:mod:`warpcloth.core.bodies`)."""
    dim = 3
    """Components of a node position: x, y, z."""

    def __init__(self, builder: SheetBuilder, device: str | None, precision: str, terms: tuple = ()) -> None:
        self.device = machine_device(device)
        self.precision = precision
        self.scalar = PRECISIONS[precision]
        self.terms = checked_terms(terms)
        """The force terms acting on every free node besides damping and gravity (kernels/force_terms.py)."""
        self.probes = SHEET_PROBES.with_terms(self.terms)
        """What the sheets record: :data:`~warpcloth.kernels.sheet.SHEET_PROBES` and the terms' channels."""
        self.kernels = sheet_kernels.build(self.scalar, self.terms)
        self.types = self.kernels.types
        self.geometry = builder.geometry
        self.sheets = tuple(builder.sheets)
        self.n_sheets = len(self.sheets)
        self.n_nodes = self.geometry.n_nodes
        self.gravity = builder.gravity
        self.compression_fraction = builder.compression_fraction
        self.release_time = builder.release_time
        materials = [s.material for s in self.sheets]
        self.density = np.array([m.density for m in materials])
        uses_history = any(
            bending_law(law).uses_reversal_memory
            for m in materials
            for law in (m.warp.bending_law, m.weft.bending_law, m.shear.law, m.twist_law()[1].law)
        )
        self.reversal_memory = builder.reversal_memory if uses_history else 0
        self.struct = self._build_struct(materials)

    def array(self, values: np.ndarray, dtype: object = None) -> wp.array:
        """A Warp array of ``values`` on this model's device in its precision."""
        return wp.array(np.ascontiguousarray(values), dtype=dtype or self.scalar, device=self.device)

    @property
    def n_bodies(self) -> int:
        """The sheets of the batch (the name every body's model shares)."""
        return self.n_sheets

    @property
    def position_type(self) -> object:
        """The Warp vector of a node position."""
        return self.types.vec3

    def budget_floor(self) -> np.ndarray:
        """The least energy scale each sheet's budget is judged at (the strip's rule,
        :data:`~warpcloth.core.divergence.BUDGET_TOLERANCE`): 1e-3 of its free nodes' weight
        times its free length, or of its warp's D W / L where that is larger (without gravity)."""
        g = self.geometry
        free = ~g.clamped
        length = float(np.ptp(g.rest_positions[:, 1])) or max(g.spacing)
        width = float(np.ptp(g.rest_positions[:, 2])) or max(g.spacing)
        weight = self.density * float(g.node_area[free].sum()) * self.gravity * length
        bending = np.array([s.material.warp.bending_rigidity for s in self.sheets]) * width / length
        return 1e-3 * np.maximum(weight, bending)

    def node_mass(self) -> np.ndarray:
        """``[node, sheet]`` masses, kg."""
        return self.geometry.node_area[:, None] * self.density[None, :]

    def state(self) -> SheetState:
        """A state at rest in the rest shape, every hinge and cell fresh."""
        return SheetState(self)

    def control(self) -> SheetControl:
        """The drives the sheets were built with."""
        return SheetControl(self)

    @functools.cached_property
    def rest_control(self) -> SheetControl:
        """The drives, read at the clamp's rest pose where a state is set (slaved nodes
        follow their masters from there, docs/model.md §17.2)."""
        return SheetControl(self)

    def _build_struct(self, materials: list[SheetMaterialSI]) -> object:
        g, t, law = self.geometry, self.types, self.kernels.structs.law
        b = self.n_sheets
        m = self.kernels.structs.SheetModel()
        m.n_nodes = self.n_nodes
        m.gravity = self.scalar(self.gravity)
        m.compression = self.scalar(self.compression_fraction)
        m.rest_position = self.array(np.repeat(g.rest_positions[:, None, :], b, axis=1), t.vec3)
        m.clamped = self.array(g.clamped.astype(np.int32), int)
        m.slaved = self.array(g.slaved.astype(np.int32), int)
        m.node_area = self.array(g.node_area)
        m.density = self.array(self.density)
        m.damping = self.array(np.array([s.damping for s in self.sheets]))
        m.spacing = self.array(np.array(g.spacing))
        m.edge_nodes = self.array(g.edge_nodes.astype(np.int32), wp.vec2i)
        m.edge_family = self.array(g.edge_family.astype(np.int32), int)
        m.edge_width = self.array(g.edge_width)
        m.hinge_nodes = self.array(g.hinge_nodes.astype(np.int32).reshape(-1, 3), wp.vec3i)
        m.hinge_axis_nodes = self.array(g.hinge_axis_nodes.astype(np.int32).reshape(-1, 2), wp.vec2i)
        m.hinge_family = self.array(g.hinge_family.astype(np.int32), int)
        m.hinge_width = self.array(g.hinge_width)
        m.hinge_curvature_scale = self.array(g.hinge_curvature_scale)
        m.hinge_pairs = g.hinge_pairs
        m.hinge_coupling = self.array(g.hinge_coupling)
        m.cell_nodes = self.array(g.cell_nodes.astype(np.int32).reshape(-1, 4), wp.vec4i)
        m.cell_area = self.array(g.cell_area)
        m.cell_scale = self.array(g.cell_scale)
        m.twist_area = self.array(g.twist_area)
        m.rest_normal = t.vec3(*g.rest_normal)
        m.ghost_nodes = self.array(g.ghost_nodes.astype(np.int32), int)
        m.ghost_masters = self.array(g.ghost_masters.astype(np.int32), int)
        m.ghost_ratios = self.array(g.ghost_ratios)
        m.slaved_ghosts = g.slaved_ghosts
        m.tensile = self.array(
            np.array([[mat.warp.tensile for mat in materials], [mat.weft.tensile for mat in materials]]), t.vec4
        )
        m.bending = self.array(
            np.array(
                [
                    [mat.warp.bending_parameters() for mat in materials],
                    [mat.weft.bending_parameters() for mat in materials],
                ]
            ),
            law.Parameters,
        )
        m.shear = self.array(np.array([mat.shear_parameters() for mat in materials]), law.Parameters)
        m.twist = self.array(np.array([mat.twist_parameters() for mat in materials]), law.Parameters)
        m.twist_elastic = self.array(np.array([mat.twist_is_elastic() for mat in materials], dtype=np.int32), int)
        m.poisson = self.array(np.array([mat.poisson_coupling for mat in materials]))
        return m


class SheetState:
    """Dynamic state of B sheets, laid out ``[node, sheet]``; starts at rest in the rest
    shape with fresh hinges and cells."""

    def __init__(self, model: SheetModel) -> None:
        self.model = model
        t, law = model.types, model.kernels.structs.law
        n, b = model.n_nodes, model.n_sheets
        g = model.geometry
        n_hinges, n_cells = len(g.hinge_nodes), len(g.cell_nodes)

        def nodes() -> wp.array:
            return wp.zeros((n, b), dtype=t.vec3, device=model.device)

        s = model.kernels.structs.SheetState()
        s.position = wp.clone(model.struct.rest_position)
        s.velocity = nodes()
        s.force_tensile = nodes()
        s.force_elastic = nodes()
        s.force_hysteretic = nodes()
        s.hinge = wp.zeros((max(1, n_hinges), b), dtype=law.Memory, device=model.device)
        s.cell = wp.zeros((max(1, n_cells), b), dtype=law.Memory, device=model.device)
        s.hinge_history = allocate_reversal_memory(
            law.History, model.reversal_memory, max(1, n_hinges), b, t.vec2, model.device
        )
        s.cell_history = allocate_reversal_memory(
            law.History, model.reversal_memory, max(1, n_cells), b, t.vec2, model.device
        )
        s.twist = wp.zeros((max(1, n_cells), b), dtype=law.Memory, device=model.device)
        s.twist_history = allocate_reversal_memory(
            law.History, model.reversal_memory, max(1, n_cells), b, t.vec2, model.device
        )
        n_ghosts = max(1, len(g.ghost_nodes))
        s.ghost_offset = wp.zeros((n_ghosts, b), dtype=t.vec3, device=model.device)
        s.ghost_held = wp.zeros((n_ghosts, b), dtype=t.vec3, device=model.device)
        s.clamp_normal = wp.array(np.repeat(g.rest_normal[None, :], b, axis=0), dtype=t.vec3, device=model.device)
        s.work = wp.zeros(b, dtype=model.kernels.structs.tally, device=model.device)
        s.step = wp.zeros(b, dtype=int, device=model.device)
        s.status = wp.zeros(b, dtype=int, device=model.device)
        s.status_step = wp.zeros(b, dtype=int, device=model.device)
        s.status_index = wp.zeros(b, dtype=int, device=model.device)
        s.status_value = wp.zeros(b, dtype=t.scalar, device=model.device)
        self.struct = s
        self.reset_memory()

    def positions(self) -> np.ndarray:
        """``[node, sheet, xyz]`` now, m."""
        return self.struct.position.numpy()

    def set_positions(self, positions: np.ndarray, velocities: np.ndarray | None = None) -> None:
        """Replace node positions ``[node, sheet, 3]`` (and velocities), m and m/s, and
        start every hinge and cell fresh there. A slaved node (docs/model.md §17.2) takes
        its coordinate along the normal from its master, at the clamp's rest pose."""
        expected = (self.model.n_nodes, self.model.n_sheets, 3)
        for name, value in (("positions", positions), ("velocities", velocities)):
            if value is None:
                continue
            array = np.asarray(value, dtype=float)
            if array.shape != expected or not np.isfinite(array).all():
                raise ArgumentError(
                    name, f"must be {expected} finite numbers ([node, sheet, xyz]), got shape {array.shape}"
                )
            target = self.struct.position if name == "positions" else self.struct.velocity
            target.assign(self.model.array(array, self.model.types.vec3))
        self.reset_memory()

    def reset_memory(self) -> None:
        """Make every hinge and cell fresh at its current curvature and shear angle."""
        for history in (self.struct.hinge_history, self.struct.cell_history, self.struct.twist_history):
            history.overflows.zero_()
            history.deepest.zero_()
        wp.launch(
            self.model.kernels.initialise_memory,
            dim=self.model.n_sheets,
            inputs=[self.model.struct, self.model.rest_control.struct, self.struct],
            device=self.model.device,
        )

    def reversal_report(self) -> dict[str, object]:
        """The reversal memory's use: capacity, and per sheet the deepest any hinge or cell
        went and the reversals not stored (empty when no law keeps any)."""
        capacity = self.model.reversal_memory
        if not capacity:
            return {}
        histories = (self.struct.hinge_history, self.struct.cell_history, self.struct.twist_history)
        return {
            "capacity": capacity,
            "deepest": np.max([h.deepest.numpy() for h in histories], axis=0).tolist(),
            "overflows": np.sum([h.overflows.numpy() for h in histories], axis=0).tolist(),
        }


def _pieces(motions: list[ClampMotion]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    n_pieces = max(1, max(len(m.start) for m in motions))
    b = len(motions)
    start, end = np.zeros((n_pieces, b)), np.zeros((n_pieces, b))
    coefficients = np.zeros((n_pieces, b, MAX_DEGREE + 1))
    for s, m in enumerate(motions):
        n = len(m.start)
        start[:n, s], end[:n, s], coefficients[:n, s] = m.start, m.end, m.coefficients
    return start, end, coefficients, np.array([len(m.start) for m in motions], dtype=np.int32)


class SheetControl:
    """The clamp's rotation and translation per sheet, and the settling before t = 0."""

    def __init__(self, model: SheetModel) -> None:
        self.release_time = model.release_time
        self.move_time = 0.0
        clamps = [s.clamp for s in model.sheets]
        t = model.types
        c = model.kernels.structs.SheetControl()
        start, end, coefficients, count = _pieces([k.rotation for k in clamps])
        c.rotation_start, c.rotation_end = model.array(start), model.array(end)
        c.rotation_coefficients = model.array(coefficients, t.vec5)
        c.rotation_segments = model.array(count, int)
        start, end, coefficients, count = _pieces([k.translation for k in clamps])
        c.translation_start, c.translation_end = model.array(start), model.array(end)
        c.translation_coefficients = model.array(coefficients, t.vec5)
        c.translation_segments = model.array(count, int)
        c.axis = model.array(np.array([_unit("clamp.axis", k.axis) for k in clamps]), t.vec3)
        c.centre = model.array(np.array([k.centre for k in clamps], dtype=float), t.vec3)
        c.direction = model.array(np.array([_unit("clamp.direction", k.direction) for k in clamps]), t.vec3)
        c.settle_damping = model.array(np.array([s.settle_damping for s in model.sheets]))
        self.struct = c
