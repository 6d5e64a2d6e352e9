"""Scene files: schema, loading, ``--set`` overrides and validation.

A scene is a TOML file whose sections map onto the dataclasses below. Every field
carries its unit in its name and a one-line description in its metadata; the README's
scene reference is the same information. Validation happens here, before any kernel
runs, and every error names the dotted field and the offending value.
"""

from __future__ import annotations

import copy
import dataclasses
import importlib.resources
import math
import tomllib
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import units
from .errors import SceneError
from .material import DEFAULT_MATERIAL, validate_material

MAX_STEPS = 2**31 - 1
MATERIAL_FILE_KEY = "material.from_file"


def _field(default: Any, doc: str, *, gt: float | None = None, ge: float | None = None,
           choices: tuple[str, ...] | None = None, per_strip: bool = False) -> Any:
    meta = {"doc": doc, "gt": gt, "ge": ge, "choices": choices, "per_strip": per_strip}
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=meta)
    return field(default=default, metadata=meta)


@dataclass
class StripSection:
    """Geometry of the strip (paper §3.1)."""

    free_length_mm: float = _field(100.0, "length hanging below the clamp", gt=0)
    clamp_length_mm: float = _field(20.0, "length held in the clamp (kinematic nodes)", gt=0)
    width_mm: float = _field(50.0, "strip width W (forces, masses and moments scale with it)",
                             gt=0, per_strip=True)
    spacing_mm: float = _field(5.0, "node spacing h; must divide both lengths", gt=0)


@dataclass
class MaterialSection:
    """Fabric in KES units; converted to SI once in warpcloth.units."""

    name: str = _field(DEFAULT_MATERIAL["name"], "label (the default is illustrative, MODEL.md)",
                       per_strip=True)
    density_g_per_cm2: float = _field(DEFAULT_MATERIAL["density_g_per_cm2"], "mass per area ρ_A",
                                      gt=0, per_strip=True)
    tensile_gf_per_cm: list[float] = _field(
        DEFAULT_MATERIAL["tensile_gf_per_cm"],
        "a1..a4 of T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴ (force per width, KES-FB1 upper loop)",
        per_strip=True)
    bending_rigidity_gf_cm2_per_cm: float = _field(
        DEFAULT_MATERIAL["bending_rigidity_gf_cm2_per_cm"], "D, slope of the centre line M = D K",
        ge=0, per_strip=True)
    hysteresis_d1_gf_cm_per_cm: float = _field(
        DEFAULT_MATERIAL["hysteresis_d1_gf_cm_per_cm"], "D1, hysteresis amplitude (0 = elastic)",
        ge=0, per_strip=True)
    hysteresis_alpha_cm: float = _field(DEFAULT_MATERIAL["hysteresis_alpha_cm"],
                                        "α, steepness of the hysteresis branches", gt=0, per_strip=True)
    hysteresis_k0_per_cm: float = _field(DEFAULT_MATERIAL["hysteresis_k0_per_cm"],
                                         "K0, curvature where the KES loop closes", gt=0, per_strip=True)
    from_file: str = _field("", "a material file (path ending in .toml, relative to the scene file) or a bundled "
                            "material name; its values fill every [material] field the scene does not set itself",
                            per_strip=True)


@dataclass
class DampingSection:
    """Viscous damping F = −γ m v (residual air and internal viscosity, tuned)."""

    gamma_per_s: float = _field(0.0, "γ after release", ge=0, per_strip=True)


@dataclass
class ClampSegment:
    """One piece of θ(t) = Σ c_k (t − t_start)^k on [t_start, t_end]."""

    t_start_s: float = _field(0.0, "segment start time", per_strip=True)
    t_end_s: float = _field(0.0, "segment end time (> t_start_s)", per_strip=True)
    theta_coefficients_si: list[float] = _field([0.0], "c_0..c_4 in rad/s^k (at most a quartic)",
                                                per_strip=True)


