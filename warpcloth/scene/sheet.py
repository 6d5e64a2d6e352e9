"""Sheet scenes (stage 3, docs/model.md §17): a scene file with a ``[sheet]`` table instead
of ``[strip]``, parsed, overridden, validated and located by the strip's machinery
(:mod:`.parse`, :mod:`.overrides`, :mod:`.locate`).

The material is the strip's ``[material]`` (the warp direction), a ``[weft]`` table of the
weft's tensile and bending fields where they differ, and a ``[shear]`` table (a law on
the shear angle, :func:`~warpcloth.scene.shear.parse_shear`); a material file fills all
three. The resolved scene (``to_dict``) holds every value, so it re-reads without the
file. Offsets are in mm from the middle of the clamp edge, in the strip's frame: x out of
the sheet's rest plane, y up, z across.
"""

from __future__ import annotations

import dataclasses
from dataclasses import MISSING, dataclass, field
from pathlib import Path

from warpcloth import units
from warpcloth.errors import ArgumentError, SceneError
from warpcloth.kernels import bending_law, bending_masing
from warpcloth.kernels.law import BENDING_RIGIDITY
from warpcloth.sheet.geometry import EDGE_HINGES

from .files import _read_scene
from .materials import (
    BIAS_TABLE,
    MATERIAL_FILE_KEY,
    ONE_PER_FABRIC,
    WEFT_TABLE,
    material_fields,
    parse_bias,
    parse_weft,
    read_material_file,
    validate_material,
    with_material_file,
)
from .parse import parse_section
from .schema import (
    MAX_STEPS_DEFAULT,
    ClampSection,
    ClampSegment,
    DampingSection,
    MaterialSection,
    RunSection,
    _field,
    field_types,
)
from .shear import SHEAR_TABLE, ShearMaterial, parse_shear
from .step import AUTO
from .validate import MAX_NODES, _multiple, validate_segments

CUTS = ("rectangle", "bias")
"""Choices of ``sheet.cut``."""

AUTO_FRACTION = 0.5
"""``integrator.dt_s = "auto"`` takes this fraction of the linearised stability estimate
(:meth:`~warpcloth.sheet.SheetSolver.stable_step`): the estimate is at the tensile
curve's initial slope a1, and a strained segment is stiffer (a4 ε³ adds 4 a4 ε³ to it),
so the full estimate is not safe in motion."""


@dataclass(frozen=True)
class SheetSection:
    """Geometry of the sheet (docs/model.md §17.2)."""

    cut: str = _field(
        "rectangle",
        "rectangle (warp down −y, weft across +z) | bias (the lattice turned by bias_angle_deg in the "
        "sheet's plane about the middle of the clamp edge; each cell the strip overlaps carries the part of "
        "its area inside, docs/model.md §17.2)",
        choices=CUTS,
    )
    free_length_mm: float = _field(100.0, "length hanging below the clamp edge", gt=0)
    width_mm: float = _field(100.0, "width across (z), centred on the middle of the clamp edge", gt=0)
    clamp_length_mm: float = _field(10.0, "length held in the clamp above its edge (kinematic nodes)", gt=0)
    spacing_warp_mm: float = _field(
        5.0,
        "node spacing along the warp; rectangle: divides free_length_mm and clamp_length_mm; "
        "bias: the one spacing of both yarns",
        gt=0,
    )
    spacing_weft_mm: float = _field(
        5.0, "node spacing along the weft; rectangle: divides width_mm; bias: equal to spacing_warp_mm", gt=0
    )
    edge_hinge: str = _field(
        "second_order",
        "second_order (a hinge at the clamp edge bends over h/2) | paper (over h), as clamp.edge_hinge of a strip",
        choices=EDGE_HINGES,
    )
    yarn_compression_fraction: float = _field(
        1.0,
        "a warp or weft segment in compression is this part as stiff as its tensile quartic mirrored "
        "(1: as stiff; 0: no resistance, the yarns buckle freely); docs/model.md §17.3",
        ge=0,
    )
    initial_waviness_mm: float = _field(
        0.0,
        "the hung sheet's out-of-plane deviation before it settles, x = A sin(π s / L) sin(π (z / W + ½)) (s the "
        "depth below the clamp edge, L the free length, W the width): a physical imperfection (no fabric hangs "
        "flat) that seeds motion out of the plane; 0: flat, and a sheet driven in its plane stays in it",
        ge=0,
    )
    bias_angle_deg: float = _field(
        45.0,
        "bias: the strip's length to the warp (0: along it, 90: along the weft); 45° with a width of whole "
        "cell diagonals puts nodes on the sides",
        ge=0,
    )


