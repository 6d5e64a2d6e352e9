"""Sheet scenes → simulation objects (SI): the only place that reads a sheet scene's fields
to simulate, and the checks that need the geometry or the step (markers on the sheet, dt
within the stability estimate)."""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from warpcloth import units
from warpcloth.core.resources import check_memory
from warpcloth.errors import ArgumentError, SceneError
from warpcloth.kernels.sheet_structs import WARP, WEFT
from warpcloth.sheet import (
    SheetBuilder,
    SheetClampMotion,
    SheetControl,
    SheetGeometry,
    SheetMaterialSI,
    SheetModel,
    SheetRecorder,
    SheetSolver,
    bias_strip,
    rectangle,
)
from warpcloth.strip import ClampMotion

from .clamp_motion import segment_pieces
from .files import _read_scene
from .locate import located, variant_error
from .materials import to_si
from .overrides import Overrides, apply_overrides
from .sheet import AUTO, AUTO_FRACTION, SheetScene, SheetSection, nodes_at_most, sheet_scene_from_dict
from .validate import check_step_count

FAMILIES = {"warp": WARP, "weft": WEFT}

ON_NODE = 0.01
"""A marker given in mm must lie on a node to within this part of the spacing: the run
records nodes, so a marker between them would be compared with a point it is not."""


@dataclass
class SheetBatch:
    """What :func:`build_sheet` makes: the model, its drives, the solver and the recorder."""

    model: SheetModel
    control: SheetControl
    solver: SheetSolver
    recorder: SheetRecorder


def sheet_geometry(scene: SheetScene) -> SheetGeometry:
    """The scene's cut, in SI (one object per ``[sheet]`` table: a sweep's variants that
    share their cut share it, so it is built once; it is never written to)."""
    return _cut(scene.sheet)


@functools.lru_cache(maxsize=16)
def _cut(st: SheetSection) -> SheetGeometry:
    # ~25 ms of Python for a 5 mm sheet: a sweep checks and sizes every variant with it
    mm = units.LENGTH_MM
    lengths = (st.free_length_mm * mm, st.width_mm * mm, st.clamp_length_mm * mm)
    spacing = (st.spacing_warp_mm * mm, st.spacing_weft_mm * mm)
    if st.cut == "rectangle":
        geometry = rectangle(*lengths, spacing, st.edge_hinge)
    else:
        geometry = bias_strip(*lengths, spacing[0], st.edge_hinge, math.radians(st.bias_angle_deg))
    if not st.initial_waviness_mm:
        return geometry
    # a node's depth below the clamp edge and place across: the clamp's nodes (s = 0) stay put
    rest = geometry.rest_positions.copy()
    depth = np.clip(-rest[:, 1], 0.0, lengths[0]) / lengths[0]
    across = np.clip(rest[:, 2] / lengths[1] + 0.5, 0.0, 1.0)
    rest[:, 0] += st.initial_waviness_mm * mm * np.sin(math.pi * depth) * np.sin(math.pi * across)
    return dataclasses.replace(geometry, rest_positions=rest)


def sheet_material(scene: SheetScene) -> SheetMaterialSI:
    """The fabric in SI: warp, weft and bias by :func:`~warpcloth.scene.to_si`, shear by
    :meth:`~warpcloth.scene.ShearMaterial.si` (the one KES → SI conversion of each)."""
    rigidity, shear = scene.shear.si()
    return SheetMaterialSI(
        to_si(scene.material),
        to_si(scene.weft_material()),
        rigidity,
        shear,
        to_si(scene.bias_material()),
        scene.bias.bending_poisson_ratio,
    )


def sheet_clamp(scene: SheetScene) -> SheetClampMotion:
    """The clamp's rotation and translation in SI, the centre absolute (from the clamp edge's middle)."""
    c = scene.clamp
    return SheetClampMotion(
        rotation=ClampMotion(*segment_pieces(c.rotation_segments, "theta_coefficients_si")),
        axis=(c.axis_x, c.axis_y, c.axis_z),
        centre=tuple(units.LENGTH_MM * v for v in (c.centre_dx_mm, c.centre_dy_mm, c.centre_dz_mm)),
        translation=ClampMotion(*segment_pieces(c.translation_segments, "d_coefficients_mm", units.LENGTH_MM)),
        direction=(c.direction_x, c.direction_y, c.direction_z),
    )


SHARED_SECTIONS = ("sheet", "integrator", "run", "output")
"""What every sheet of a batch shares (the cut, the step, the duration, what is recorded),
with the settling time: a batch's sheets differ in material, weft, shear, damping,
settling damping and clamp motion only."""