@dataclass
class ClampSection:
    """Kinematic clamp: rigid rotation θ(t) about a rotation centre."""

    motion: str = _field("fixed", "fixed | piecewise (segments) | table (sampled θ)",
                         choices=("fixed", "piecewise", "table"), per_strip=True)
    rotation_centre_dx_mm: float = _field(0.0, "rotation centre x offset from the clamp's lowest point",
                                          per_strip=True)
    rotation_centre_dy_mm: float = _field(0.0, "rotation centre y offset (up +) from the clamp's lowest point",
                                          per_strip=True)
    segments: list[ClampSegment] = _field([], "piecewise polynomial θ(t), contiguous, θ continuous",
                                          per_strip=True)
    table_t_s: list[float] = _field([], "sampled times, strictly increasing", per_strip=True)
    table_theta_rad: list[float] = _field([], "sampled angles (counter-clockwise +)", per_strip=True)
    interpolation: str = _field("linear", "linear | cubic (natural spline) for a table",
                                choices=("linear", "cubic"), per_strip=True)


@dataclass
class ReleaseSection:
    """Hold-and-release start of the damped swing: the free end is carried to a held
    position, held while the strip settles, then released at t = 0."""

    enabled: bool = _field(False, "start with the hold-and-release phase")
    hold_x_mm: float = _field(50.0, "held free-end x, from the clamp's lowest point", per_strip=True)
    hold_y_mm: float = _field(-80.0, "held free-end y (up +), from the clamp's lowest point",
                              per_strip=True)
    move_time_s: float = _field(0.3, "time to carry the free end to the held position", gt=0)
    settle_time_s: float = _field(1.0, "time held before release", ge=0)
    settle_damping_per_s: float = _field(20.0, "γ while held, so the strip settles", ge=0,
                                         per_strip=True)


@dataclass
class IntegratorSection:
    """Explicit time integration (paper §2.3)."""

    scheme: str = _field("semi_implicit", "semi_implicit (symplectic Euler) | forward (paper eqs. 5–6)",
                         choices=("semi_implicit", "forward"))
    dt_s: float = _field(1e-5, "time step (the paper used 1e-7)", gt=0)
    precision: str = _field("float64", "float64 | float32", choices=("float64", "float32"))
    divergence_strain: float = _field(0.25, "|ε| beyond which a strip counts as diverged; the "
                                      "tensile curve must increase up to it", gt=0)


@dataclass
class RunSection:
    """Length of the recorded run and the environment."""

    duration_s: float = _field(2.0, "recorded time after t = 0 (release)", gt=0)
    gravity_m_per_s2: float = _field(9.80665, "g (0 for the beam test)", ge=0)


@dataclass
class OutputSection:
    """What is recorded and how often."""

    frame_rate_hz: float = _field(60.0, "shape frames per second (the paper's video rate)", gt=0)
    probes_per_frame: int = _field(10, "probe samples per frame interval", ge=1)
    laser_height_mm: float = _field(-80.0, "height of the laser line, from the clamp's lowest point")
    loop_hinge_mm: float = _field(0.0, "arc length below the clamp's lowest point of the hinge whose curvature and "
                                  "moment are probed (the moment–curvature loop); 0 = the clamp-edge hinge", ge=0)


@dataclass
class Scene:
    """A complete, validated description of one strip experiment."""

    strip: StripSection = field(default_factory=StripSection)
    material: MaterialSection = field(default_factory=MaterialSection)
    damping: DampingSection = field(default_factory=DampingSection)
    clamp: ClampSection = field(default_factory=ClampSection)
    release: ReleaseSection = field(default_factory=ReleaseSection)
    integrator: IntegratorSection = field(default_factory=IntegratorSection)
    run: RunSection = field(default_factory=RunSection)
    output: OutputSection = field(default_factory=OutputSection)

    # Derived quantities used by the orchestration (SI, computed after validation).
    @property
    def spacing(self) -> float:
        """Node spacing h in metres."""
        return self.strip.spacing_mm * units.LENGTH_MM

    @property
    def loop_hinge(self) -> int:
        """Index of the probed hinge (0 = the clamp-edge hinge)."""
        return round(self.output.loop_hinge_mm / self.strip.spacing_mm)

    @property
    def n_clamped(self) -> int:
        """Number of kinematic clamp nodes (s ≤ clamp length)."""
        return round(self.strip.clamp_length_mm / self.strip.spacing_mm) + 1

    @property
    def n_nodes(self) -> int:
        """Number of nodes, clamp included."""
        return round((self.strip.clamp_length_mm + self.strip.free_length_mm) / self.strip.spacing_mm) + 1

    @property
    def output_interval(self) -> float:
        """Seconds between probe samples."""
        return 1.0 / (self.output.frame_rate_hz * self.output.probes_per_frame)

    @property
    def preroll(self) -> float:
        """Seconds simulated before t = 0 (the hold), 0 without a release phase."""
        return self.release.move_time_s + self.release.settle_time_s if self.release.enabled else 0.0

    def to_dict(self) -> dict:
        """Plain nested dict (TOML-ready) of every field, defaults included."""
        return dataclasses.asdict(self)