def _weft_section() -> type:
    # [weft]: every [material] field with a value per direction, with its type, default and doc
    hints = field_types(MaterialSection)
    fields = []
    for f in dataclasses.fields(MaterialSection):
        if f.name in ONE_PER_FABRIC:
            continue
        meta = {**f.metadata, "doc": f"the weft's {f.name}, where it differs from material.{f.name} (the warp's)"}
        if f.default_factory is not MISSING:
            fields.append((f.name, hints[f.name], field(default_factory=f.default_factory, metadata=meta)))
        else:
            fields.append((f.name, hints[f.name], field(default=f.default, metadata=meta)))
    section = dataclasses.make_dataclass("WeftSection", fields, frozen=True)
    section.__module__ = __name__
    section.__doc__ = "The weft direction's tensile and bending fields (KES units); unset ones are the warp's."
    return section


WeftSection = _weft_section()


def _bias_section() -> type:
    # [bias]: every bending field of [material] (its law, B and the laws' parameters), the
    # bending Poisson ratio
    hints = field_types(MaterialSection)
    fields = [
        (
            "bending_poisson_ratio",
            float,
            _field(0.0, "ν of the plate's bending, D12 = ν √(D11 D22), in (−1, 1) (a woven fabric's is small)", gt=-1),
        )
    ]
    for f in dataclasses.fields(MaterialSection):
        if f.name in (*ONE_PER_FABRIC, "tensile_gf_per_cm"):
            continue
        doc = f"bending on the bias (KES-FB2 on a sample cut at 45°): {f.metadata['doc']}; unset: from warp and weft"
        fields.append((f.name, hints[f.name], field(default=f.default, metadata={**f.metadata, "doc": doc})))
    section = dataclasses.make_dataclass("BiasSection", fields, frozen=True)
    section.__module__ = __name__
    section.__doc__ = (
        "Bending on the bias as KES-FB2 measures it (a wide sample cut at 45°, held in cylindrical bending), "
        "and the bending Poisson ratio: the sheet's twist follows (docs/model.md §17.4)."
    )
    return section


BiasSection = _bias_section()


def bias_from_yarns(warp: dict, weft: dict) -> dict:
    """The [bias] fields a scene leaves unset, from its resolved warp and weft (KES units):
    B and each moment of the law their mean (D12 + 2 D66 = (D11 + D22)/2, the twist carrying
    no hysteresis of its own), the law and its other parameters the warp's."""
    defaults = MaterialSection()
    law = warp.get("bending_law", defaults.bending_law)

    def value(table: dict, name: str) -> float:
        return table.get(name, getattr(defaults, name))

    mean = {BENDING_RIGIDITY.scene_field}
    mean |= {p.scene_field for p in bending_law(law).parameters if p.kind == "moment"}
    out = {"bending_law": law}
    for p in bending_law(law).parameters:
        out[p.scene_field] = value(warp, p.scene_field)
    for name in mean:
        same = weft.get("bending_law", law) == law
        out[name] = (value(warp, name) + value(weft, name)) / 2 if same else value(warp, name)
    return out


