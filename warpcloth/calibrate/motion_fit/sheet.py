"""The motion fit for a woven sheet (docs/model.md §17, docs/calibration.md): the same
search, Jacobian, verdict and report as the strip's, with a sheet scene's free fields
and tracked sheet markers (:func:`warpcloth.io.measured.read_sheet_markers`) for the
residuals, every batch of candidates one batch of sheets (one launch per chunk)."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np

from warpcloth.errors import ArgumentError, ArgumentTypeError, SceneError
from warpcloth.io.measured import SheetMarkers
from warpcloth.kernels import bending_law
from warpcloth.kernels.laws import LAW_PARAMETERS
from warpcloth.scene import set_field
from warpcloth.scene.shear import RIGIDITY_FIELD, ShearMaterial, shear_field
from warpcloth.scene.sheet import SHEET_SECTIONS, SheetScene, sheet_scene_from_dict
from warpcloth.scene.sheet_build import (
    SHARED_SECTIONS,
    build_sheets,
    check_sheet_scene,
    marker_nodes,
    sheet_geometry,
)
from warpcloth.scene.step import AUTO
from warpcloth.sheet import SheetResult, simulate_sheets

from .objective import FitObjective
from .parameters import FreeParameter, default_range, parse_bounds

SHEET_ALIASES = {
    "gamma": "damping.gamma_per_s",
    "G": f"shear.{RIGIDITY_FIELD}",
    "D": "material.bending_rigidity_gf_cm2_per_cm",
    "D_weft": "weft.bending_rigidity_gf_cm2_per_cm",
    "density": "material.density_g_per_cm2",
    "centre_dx_mm": "clamp.centre_dx_mm",
    "centre_dy_mm": "clamp.centre_dy_mm",
    "centre_dz_mm": "clamp.centre_dz_mm",
}
"""Short names ``warpcloth fit --free`` accepts for a sheet scene (any per-sheet numeric
field also works by its dotted name: ``shear.hysteresis_d1_gf_per_cm``,
``weft.tensile_a1_gf_per_cm``, ``clamp.axis_y``)."""

SHEET_AMPLITUDES = frozenset(
    [f"{table}.{field}" for table in ("material", "weft") for field, (p, _) in LAW_PARAMETERS.items() if p.amplitude]
    + [f"shear.{shear_field(p)}" for field, (p, _) in LAW_PARAMETERS.items() if p.amplitude]
)
"""The fields that set the size of a bending or shear law's hysteresis: fitted from 0 (no
hysteresis) to 4× the scene's value by default."""


def checked_shear(scene: SheetScene) -> ShearMaterial:
    """The scene's shear law (a parsed sheet scene always has one)."""
    if scene.shear is None:
        raise SceneError("shear", "a sheet needs a shear law: give a [shear] table")
    return scene.shear


def sheet_value(scene: SheetScene, dotted: str) -> object:
    """The value of the sheet scene's field ``dotted`` (``shear.<field>`` included); an
    ArgumentError naming ``dotted`` and the fields there are if it has none."""
    section, _, key = dotted.partition(".")
    if section == "shear":
        shear = checked_shear(scene)
        if key == RIGIDITY_FIELD:
            return shear.rigidity_gf_per_cm_deg
        if key in shear.parameters:
            return shear.parameters[key]
        known = ", ".join(f"shear.{f}" for f in (RIGIDITY_FIELD, *shear.parameters))
        raise ArgumentError("dotted", f"{dotted!r} is not a field of the sheet scene's shear law; it has {known}")
    if not key or not hasattr(scene, section) or not hasattr(getattr(scene, section), key):
        table = getattr(scene, section, None) if section in SHEET_SECTIONS else None
        known = (
            f"[{section}] has {', '.join(f.name for f in dataclasses.fields(table))}"
            if dataclasses.is_dataclass(table)
            else f"its sections are {', '.join(SHEET_SECTIONS)}"
        )
        raise ArgumentError("dotted", f"{dotted!r} is not a field of the sheet scene; {known}")
    return getattr(getattr(scene, section), key)