def batch_fields() -> list[str]:
    """Dotted names of the fields that must agree across the strips of one batch."""
    return [f"{section}.{f.name}" for section, tp in _hints(Scene).items()
            for f in dataclasses.fields(tp) if not f.metadata["per_strip"]]


def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _coerce(value: Any, tp: Any, name: str, meta: dict) -> Any:
    origin = typing.get_origin(tp)
    if origin is list:
        (item,) = typing.get_args(tp)
        if not isinstance(value, list):
            raise SceneError(name, f"expected a list, got {value!r}")
        if dataclasses.is_dataclass(item):
            return [_parse(item, v, f"{name}[{i}]") for i, v in enumerate(value)]
        return [_coerce(v, item, f"{name}[{i}]", {}) for i, v in enumerate(value)]
    if tp is bool:
        if not isinstance(value, bool):
            raise SceneError(name, f"expected true or false, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(name, f"expected an integer, got {value!r}")
        out: Any = value
    elif tp is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(name, f"expected a number, got {value!r}")
        out = float(value)
        if not math.isfinite(out):
            raise SceneError(name, f"must be a finite number, got {out}")
    elif tp is str:
        if not isinstance(value, str):
            raise SceneError(name, f"expected a string, got {value!r}")
        choices = meta.get("choices")
        if choices and value not in choices:
            raise SceneError(name, f"must be one of {', '.join(choices)}; got {value!r}")
        return value
    else:  # pragma: no cover - schema error, not user error
        raise TypeError(f"unsupported field type {tp} for {name}")
    if meta.get("gt") is not None and not out > meta["gt"]:
        raise SceneError(name, f"must be > {meta['gt']:g}, got {out:g}")
    if meta.get("ge") is not None and not out >= meta["ge"]:
        raise SceneError(name, f"must be ≥ {meta['ge']:g}, got {out:g}")
    return out


def _parse(cls: type, data: Any, prefix: str) -> Any:
    if not isinstance(data, dict):
        raise SceneError(prefix or "scene", f"expected a table, got {data!r}")
    hints = _hints(cls)
    known = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in known:
            where = f"{prefix}.{key}" if prefix else key
            raise SceneError(where, f"unknown field; known fields here: {', '.join(known)}")
    kwargs = {}
    for name, f in known.items():
        if name not in data:
            continue
        where = f"{prefix}.{name}" if prefix else name
        tp = hints[name]
        if dataclasses.is_dataclass(tp):
            kwargs[name] = _parse(tp, data[name], where)
        else:
            kwargs[name] = _coerce(data[name], tp, where, dict(f.metadata))
    return cls(**kwargs)


def _parse_value(text: str) -> Any:
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text  # a bare word such as forward or float32


def set_field(data: dict, key: str, value: Any) -> None:
    """Set the field ``key`` (dotted; list items by index) of raw scene ``data`` in place.

    Setting ``material.from_file`` selects that material: the [material] values already in
    ``data`` are dropped so that the file supplies them (set other material fields after it).
    """
    parts = key.strip().split(".")
    if parts == MATERIAL_FILE_KEY.split("."):
        if not isinstance(value, str) or not value.strip():
            raise SceneError(MATERIAL_FILE_KEY, f"{value!r} names no material file; give a bundled material name "
                             f"({', '.join(bundled_materials())}) or a path ending in .toml")
        if value.endswith(".toml") and not Path(value).is_absolute():
            value = str(Path(value).resolve())  # relative to where the command runs, recorded absolute
        if isinstance(data.get("material"), dict):
            data["material"] = {k: v for k, v in data["material"].items() if k not in material_fields()}
    elif parts[0] == "material" and len(parts) > 2:
        # A list item of a material that comes from a file: the file's list first.
        data.update(_with_material_file(data))
    node: Any = data
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise SceneError(".".join(parts[: i + 1]), f"no list item {part!r}")
            if last:
                node[int(part)] = value
            else:
                node = node[int(part)]
        elif last:
            node[part] = value
        else:
            node = node.setdefault(part, {})
            if not isinstance(node, (dict, list)):
                raise SceneError(".".join(parts[: i + 1]), "is a value, not a section")


def apply_overrides(data: dict, overrides: typing.Iterable[str]) -> dict:
    """Return a copy of raw scene ``data`` with ``key=value`` overrides applied.

    Keys are dotted field names (``integrator.dt_s``); list items are addressed by
    index (``clamp.segments.1.t_end_s``). Values are TOML literals; a bare word is a
    string. Unknown keys are reported when the result is parsed. A ``material.from_file``
    override replaces the scene's own material values by the file's; the other
    ``material.*`` overrides apply on top of it, wherever they stand in the list.
    """
    data = copy.deepcopy(data)
    # stable sort: the material file first, so that it cannot undo a field override
    for item in sorted(overrides, key=lambda o: o.split("=", 1)[0].strip() != MATERIAL_FILE_KEY):
        if "=" not in item:
            raise SceneError(item, "an override must look like section.field=value")
        key, text = item.split("=", 1)
        set_field(data, key, _parse_value(text.strip()))
    return data


def bundled_scenes() -> list[str]:
    """Names of the scenes shipped with warpcloth."""
    root = importlib.resources.files("warpcloth.scenes")
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def bundled_materials() -> list[str]:
    """Names of the material files shipped with warpcloth (``scenes/materials/*.toml``)."""
    root = importlib.resources.files("warpcloth.scenes") / "materials"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def material_fields() -> list[str]:
    """The [material] fields a material file must give (every one but ``from_file``)."""
    return [f.name for f in dataclasses.fields(MaterialSection) if f.name != "from_file"]


def _parse_toml(text: str, where: str, field: str) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(field, f"{where} is not valid TOML: {exc}") from None


def read_material_file(ref: str | Path) -> dict:
    """Raw TOML of a material file, validated; ``ref`` is a path ending in ``.toml``
    (relative to the current directory) or the name of a bundled material.

    The file holds a ``[material]`` table with every scene [material] field except
    ``from_file``, plus ``source`` (where the numbers come from), and, for a fitted
    material, a ``[fit]`` table (residuals, KES summary values) that is informational.
    """
    ref = str(ref)
    if ref.endswith(".toml"):
        path = Path(ref)
        where = str(path)
        try:
            text = path.read_text()
        except OSError as exc:
            raise SceneError(MATERIAL_FILE_KEY, f"cannot read material file {ref!r}: {exc.strerror} (a path is "
                             f"relative to the scene file; a bundled material is named without .toml: "
                             f"{', '.join(bundled_materials())})") from None
    else:
        resource = importlib.resources.files("warpcloth.scenes") / "materials" / f"{ref}.toml"
        if not ref or not resource.is_file():
            raise SceneError(MATERIAL_FILE_KEY, f"no bundled material {ref!r} (bundled: "
                             f"{', '.join(bundled_materials())}; a material file is a path ending in .toml)")
        text = resource.read_text()
        where = f"bundled material {ref}"
    data = _parse_toml(text, where, MATERIAL_FILE_KEY)
    extra = sorted(set(data) - {"material", "fit"})
    if extra:
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: unknown top-level entry {extra[0]!r}; a material file "
                         "has a [material] and optionally a [fit] table")
    material = data.get("material")
    if not isinstance(material, dict) or not isinstance(data.get("fit", {}), dict):
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: needs a [material] table (and [fit], if any, a table)")
    missing = [k for k in [*material_fields(), "source"] if k not in material]
    if missing:
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: [material] lacks {', '.join(missing)}; a material file "
                         "gives every field, so that nothing silently comes from the default material")
    source = material["source"]
    if not isinstance(source, str) or not source.strip():
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: material.source must say where the numbers come from, "
                         f"got {source!r}")
    if "from_file" in material:
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: a material file cannot refer to another (from_file)")
    try:
        _parse(MaterialSection, {k: v for k, v in material.items() if k != "source"}, "material")
    except SceneError as exc:
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: {exc}") from None
    return data