def sheet_batch_key(scene: SheetScene, with_step: bool = True) -> str:
    """What ``scene`` shares with every sheet of its batch, as text: equal for two scenes
    exactly when :func:`check_sheet_batch` lets them run together (``with_step=False``:
    but for the step, ``integrator.dt_s`` and ``dt_chosen_by``)."""
    d = scene.to_dict()
    shared = {section: d[section] for section in SHARED_SECTIONS} | {"settle_time_s": d["release"]["settle_time_s"]}
    if not with_step:
        shared["integrator"] = {k: v for k, v in shared["integrator"].items() if k not in ("dt_s", "dt_chosen_by")}
    return json.dumps(shared, sort_keys=True)


def check_sheet_batch(scenes: Sequence[SheetScene]) -> None:
    """Refuse, naming the field, a batch whose scenes differ where sheets of one launch
    cannot (:data:`SHARED_SECTIONS`, ``release.settle_time_s``)."""
    if not scenes:
        raise SceneError("scenes", "a batch needs at least one sheet scene")
    first = scenes[0]
    for j, scene in enumerate(scenes[1:], start=1):
        for section in SHARED_SECTIONS:
            ours, theirs = getattr(first, section), getattr(scene, section)
            for f in dataclasses.fields(ours):
                if getattr(ours, f.name) != getattr(theirs, f.name):
                    raise SceneError(
                        f"{section}.{f.name}",
                        f"sheets of one batch share it: variant {j} has {getattr(theirs, f.name)!r}, "
                        f"variant 0 {getattr(ours, f.name)!r}",
                        variant=j,
                    )
        if scene.release.settle_time_s != first.release.settle_time_s:
            raise SceneError(
                "release.settle_time_s",
                f"sheets of one batch share it: variant {j} has {scene.release.settle_time_s!r}, "
                f"variant 0 {first.release.settle_time_s!r}",
                variant=j,
            )


def _builder(scenes: Sequence[SheetScene], geometry: SheetGeometry) -> SheetBuilder:
    first = scenes[0]
    builder = SheetBuilder(
        geometry,
        first.run.gravity_m_per_s2,
        release_time=first.release.settle_time_s,
        reversal_memory=first.integrator.reversal_memory,
        compression_fraction=first.sheet.yarn_compression_fraction,
    )
    for scene in scenes:
        builder.add_sheet(
            sheet_material(scene),
            damping=scene.damping.gamma_per_s,
            settle_damping=scene.release.settle_damping_per_s,
            clamp=sheet_clamp(scene),
        )
    return builder


def _nearest(points: np.ndarray, yz_mm: list[float]) -> tuple[int, float]:
    # in the sheet's plane: a wavy sheet's nodes lie off it by its waviness, not elsewhere
    target = np.array(yz_mm) * units.LENGTH_MM
    distance = np.linalg.norm(points[:, 1:] - target[None, :], axis=1)
    k = int(np.argmin(distance))
    return k, float(distance[k])


def marker_nodes(scene: SheetScene, geometry: SheetGeometry) -> list[int]:
    """The tracked nodes, ``output.markers_ij`` then ``output.markers_mm``; a SceneError
    naming the marker when it is not on the sheet."""
    nodes = []
    for i, (a, b) in enumerate(scene.output.markers_ij):
        try:
            nodes.append(geometry.node(a, b))
        except ArgumentError:
            top = geometry.lattice.max(axis=0)
            raise SceneError(
                f"output.markers_ij[{i}]",
                f"[{a}, {b}] is not a node of the sheet (its lattice reaches i ≤ {top[0]}, j ≤ {top[1]}, "
                "where the cut keeps cells)",
                related=("sheet.cut", "sheet.spacing_warp_mm", "sheet.spacing_weft_mm"),
            ) from None
    reach = ON_NODE * min(geometry.spacing)
    for i, yz in enumerate(scene.output.markers_mm):
        k, distance = _nearest(geometry.rest_positions, yz)
        if distance > reach:
            y, z = geometry.rest_positions[k, 1:] / units.LENGTH_MM
            raise SceneError(
                f"output.markers_mm[{i}]",
                f"[{yz[0]:g}, {yz[1]:g}] mm is not on a node of the sheet: the nearest, [{y:.6g}, {z:.6g}] mm, is "
                f"{distance * 1e3:.3g} mm away (more than {ON_NODE:.0%} of a spacing); a marker is a node, so "
                f"give a node's position, or its lattice position in output.markers_ij (the sheet hangs from "
                f"y = 0 to -{scene.sheet.free_length_mm:g} mm, z within ±{scene.sheet.width_mm / 2:g} mm)",
                related=("sheet.free_length_mm", "sheet.width_mm", "sheet.spacing_warp_mm", "sheet.spacing_weft_mm"),
            )
        nodes.append(k)
    return nodes