def sheet_free_parameters(names: str | list[str], base: SheetScene, bounds: str | None = None) -> list[FreeParameter]:
    """Resolve ``--free`` names for a sheet scene (:data:`SHEET_ALIASES` or dotted fields)
    and ``--bounds name=lo:hi,...``; default ranges as a strip's (a clamp centre ± 10 mm,
    γ 0 to 4×, a hysteresis amplitude 0 to 4×, any other positive field ¼× to 4×). Every
    end of the box must be a valid sheet scene."""
    names = [n.strip() for n in (names.split(",") if isinstance(names, str) else names) if n.strip()]
    if not names:
        raise ArgumentError("names", "name at least one parameter to fit, e.g. G,gamma")
    given = parse_bounds(bounds)
    out: list[FreeParameter] = []
    for name in names:
        dotted = SHEET_ALIASES.get(name, name)
        try:
            value = sheet_value(base, dotted)
        except ArgumentError:
            shear = ", ".join(f"shear.{f}" for f in (RIGIDITY_FIELD, *checked_shear(base).parameters))
            raise ArgumentError(
                "names",
                f"{name!r} is neither a field of this sheet scene nor one of {', '.join(SHEET_ALIASES)} "
                f"(its shear law's fields: {shear})",
            ) from None
        shared = dotted.split(".")[0] in SHARED_SECTIONS or dotted == "release.settle_time_s"
        if shared or isinstance(value, bool) or not isinstance(value, int | float):
            raise ArgumentError(
                "names",
                f"{name} ({dotted}) is shared by the sheets of one batch or is not a number; only "
                "per-sheet numeric fields can be fitted (material, weft, shear, damping, clamp, "
                "release.settle_damping_per_s)",
            )
        key = name if name in given else dotted if dotted in given else None
        if key is not None:
            lower, upper = given.pop(key)
        else:
            lower, upper = default_range(name, dotted, float(value), amplitude=dotted in SHEET_AMPLITUDES)
        if not lower < upper:
            raise ArgumentError("bounds", f"{name}: lower bound {lower:g} must be below upper bound {upper:g}")
        if any(p.field == dotted for p in out):
            raise ArgumentError("names", f"{name} ({dotted}) is named twice")
        for bound in (lower, upper):
            data = base.to_dict()
            set_field(data, dotted, float(bound))
            if base.integrator.dt_chosen_by == AUTO:
                set_field(data, "integrator.dt_s", AUTO)
            try:
                check_sheet_scene(sheet_scene_from_dict(data))
            except SceneError as exc:
                raise ArgumentError("bounds", f"{name} = {bound:g} is not a valid sheet scene: {exc}") from None
        out.append(FreeParameter(name, dotted, float(lower), float(upper), float(min(max(float(value), lower), upper))))
    if given:
        raise ArgumentError("bounds", f"{next(iter(given))!r} is not among the --free parameters")
    return out