def _with_material_file(data: dict) -> dict:
    # The material file fills only what the scene leaves unset; a resolved scene sets
    # every field, so the file is not even read (it may have moved since the run).
    material = data.get("material")
    if not isinstance(material, dict) or "from_file" not in material:
        return data
    ref = _coerce(material["from_file"], str, MATERIAL_FILE_KEY, {})
    missing = [k for k in material_fields() if k not in material]
    if not ref or not missing:
        return data
    values = read_material_file(ref)["material"]
    return {**data, "material": {**{k: values[k] for k in missing}, **material}}


def _rebase_material_file(data: dict, directory: Path) -> None:
    # A material path written in a scene file, in [material] or among the values of a
    # [sweep], is relative to that file, not to the directory the command runs in.
    def rebase(ref: Any) -> Any:
        if isinstance(ref, str) and ref.endswith(".toml") and not Path(ref).is_absolute():
            return str((directory / ref).resolve())
        return ref

    material = data.get("material")
    if isinstance(material, dict) and "from_file" in material:
        material["from_file"] = rebase(material["from_file"])
    sweep = data.get("sweep")
    for block in ("grid", "zip"):
        table = sweep.get(block) if isinstance(sweep, dict) else None
        if isinstance(table, dict) and isinstance(table.get(MATERIAL_FILE_KEY), list):
            table[MATERIAL_FILE_KEY] = [rebase(ref) for ref in table[MATERIAL_FILE_KEY]]