def probed_elements(scene: SheetScene, geometry: SheetGeometry) -> tuple[int, int]:
    """(cell, hinge) probed: the free ones nearest ``output.probe_cell_mm`` (a cell's
    centre) and ``probe_hinge_mm`` (a hinge's node), each within half a cell's diagonal
    (as far as a point of the sheet can be from both), else a SceneError naming the field
    and the nearest one's position."""
    rest = geometry.rest_positions
    reach = 0.5 * float(np.hypot(*geometry.spacing)) * (1 + 1e-9)
    family = FAMILIES[scene.output.probe_hinge_family]
    candidates = np.flatnonzero(geometry.hinge_family == family)
    if not len(candidates):
        raise SceneError(
            "output.probe_hinge_family",
            f"the sheet has no free {scene.output.probe_hinge_family} hinge (a line needs three nodes)",
        )
    found = []
    for name, places, what in (
        ("probe_cell_mm", rest[geometry.cell_nodes].mean(axis=1), "free cell's centre"),
        ("probe_hinge_mm", rest[geometry.hinge_nodes[candidates, 1]], f"free {scene.output.probe_hinge_family} hinge"),
    ):
        yz = getattr(scene.output, name)
        k, distance = _nearest(places, yz)
        if distance > reach:
            y, z = places[k, 1:] / units.LENGTH_MM
            raise SceneError(
                f"output.{name}",
                f"[{yz[0]:g}, {yz[1]:g}] mm is {distance * 1e3:.3g} mm from the nearest {what}, "
                f"[{y:.6g}, {z:.6g}] mm (more than half a cell's diagonal): give a position on the sheet, "
                "[y, z] in mm from the middle of the clamp edge (elements wholly inside the clamp are not free)",
                related=("output.probe_hinge_family",) if name == "probe_hinge_mm" else (),
            )
        found.append(k)
    return found[0], int(candidates[found[1]])


def sheet_state_bytes(n_nodes: float, n_elements: float, reversal_memory: int) -> float:
    """What one sheet's model and state hold, bytes: per node its rest and current
    position, velocity and three force buffers (float64 3-vectors) and its area; per
    hinge and per cell its law's memory and, for a law with return-point memory, its
    reversal points (``reversal_memory`` + 1 pairs)."""
    return 6 * 24 * n_nodes + 8 * n_nodes + n_elements * (24 + 16 * (reversal_memory + 1) + 48)


def check_sheet_scene(scene: SheetScene) -> SheetScene:
    """The scene ready to run: markers on the sheet, memory that fits, and ``dt_s`` within
    the stability estimate (``"auto"``: :data:`~warpcloth.scene.sheet.AUTO_FRACTION` of it,
    a whole fraction of the probe interval, recorded with ``dt_chosen_by = "auto"``)."""
    # sized from the cut's bounding rectangle before the cut is built (node by node, in Python)
    nodes = nodes_at_most(scene.sheet)
    knobs = "use a coarser sheet.spacing_warp_mm / spacing_weft_mm"
    check_memory(
        sheet_state_bytes(nodes, 3 * nodes, scene.integrator.reversal_memory),
        f"the state of a sheet of up to {nodes:.3g} nodes",
        knobs,
    )
    try:
        geometry = sheet_geometry(scene)
    except ArgumentError as exc:  # a bias cut narrower than a cell, a clamp holding nothing
        raise SceneError("sheet.cut", f"{scene.sheet.cut}: {exc.message}", related=("sheet.width_mm",)) from None
    marker_nodes(scene, geometry)
    probed_elements(scene, geometry)
    check_memory(
        sheet_state_bytes(
            geometry.n_nodes, len(geometry.hinge_nodes) + len(geometry.cell_nodes), scene.integrator.reversal_memory
        ),
        f"the state of a sheet of {geometry.n_nodes} nodes",
        knobs,
    )
    model = _builder([scene], geometry).finalize(device="cpu", precision=scene.integrator.precision)
    stable = SheetSolver(model, 1.0).stable_step()
    dt = scene.integrator.dt_s
    if dt == AUTO:
        interval = scene.output_interval
        chosen = interval / math.ceil(interval / (AUTO_FRACTION * stable) * (1 - 1e-12))
        integrator = dataclasses.replace(scene.integrator, dt_s=chosen, dt_chosen_by=AUTO)
        scene = dataclasses.replace(scene, integrator=integrator)
    elif dt > stable:
        raise SceneError(
            "integrator.dt_s",
            f"{dt:g} s is above the sheet's linearised stability estimate {stable:.4g} s "
            f"(SheetSolver.stable_step(), at sheet.spacing_warp_mm = {scene.sheet.spacing_warp_mm:g}, "
            f"spacing_weft_mm = {scene.sheet.spacing_weft_mm:g}); use a dt_s below it (in motion, where "
            f'strain stiffens the yarns, {AUTO_FRACTION:g} of it is safe), or dt_s = "auto"',
            related=("sheet.spacing_warp_mm", "sheet.spacing_weft_mm", "material.from_file"),
        )
    check_step_count(
        scene.release.settle_time_s + scene.run.duration_s,
        scene.integrator,
        geometry.n_nodes,
        "sheet",
        ("run.duration_s", "release.settle_time_s", "sheet.spacing_warp_mm", "sheet.spacing_weft_mm"),
    )
    return scene