@dataclass(frozen=True)
class TranslationSegment:
    """One piece of d(t) = Σ c_k (t − t_start)^k on [t_start, t_end], along clamp.direction."""

    t_start_s: float = _field(0.0, "segment start time")
    t_end_s: float = _field(0.0, "segment end time (> t_start_s)")
    d_coefficients_mm: list[float] = _field([0.0], "c_0..c_4 in mm/s^k (at most a quartic)")


@dataclass(frozen=True)
class SheetClampSection:
    """The clamp's rigid motion: a rotation θ(t) about an axis through a centre, then a
    translation d(t) along a direction (docs/model.md §17.4); no segments: it stands still."""

    rotation_segments: list[ClampSegment] = _field([], "pieces of θ(t) (rad), as a strip's clamp.segments")
    axis_x: float = _field(0.0, "rotation axis, x component (normalised)")
    axis_y: float = _field(0.0, "rotation axis, y component (up)")
    axis_z: float = _field(1.0, "rotation axis, z component (across; z: the strip's swing)")
    centre_dx_mm: float = _field(0.0, "rotation centre, x offset from the middle of the clamp edge")
    centre_dy_mm: float = _field(0.0, "rotation centre, y offset (up +)")
    centre_dz_mm: float = _field(0.0, "rotation centre, z offset (across)")
    translation_segments: list[TranslationSegment] = _field([], "pieces of d(t) (mm) along the direction")
    direction_x: float = _field(0.0, "translation direction, x component (normalised)")
    direction_y: float = _field(0.0, "translation direction, y component")
    direction_z: float = _field(1.0, "translation direction, z component (z: sideways in the sheet's plane)")


@dataclass(frozen=True)
class SheetReleaseSection:
    """The sheet settles under gravity, damped, before t = 0 (the clamp moves from t = 0)."""

    settle_time_s: float = _field(0.5, "time to settle before t = 0 (0: start from the flat rest shape)", ge=0)
    settle_damping_per_s: float = _field(20.0, "γ while settling", ge=0)


@dataclass(frozen=True)
class SheetIntegratorSection:
    """Symplectic Euler at a fixed step (docs/model.md §17.5)."""

    dt_s: float = _field(
        AUTO,
        'time step, at most the linearised stability estimate SheetSolver.stable_step(); "auto": '
        f"{AUTO_FRACTION:g} of it, shortened to a whole fraction of the probe interval",
        gt=0,
        words=(AUTO,),
    )
    dt_chosen_by: str = _field(
        "scene",
        '"auto" when dt_s = "auto" chose the step (the recorded scene keeps the number), else "scene"',
        choices=("scene", "auto"),
    )
    precision: str = _field("float64", "float64 | float32", choices=("float64", "float32"))
    divergence_strain: float = _field(0.25, "|ε| of a segment beyond which a sheet counts as diverged", gt=0)
    divergence_shear_deg: float = _field(60.0, "|φ| of a cell beyond which a sheet counts as diverged", gt=0)
    reversal_memory: int = _field(
        bending_masing.DEFAULT_CAPACITY, "masing: open reversal points each hinge and cell keeps", ge=1
    )
    max_steps: int = _field(
        MAX_STEPS_DEFAULT,
        "steps of each sheet a run may take (settling and the record together); a step that "
        "collapses (a stiffness or spacing beyond reason) is refused past it: raise it to run a long "
        "run on purpose, up to 2147483647",
        ge=1,
    )


@dataclass(frozen=True)
class SheetOutputSection:
    """What is recorded and how often."""

    frame_rate_hz: float = _field(60.0, "shape frames per second (a lab video's rate)", gt=0)
    probes_per_frame: int = _field(10, "probe and marker samples per frame interval", ge=1)
    markers_ij: list[list[int]] = _field(
        [], "tracked nodes by lattice position [i, j] (i along the warp, j along the weft, from the cut's first node)"
    )
    markers_mm: list[list[float]] = _field(
        [],
        "tracked nodes by rest position [y, z] in mm from the middle of the clamp edge (y up: "
        "−50 is 50 mm below it); each the nearest node, within half a spacing",
    )
    probe_cell_mm: list[float] = _field(
        [0.0, 0.0], "[y, z] mm: the free cell whose centre is nearest is probed (cell_shear_angle, cell_shear_force)"
    )
    probe_hinge_mm: list[float] = _field(
        [0.0, 0.0], "[y, z] mm: the free hinge of probe_hinge_family nearest is probed (hinge_curvature, hinge_moment)"
    )
    probe_hinge_family: str = _field("warp", "warp | weft: the line the probed hinge bends", choices=("warp", "weft"))