class SheetObjective(FitObjective):
    """Residuals of simulated against tracked sheet markers for batches of parameter points
    (the strip's :class:`~.objective.Objective`: the unit box, the clock offset, the
    Jacobian; here a batch is sheets and a residual a marker coordinate)."""

    def __init__(
        self,
        base: dict,
        measurement: SheetMarkers,
        free: list[FreeParameter],
        align_start_s: float = 0.0,
        device: str | None = None,
    ) -> None:
        if not isinstance(measurement, SheetMarkers):
            raise ArgumentTypeError(
                "measurement",
                "a sheet scene is fitted to tracked sheet markers (read_sheet_markers), not a "
                f"{type(measurement).__name__}",
            )
        self.measurement: SheetMarkers = measurement
        self.free = free
        self.align = float(align_start_s)
        self.device = device
        self.base = copy.deepcopy(base)
        scene = self.scene_of(copy.deepcopy(self.base))
        span = float(measurement.t[-1] - measurement.t[0])
        if self.align > span:
            raise ArgumentError("align_start_s", f"{self.align:g} s is longer than the measured record ({span:g} s)")
        if measurement.t[0] + self.align < 0:
            raise ArgumentError(
                "measurement",
                f"measured times start at {measurement.t[0]:g} s, before the scene's t = 0 (the clamp's "
                "start) even with the allowed --align-start; shift them",
            )
        set_field(self.base, "run.duration_s", float(measurement.t[-1]) + self.align + scene.output_interval)
        self._choose_step()
        self.scene = self.scene_of(copy.deepcopy(self.base))
        tracked = len(marker_nodes(self.scene, sheet_geometry(self.scene)))
        beyond = measurement.marker >= tracked
        if beyond.any():
            raise ArgumentError(
                "measurement",
                f"marker {measurement.marker[beyond][0]} is measured, but the scene tracks {tracked} "
                f"(output.markers_ij and output.markers_mm, 0 … {tracked - 1})",
            )
        self.shift_step = 0.5 * self.scene.output_interval
        self.launches = 0
        self.variants = 0

    spacing_fields = ("sheet.spacing_warp_mm", "sheet.spacing_weft_mm")

    def mesh_note(self) -> str:
        """Why the fit holds at its spacing only (:func:`sheet_mesh_note`), or ""."""
        return sheet_mesh_note(self.base)

    def scene_of(self, data: dict) -> SheetScene:
        """The sheet scene of raw scene data, checked (markers, memory, step)."""
        return check_sheet_scene(sheet_scene_from_dict(data))

    def continuum_order(self) -> float | None:
        """2 (docs/model.md §17.7), 1 with the paper's clamp edge (``sheet.edge_hinge``, as a
        strip's); None when a bending or shear law has no continuum limit."""
        if sheet_mesh_note(self.base):
            return None
        return 1.0 if self.scene.sheet.edge_hinge == "paper" else 2.0

    def corner_step(self, corners: list[dict]) -> float:
        """The shortest step any corner sheet chooses (``dt_s = "auto"``, :func:`check_sheet_scene`)."""
        return min(self.scene_of(data).integrator.dt_s for data in corners)

    def run(self, points: np.ndarray) -> SheetResult:
        """Simulate every point (rows) as one batch of sheets."""
        scenes = [self.scene_of(self.scene_data(u)) for u in points]
        self.launches += 1
        self.variants += len(points)
        batch = build_sheets(scenes, self.device)
        return simulate_sheets(
            batch.model, batch.control, batch.solver, batch.recorder, on_divergence="record", keep_frames=False
        )

    def residual_groups(self) -> np.ndarray:
        """The markers' residuals (each row's coordinates) grouped by their time: a frame's
        markers share its errors (the camera's, the tracker's) as a strip's do."""
        m = self.measurement
        return np.repeat(m.t, len(m.axes))

    def residuals(self, result: SheetResult, j: int, shift: float, penalise: bool = True) -> np.ndarray:
        """Simulated minus measured marker coordinates (m), row by row, for sheet j at clock
        offset δ; where the sheet diverged, 10 cm per coordinate (NaN with ``penalise=False``)."""
        m = self.measurement
        t = m.t + shift
        k = np.clip(np.searchsorted(result.t, t) - 1, 0, len(result.t) - 2)
        w = ((t - result.t[k]) / (result.t[k + 1] - result.t[k])).clip(0, 1)[:, None]
        axes = ["xyz".index(a) for a in m.axes]
        track = result.markers[:, j][:, :, axes]  # [sample, marker, axis]
        simulated = track[k, m.marker] * (1 - w) + track[k + 1, m.marker] * w
        diff = simulated - m.position
        return np.where(np.isfinite(diff), diff, 0.1 if penalise else np.nan).ravel()


def sheet_mesh_note(base: dict) -> str:
    """Why a sheet fit holds at its spacing only, when one of its laws' answers depends on
    the mesh; "" when every law converges in h."""
    scene = sheet_scene_from_dict(copy.deepcopy(base))
    laws = {
        "the warp's bending": scene.material.bending_law,
        "the weft's bending": scene.weft_material().bending_law,
        "the shear": checked_shear(scene).law,
    }
    dependent = [f"{what} ({law})" for what, law in laws.items() if not bending_law(law).mesh_independent]
    if not dependent:
        return ""
    return (
        f"{', '.join(dependent)} law's hysteresis depends on the mesh (no return-point memory, docs/model.md "
        f"§15.6): these values hold at sheet.spacing_warp_mm = {scene.sheet.spacing_warp_mm:g}, "
        f"spacing_weft_mm = {scene.sheet.spacing_weft_mm:g} only; the masing law converges in h"
    )