def describe_sheet_step(scene: SheetScene) -> str:
    """The sentence ``warpcloth run`` prints of a step auto chose for a sheet."""
    return (
        f"integrator.dt_s = auto: {scene.integrator.dt_s:.4e} s ({AUTO_FRACTION:g} of the linearised "
        "stability estimate, a whole fraction of the probe interval)"
    )


def load_sheet_scene(name_or_path: str | Path, overrides: Overrides = ()) -> SheetScene:
    """Read a sheet scene by path or bundled name, apply overrides (as :func:`load_scene`),
    validate it and check it can run (:func:`check_sheet_scene`); every error names the
    field and where it was set. A ``[sweep]`` section is ignored here, as by
    :func:`~warpcloth.scene.load_scene`: this is the sweep's base scene."""
    data, text, where = _read_scene(name_or_path)
    data.pop("sweep", None)
    try:
        scene = check_sheet_scene(sheet_scene_from_dict(apply_overrides(data, overrides)))
    except SceneError as exc:
        raise located(exc, text, where, overrides) from None
    return scene


def build_sheet(scene: SheetScene, device: str | None = None) -> SheetBatch:
    """Model, control, solver and recorder of one sheet scene (checked by :func:`check_sheet_scene`)."""
    return build_sheets([scene], device)


def build_sheets(scenes: Sequence[SheetScene], device: str | None = None, terms: tuple = ()) -> SheetBatch:
    """One batch of sheet scenes (each checked by :func:`check_sheet_scene`), every sheet in
    the same launches: they must agree on what sheets of a batch share (:func:`check_sheet_batch`);
    the force ``terms`` (:mod:`warpcloth.kernels.force_terms`) act on every free node."""
    check_sheet_batch(scenes)
    scene = scenes[0]
    geometry = sheet_geometry(scene)
    model = _builder(scenes, geometry).finalize(device=device, precision=scene.integrator.precision, terms=terms)
    solver = SheetSolver(
        model,
        scene.integrator.dt_s,
        divergence_strain=scene.integrator.divergence_strain,
        divergence_shear=math.radians(scene.integrator.divergence_shear_deg),
    )
    cell, hinge = probed_elements(scene, geometry)
    recorder = SheetRecorder(
        interval=scene.output_interval,
        probes_per_frame=scene.output.probes_per_frame,
        duration=scene.run.duration_s,
        markers=tuple(marker_nodes(scene, geometry)),
        probe_cell=cell,
        probe_hinge=hinge,
    )
    return SheetBatch(model, model.control(), solver, recorder)


def sheet_variants(scenes: list, assignments: list[dict[str, Any]]) -> list[SheetScene]:
    """The sheet variants ready to run: each checked (markers, memory, its step within its
    own stability estimate); those that ask auto for their step share the shortest any of
    them gets alone among the variants that may share a batch, so a batch has one step
    that suits every sheet (each alone: a whole fraction of the probe interval, so the
    shortest is one too)."""
    checked = []
    for i, scene in enumerate(scenes):
        try:
            checked.append(check_sheet_scene(scene))
        except SceneError as exc:
            raise variant_error(exc, i, assignments[i]) from exc
    shortest: dict[str, float] = {}
    for asked, scene in zip(scenes, checked, strict=True):
        if asked.integrator.dt_s == AUTO:
            key = sheet_batch_key(scene, with_step=False)
            shortest[key] = min(shortest.get(key, math.inf), scene.integrator.dt_s)
    for i, (asked, scene) in enumerate(zip(scenes, checked, strict=True)):
        if asked.integrator.dt_s == AUTO:
            integrator = dataclasses.replace(scene.integrator, dt_s=shortest[sheet_batch_key(scene, with_step=False)])
            checked[i] = dataclasses.replace(scene, integrator=integrator)
    return checked