@dataclass(frozen=True)
class SheetScene:
    """A complete, validated description of one woven-sheet experiment."""

    sheet: SheetSection = field(default_factory=SheetSection)
    material: MaterialSection = field(default_factory=MaterialSection)
    weft: WeftSection = field(default_factory=WeftSection)  # type: ignore[valid-type]
    bias: BiasSection = field(default_factory=BiasSection)  # type: ignore[valid-type]
    shear: ShearMaterial | None = None
    damping: DampingSection = field(default_factory=DampingSection)
    clamp: SheetClampSection = field(default_factory=SheetClampSection)
    release: SheetReleaseSection = field(default_factory=SheetReleaseSection)
    integrator: SheetIntegratorSection = field(default_factory=SheetIntegratorSection)
    run: RunSection = field(default_factory=RunSection)
    output: SheetOutputSection = field(default_factory=SheetOutputSection)

    @property
    def spacing(self) -> tuple[float, float]:
        """(h_warp, h_weft) in metres."""
        return (self.sheet.spacing_warp_mm * units.LENGTH_MM, self.sheet.spacing_weft_mm * units.LENGTH_MM)

    @property
    def output_interval(self) -> float:
        """Seconds between probe samples."""
        return 1.0 / (self.output.frame_rate_hz * self.output.probes_per_frame)

    def weft_material(self) -> MaterialSection:
        """The weft as a [material] section: the fabric's name and density, the weft's fields."""
        values = {k: getattr(self.weft, k) for k in material_fields() if k not in ONE_PER_FABRIC}
        return MaterialSection(
            name=f"{self.material.name} (weft)",
            density_g_per_cm2=self.material.density_g_per_cm2,
            bending_law=self.weft.bending_law,
            **values,
        )

    def bias_material(self) -> MaterialSection:
        """Bending on the bias as a [material] section (the warp's tensile fields, unused)."""
        values = {
            k: getattr(self.bias, k) for k in material_fields() if k not in (*ONE_PER_FABRIC, "tensile_gf_per_cm")
        }
        return MaterialSection(
            name=f"{self.material.name} (bias)",
            density_g_per_cm2=self.material.density_g_per_cm2,
            tensile_gf_per_cm=self.material.tensile_gf_per_cm,
            bending_law=self.bias.bending_law,
            **values,
        )

    def to_dict(self) -> dict:
        """Plain nested dict (TOML-ready) of every field, defaults included."""
        out = {f.name: dataclasses.asdict(getattr(self, f.name)) for f in dataclasses.fields(self) if f.name != "shear"}
        out[SHEAR_TABLE] = self.shear.table()
        return out


SHEET_SECTIONS = tuple(f.name for f in dataclasses.fields(SheetScene))


def sheet_sections(data: dict) -> list[str]:
    """The sections and fields of raw scene ``data`` that only a sheet has ([weft], [shear],
    clamp.rotation_segments, ...): a file without a [sheet] table that gives them is
    refused by :func:`warpcloth.bodies.of_data` (read as a strip's, they would be refused
    field by field)."""
    clamp = data.get("clamp")
    strip_clamp = {f.name for f in dataclasses.fields(ClampSection)}
    own = [f"[{t}]" for t in (WEFT_TABLE, BIAS_TABLE, SHEAR_TABLE) if t in data]
    return own + [f"clamp.{k}" for k in (clamp if isinstance(clamp, dict) else {}) if k not in strip_clamp]