def read_scene_file(name_or_path: str | Path) -> dict:
    """Raw TOML data of a scene given by path or by bundled name (``damped_swing``).

    A relative ``material.from_file`` path in the file is made absolute against the
    scene file's directory.
    """
    path = Path(name_or_path)
    if path.is_file():
        text = path.read_text()
        where = str(path)
    else:
        resource = importlib.resources.files("warpcloth.scenes") / f"{path.stem}.toml"
        if path.suffix not in ("", ".toml") or not resource.is_file():
            raise SceneError("scene", f"no scene file {str(name_or_path)!r} and no bundled scene of that "
                             f"name (bundled: {', '.join(bundled_scenes())})")
        text = resource.read_text()
        where = f"bundled scene {path.stem}"
    data = _parse_toml(text, where, "scene")
    if path.is_file():
        _rebase_material_file(data, path.parent)
    return data


def scene_from_dict(data: dict) -> Scene:
    """Parse and validate raw scene data.

    A ``material.from_file`` (path or bundled name) fills every [material] field the data
    do not set; the scene holds the explicit values afterwards, so ``to_dict()`` re-reads
    to the same scene.
    """
    scene = _parse(Scene, _with_material_file(data), "")
    validate_scene(scene)
    return scene


def load_scene(name_or_path: str | Path, overrides: typing.Iterable[str] = ()) -> Scene:
    """Read a scene by path or bundled name, apply ``--set`` overrides, validate it.

    A ``[sweep]`` section is ignored here: this is the sweep's base scene.
    """
    data = read_scene_file(name_or_path)
    data.pop("sweep", None)
    return scene_from_dict(apply_overrides(data, overrides))


def _multiple(length: float, spacing: float) -> bool:
    ratio = length / spacing
    return abs(ratio - round(ratio)) < 1e-9 * max(1.0, ratio)