def _complete(table: dict, law_key: str = "bending_law") -> bool:
    law = table.get(law_key)
    return isinstance(law, str) and all(k in table for k in material_fields(law) if k not in ONE_PER_FABRIC)


def _with_sheet_material(data: dict) -> dict:
    # The material file fills [material] (as for a strip), [weft] and [shear]; the scene's
    # own values win. A resolved scene holds all three whole, so the file is not read.
    data = dict(data)
    material = data.get("material")
    ref = material.get("from_file", "") if isinstance(material, dict) else ""
    weft = data.get(WEFT_TABLE, {})
    bias = data.get(BIAS_TABLE, {})
    shear = data.get(SHEAR_TABLE)
    filled = with_material_file(data)
    full_weft = _complete(weft) if isinstance(weft, dict) else True
    if isinstance(ref, str) and ref.strip() and not (shear is not None and full_weft and filled is data):
        file = read_material_file(ref)
        if isinstance(weft, dict):
            weft = {**file.get(WEFT_TABLE, {}), **weft}
        if isinstance(bias, dict):
            bias = {**file.get(BIAS_TABLE, {}), **bias}
        if SHEAR_TABLE in file:
            given = file[SHEAR_TABLE]
            if isinstance(shear, dict) and shear.get("law", given["law"]) == given["law"]:
                shear = {**given, **shear}
            elif shear is None:
                shear = dict(given)
    data = dict(filled)
    if isinstance(weft, dict) and isinstance(data.get("material"), dict):
        warp = data["material"]
        law = weft.get("bending_law", warp.get("bending_law", MaterialSection().bending_law))
        carried = {k: warp[k] for k in material_fields(law) if k in warp and k not in ONE_PER_FABRIC}
        weft = {**carried, "bending_law": law, **weft}
        if isinstance(bias, dict):
            bias = {**bias_from_yarns(warp, weft), **bias}
    data[WEFT_TABLE] = weft
    data[BIAS_TABLE] = bias
    if shear is not None:
        data[SHEAR_TABLE] = shear
    return data


def sheet_scene_from_dict(data: dict) -> SheetScene:
    """Parse and validate raw sheet-scene data (a material file filling [material],
    [weft] and [shear]); ``dt_s = "auto"`` stays a word until :func:`~warpcloth.scene.sheet_build.check_sheet_scene`."""
    if not isinstance(data, dict):
        raise SceneError("scene", f"expected a table, got {data!r}")
    if "sheet" not in data:
        raise SceneError("sheet", "is missing: this is a strip scene (warpcloth.load_scene reads it)")
    data = _with_sheet_material(data)
    shear = data.pop(SHEAR_TABLE, None)
    if shear is None:
        ref = data.get("material", {}).get("from_file", "") if isinstance(data.get("material"), dict) else ""
        raise SceneError(
            SHEAR_TABLE,
            "a sheet needs a shear law: give a [shear] table "
            + (f"(its material file {ref!r} has none)" if ref else "or a material.from_file that has one"),
            related=(MATERIAL_FILE_KEY,),
        )
    parse_weft(data[WEFT_TABLE])
    parse_bias(data[BIAS_TABLE])
    scene = parse_section(SheetScene, data, "")
    scene = dataclasses.replace(scene, shear=parse_shear(shear))
    validate_sheet_scene(scene)
    return scene


def nodes_at_most(st: SheetSection) -> float:
    """The nodes of the sheet's cut at most, in floats, before the cut counts one (a length
    of 1e308 mm is inf of them): a rectangle's lattice, or for a bias cut, whose cells
    reach past its rectangle's edges, twice that rectangle's with a spacing's margin
    all round (the bundled bias strip: 181 nodes, bounded by 450)."""
    along = (st.free_length_mm + st.clamp_length_mm) / st.spacing_warp_mm + 1
    across = st.width_mm / st.spacing_weft_mm + 1
    if st.cut == "rectangle":
        return along * across
    return 2 * (along + 2) * (across + 2)