def validate_scene(scene: Scene) -> None:
    """Cross-field checks that single fields cannot express; raises SceneError."""
    st = scene.strip
    for name in ("free_length_mm", "clamp_length_mm"):
        if not _multiple(getattr(st, name), st.spacing_mm):
            raise SceneError("strip.spacing_mm", f"{st.spacing_mm:g} mm does not divide strip.{name} = "
                             f"{getattr(st, name):g} mm into whole segments")
    if scene.n_nodes - scene.n_clamped < 2:
        raise SceneError("strip.spacing_mm", f"{st.spacing_mm:g} mm leaves fewer than 2 free nodes")
    validate_material(scene.material, scene.integrator.divergence_strain, "material")
    _validate_clamp(scene.clamp)
    if scene.release.enabled:
        r = math.hypot(scene.release.hold_x_mm, scene.release.hold_y_mm)
        if not st.spacing_mm <= r <= st.free_length_mm:
            raise SceneError("release.hold_x_mm", f"held position ({scene.release.hold_x_mm:g}, "
                             f"{scene.release.hold_y_mm:g}) mm is {r:g} mm from the clamp's lowest point; "
                             f"the free end reaches between {st.spacing_mm:g} and {st.free_length_mm:g} mm")
    n_hinges = scene.n_nodes - scene.n_clamped
    if not _multiple(scene.output.loop_hinge_mm, st.spacing_mm) or scene.loop_hinge >= n_hinges:
        raise SceneError("output.loop_hinge_mm", f"{scene.output.loop_hinge_mm:g} mm is not a hinge: hinges lie "
                         f"every strip.spacing_mm = {st.spacing_mm:g} mm from 0 to "
                         f"{st.free_length_mm - st.spacing_mm:g} mm below the clamp")
    dt = scene.integrator.dt_s
    if dt > scene.output_interval:
        raise SceneError("integrator.dt_s", f"{dt:g} s is longer than the probe interval "
                         f"{scene.output_interval:g} s (output.frame_rate_hz × output.probes_per_frame)")
    steps = (scene.preroll + scene.run.duration_s) / dt
    if steps > MAX_STEPS:
        raise SceneError("run.duration_s", f"{scene.preroll + scene.run.duration_s:g} s at dt {dt:g} s is "
                         f"{steps:.3g} steps, more than {MAX_STEPS}")


def _validate_clamp(clamp: ClampSection) -> None:
    if clamp.motion == "piecewise":
        if not clamp.segments:
            raise SceneError("clamp.segments", "motion = 'piecewise' needs at least one segment")
        for i, seg in enumerate(clamp.segments):
            where = f"clamp.segments[{i}]"
            if not seg.t_end_s > seg.t_start_s:
                raise SceneError(f"{where}.t_end_s", f"{seg.t_end_s:g} must be after t_start_s {seg.t_start_s:g}")
            if not 1 <= len(seg.theta_coefficients_si) <= 5:
                raise SceneError(f"{where}.theta_coefficients_si",
                                 f"needs 1 to 5 coefficients (up to a quartic), got {len(seg.theta_coefficients_si)}")
            if i:
                prev = clamp.segments[i - 1]
                if abs(seg.t_start_s - prev.t_end_s) > 1e-12:
                    raise SceneError(f"{where}.t_start_s", f"{seg.t_start_s:g} s must equal the previous "
                                     f"segment's t_end_s {prev.t_end_s:g} s")
                tau = prev.t_end_s - prev.t_start_s
                end = sum(c * tau**k for k, c in enumerate(prev.theta_coefficients_si))
                jump = seg.theta_coefficients_si[0] - end
                if abs(jump) > 1e-9 * max(1.0, abs(end)):
                    raise SceneError(f"{where}.theta_coefficients_si",
                                     f"θ jumps by {jump:.3g} rad at t = {seg.t_start_s:g} s; the clamp "
                                     "cannot teleport (make c_0 equal the previous segment's end value)")
    elif clamp.motion == "table":
        t, th = clamp.table_t_s, clamp.table_theta_rad
        if len(t) < 2 or len(t) != len(th):
            raise SceneError("clamp.table_theta_rad", f"needs as many samples as clamp.table_t_s, at least 2 "
                             f"(got {len(t)} times and {len(th)} angles)")
        for i in range(1, len(t)):
            if not t[i] > t[i - 1]:
                raise SceneError(f"clamp.table_t_s[{i}]", f"{t[i]:g} s must be after {t[i - 1]:g} s")