def validate_sheet_scene(scene: SheetScene) -> None:
    """Cross-field checks that single fields cannot express; raises SceneError."""
    st = scene.sheet
    nodes = nodes_at_most(st)
    if not nodes <= MAX_NODES:
        raise SceneError(
            "sheet.free_length_mm",
            f"{st.free_length_mm:g} mm below and sheet.clamp_length_mm = {st.clamp_length_mm:g} mm in the clamp, "
            f"sheet.width_mm = {st.width_mm:g} mm across, at spacings {st.spacing_warp_mm:g} and "
            f"{st.spacing_weft_mm:g} mm, are {nodes:.3g} nodes, more than {MAX_NODES}",
            related=("sheet.clamp_length_mm", "sheet.width_mm", "sheet.spacing_warp_mm", "sheet.spacing_weft_mm"),
        )
    if st.yarn_compression_fraction > 1:
        raise SceneError(
            "sheet.yarn_compression_fraction",
            f"{st.yarn_compression_fraction:g} is above 1: a yarn is not stiffer in compression than in tension",
        )
    if st.cut == "rectangle":
        for name, spacing in (
            ("free_length_mm", "spacing_warp_mm"),
            ("clamp_length_mm", "spacing_warp_mm"),
            ("width_mm", "spacing_weft_mm"),
        ):
            if not _multiple(getattr(st, name), getattr(st, spacing)):
                raise SceneError(
                    f"sheet.{spacing}",
                    f"{getattr(st, spacing):g} mm does not divide sheet.{name} = {getattr(st, name):g} mm "
                    "into whole cells",
                    related=(f"sheet.{name}",),
                )
    elif st.bias_angle_deg > 90:
        raise SceneError("sheet.bias_angle_deg", f"{st.bias_angle_deg:g}° is beyond 90° (along the weft)")
    elif st.spacing_weft_mm != st.spacing_warp_mm:
        raise SceneError(
            "sheet.spacing_weft_mm",
            f"{st.spacing_weft_mm:g} mm differs from sheet.spacing_warp_mm = {st.spacing_warp_mm:g} mm; "
            'a bias cut has one spacing (set both, or leave spacing_weft_mm out of cut = "bias")',
            related=("sheet.spacing_warp_mm", "sheet.cut"),
        )
    limit = scene.integrator.divergence_strain
    validate_material(scene.material, limit, "material")
    validate_material(scene.weft_material(), limit, WEFT_TABLE)
    _check_bias(scene)
    clamp = scene.clamp
    validate_segments(clamp.rotation_segments, "clamp.rotation_segments", "theta_coefficients_si", "θ", "rad")
    validate_segments(clamp.translation_segments, "clamp.translation_segments", "d_coefficients_mm", "d", "mm")
    for name, coefficients, unit in (
        ("rotation_segments", "theta_coefficients_si", "rad"),
        ("translation_segments", "d_coefficients_mm", "mm"),
    ):
        pieces = getattr(clamp, name)
        if pieces and getattr(pieces[0], coefficients)[0] != 0:
            # the sheet hangs from the clamp at rest: a motion that starts elsewhere would
            # move the clamp there in one step
            raise SceneError(
                f"clamp.{name}[0].{coefficients}",
                f"starts at {getattr(pieces[0], coefficients)[0]:g} {unit}; the clamp starts at rest where the "
                "sheet hangs, so the first piece's c_0 must be 0 (the clamp cannot teleport)",
            )
    for name in ("axis", "direction"):
        components = [getattr(clamp, f"{name}_{c}") for c in "xyz"]
        if not any(components):
            raise SceneError(f"clamp.{name}_z", f"clamp.{name}_x, _y and _z are all 0; the {name} needs a direction")
    output = scene.output
    for i, ij in enumerate(output.markers_ij):
        if len(ij) != 2:
            raise SceneError(f"output.markers_ij[{i}]", f"a lattice position is [i, j], got {ij!r}")
    for name in ("markers_mm",):
        for i, yz in enumerate(getattr(output, name)):
            if len(yz) != 2:
                raise SceneError(f"output.{name}[{i}]", f"a rest position is [y, z] in mm, got {yz!r}")
    for name in ("probe_cell_mm", "probe_hinge_mm"):
        if len(getattr(output, name)) != 2:
            raise SceneError(f"output.{name}", f"a rest position is [y, z] in mm, got {getattr(output, name)!r}")
    dt = scene.integrator.dt_s
    if isinstance(dt, str):
        return
    if dt > scene.output_interval:
        raise SceneError(
            "integrator.dt_s",
            f"{dt:g} s is longer than the probe interval {scene.output_interval:g} s "
            "(1 / (output.frame_rate_hz × output.probes_per_frame))",
            related=("output.frame_rate_hz", "output.probes_per_frame"),
        )


def _check_bias(scene: SheetScene) -> None:
    # the twist the bias implies must be a plate's (docs/model.md §17.4): refused by the
    # [bias] field, with the value, before any kernel runs
    from warpcloth.sheet.material import SheetMaterialSI

    from .materials import to_si

    b_warp = scene.material.bending_rigidity_gf_cm2_per_cm
    b_weft = scene.weft.bending_rigidity_gf_cm2_per_cm
    nu = scene.bias.bending_poisson_ratio
    least = (b_warp + b_weft + 2 * nu * (b_warp * b_weft) ** 0.5) / 4
    given = scene.bias.bending_rigidity_gf_cm2_per_cm
    if given < least * (1 - 1e-12):
        raise SceneError(
            f"{BIAS_TABLE}.bending_rigidity_gf_cm2_per_cm",
            f"{given:g} gf·cm²/cm is below (B_warp + B_weft + 2 D12)/4 = {least:.4g} gf·cm²/cm (B_warp {b_warp:g}, "
            f"B_weft {b_weft:g}, ν {nu:g}), the least a plate with a twist rigidity D66 ≥ 0 bends on the bias; "
            f"a softer bias needs a negative {BIAS_TABLE}.bending_poisson_ratio",
        )
    law = bending_law(scene.bias.bending_law)
    if scene.bias.bending_law == scene.material.bending_law == scene.weft.bending_law:
        for p in law.parameters:
            if p.kind != "moment":
                continue
            ends = [getattr(t, p.scene_field) for t in (scene.bias, scene.material, scene.weft)]
            if 2 * ends[0] < (ends[1] + ends[2]) * (1 - 1e-12):
                raise SceneError(
                    f"{BIAS_TABLE}.{p.scene_field}",
                    f"{ends[0]:g} is below the mean of the warp's {ends[1]:g} and the weft's {ends[2]:g}: the "
                    f"twist's own hysteresis, 2 × the bias's − the warp's − the weft's, would be negative",
                )
    warp, weft, bias = (to_si(m) for m in (scene.material, scene.weft_material(), scene.bias_material()))
    try:
        SheetMaterialSI(warp, weft, 0.0, warp.bending, bias, nu)
    except ArgumentError as exc:
        raise SceneError(f"{BIAS_TABLE}.bending_law", f"{scene.bias.bending_law!r}: {exc.message}") from None


def read_sheet_scene(path: str | Path) -> SheetScene:
    """A recorded (resolved) sheet scene, as a run directory stores it."""
    data, _, _ = _read_scene(Path(path))
    return sheet_scene_from_dict(data)


def sheet_scene_fields() -> list[str]:
    """Dotted names of every sheet-scene field (the guide documents each)."""
    hints = field_types(SheetScene)
    names = []
    for section in SHEET_SECTIONS:
        if section == SHEAR_TABLE:
            continue
        names += [f"{section}.{f.name}" for f in dataclasses.fields(hints[section])]
    return names
