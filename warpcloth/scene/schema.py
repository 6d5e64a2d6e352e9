"""The scene schema: what a scene file may say, field by field.

A scene is a TOML file whose sections map onto the dataclasses below. Every field
carries its unit in its name and a one-line description in its metadata (the user guide's
scene reference is the same information); ``per_strip`` fields may differ between the
strips of one batch, the others split a sweep into batches. The default material is the
bundled material file ``wool90-nylon10``: its numbers live there only.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import importlib.resources
import tomllib
import typing
from dataclasses import dataclass, field
from typing import Any

from warpcloth import units
from warpcloth.kernels import BENDING_LAWS, DEFAULT_BENDING_LAW, bending_masing
from warpcloth.kernels.law import BENDING_RIGIDITY, LawParameter
from warpcloth.kernels.laws import LAW_PARAMETERS
from warpcloth.strip import SOLVERS

EDGE_HINGES = ("second_order", "paper")
"""Choices of ``clamp.edge_hinge``, the treatment of the built-in end (docs/model.md §5.3)."""

DEFAULT_MATERIAL_NAME = "wool90-nylon10"
"""The bundled material every scene uses unless it says otherwise."""


def _bundled_default_material() -> dict:
    resource = importlib.resources.files("warpcloth.scenes") / "materials" / f"{DEFAULT_MATERIAL_NAME}.toml"
    values = tomllib.loads(resource.read_text())["material"]
    return {k: v for k, v in values.items() if k != "source"}


DEFAULT_MATERIAL = _bundled_default_material()
"""The default material's fields, read from the bundled ``wool90-nylon10`` material file:
docs/model.md's illustrative wool 90 % / nylon 10 % (warp direction). The paper's measured
Fig. 8 curves are not in its text, so these numbers are plausible, not measured."""


AUTO = "auto"
"""The word ``integrator.dt_s`` takes for a step warpcloth chooses."""

MAX_STEPS_DEFAULT = 10**8
"""Steps of each body a run may take unless its scene's ``integrator.max_steps`` says more:
23 times the paper's own step count (dt = 1e-7 s over a 4.3 s hold and swing), and beyond it
a step has collapsed under a stiffness or spacing no fabric has (docs/promises.md)."""


def _field(
    default: Any,
    doc: str,
    *,
    gt: float | None = None,
    ge: float | None = None,
    choices: tuple[str, ...] | None = None,
    per_strip: bool = False,
    laws: tuple[str, ...] = (),
    words: tuple[str, ...] = (),
) -> Any:
    # ``laws``: the field is a parameter of those bending laws only (material fields; none: every law's)
    # ``words``: strings a number field also takes (dt_s = "auto")
    meta = {"doc": doc, "gt": gt, "ge": ge, "choices": choices, "per_strip": per_strip, "laws": laws, "words": words}
    if isinstance(default, list):
        return field(default_factory=lambda: list(default), metadata=meta)
    return field(default=default, metadata=meta)


@dataclass(frozen=True)
class StripSection:
    """Geometry of the strip (paper §3.1)."""

    free_length_mm: float = _field(100.0, "length hanging below the clamp", gt=0)
    clamp_length_mm: float = _field(20.0, "length held in the clamp (kinematic nodes)", gt=0)
    width_mm: float = _field(50.0, "strip width W (forces, masses and moments scale with it)", gt=0, per_strip=True)
    spacing_mm: float = _field(5.0, "node spacing h; must divide both lengths", gt=0)
    rest_curvature_per_cm: float = _field(
        0.0,
        "K_rest, the natural curvature the unloaded strip keeps (its set, "
        "'kuse'), in the bending plane, counter-clockwise positive; every bending "
        "law acts on K − K_rest (docs/model.md §5.4)",
        per_strip=True,
    )
    rest_curvature_table_s_mm: list[float] = _field(
        [],
        "arc lengths below the clamp's lowest point of a profile "
        "K_rest(s), strictly increasing from 0 to at least "
        "free_length_mm (linear between; instead of "
        "rest_curvature_per_cm)",
        per_strip=True,
    )
    rest_curvature_table_per_cm: list[float] = _field(
        [], "K_rest at those arc lengths (counter-clockwise +)", per_strip=True
    )


def _law_field(parameter: LawParameter, laws: tuple[str, ...]) -> Any:
    # A law's parameter as a [material] field: the default material's value where it gives one,
    # else the law's own default (which may be the default material's loop).
    default = DEFAULT_MATERIAL.get(parameter.scene_field)
    if default is None:
        given = {p.name: DEFAULT_MATERIAL[name] for name, (p, _) in LAW_PARAMETERS.items() if name in DEFAULT_MATERIAL}
        default = parameter.default(given) if callable(parameter.default) else parameter.default
    if default is None:
        raise ImportError(
            f"the default material {DEFAULT_MATERIAL_NAME!r} lacks {parameter.scene_field}, and the "
            f"{' and '.join(laws)} law gives it no default"
        )
    return _field(
        default, f"{', '.join(laws)}: {parameter.doc}", gt=parameter.gt, ge=parameter.ge, per_strip=True, laws=laws
    )


def _with_law_fields(cls: type) -> type:
    # Every law's own parameters (from the laws' descriptions, kernels/law.py) as fields,
    # after the common ones and before from_file, ahead of @dataclass reading the class.
    annotations = dict(cls.__dict__["__annotations__"])
    last = annotations.pop("from_file")
    for name, (parameter, laws) in LAW_PARAMETERS.items():
        annotations[name] = "float"
        setattr(cls, name, _law_field(parameter, laws))
    annotations["from_file"] = last
    cls.__annotations__ = annotations
    return cls


@dataclass(frozen=True)
@_with_law_fields
class MaterialSection:
    """Fabric in KES units; converted to SI once, by warpcloth.scene.to_si. The bending laws'
    own fields (between ``bending_law`` and ``from_file``) come from their descriptions
    (kernels/law.py)."""

    name: str = _field(DEFAULT_MATERIAL["name"], "label (the default is illustrative, docs/model.md)", per_strip=True)
    density_g_per_cm2: float = _field(DEFAULT_MATERIAL["density_g_per_cm2"], "mass per area ρ_A", gt=0, per_strip=True)
    tensile_gf_per_cm: list[float] = _field(
        DEFAULT_MATERIAL["tensile_gf_per_cm"],
        "a1..a4 of T(ε) = a1 ε + a2 ε² + a3 ε³ + a4 ε⁴ (force per width, KES-FB1 upper loop)",
        per_strip=True,
    )
    bending_rigidity_gf_cm2_per_cm: float = _field(
        DEFAULT_MATERIAL[BENDING_RIGIDITY.scene_field], BENDING_RIGIDITY.doc, ge=BENDING_RIGIDITY.ge, per_strip=True
    )
    bending_law: str = _field(
        DEFAULT_MATERIAL.get("bending_law", DEFAULT_BENDING_LAW),
        "hysteretic bending law (docs/model.md §4): "
        + ", ".join(f"{law.name} ({law.summary})" for law in BENDING_LAWS.values())
        + "; each reads only its own fields below",
        choices=tuple(BENDING_LAWS),
        per_strip=True,
    )
    from_file: str = _field(
        "",
        "a material file (path ending in .toml, relative to the scene file) or a bundled "
        "material name; its values fill every [material] field the scene does not set itself",
        per_strip=True,
    )


@dataclass(frozen=True)
class DampingSection:
    """Viscous damping F = −γ m v (residual air and internal viscosity, tuned)."""

    gamma_per_s: float = _field(0.0, "γ after release", ge=0, per_strip=True)


@dataclass(frozen=True)
class ClampSegment:
    """One piece of θ(t) = Σ c_k (t − t_start)^k on [t_start, t_end]."""

    t_start_s: float = _field(0.0, "segment start time", per_strip=True)
    t_end_s: float = _field(0.0, "segment end time (> t_start_s)", per_strip=True)
    theta_coefficients_si: list[float] = _field([0.0], "c_0..c_4 in rad/s^k (at most a quartic)", per_strip=True)


@dataclass(frozen=True)
class ClampSection:
    """Kinematic clamp: rigid rotation θ(t) about a rotation centre."""

    motion: str = _field(
        "fixed",
        "fixed | piecewise (segments) | table (sampled θ)",
        choices=("fixed", "piecewise", "table"),
        per_strip=True,
    )
    rotation_centre_dx_mm: float = _field(0.0, "rotation centre x offset from the clamp's lowest point", per_strip=True)
    rotation_centre_dy_mm: float = _field(
        0.0, "rotation centre y offset (up +) from the clamp's lowest point", per_strip=True
    )
    segments: list[ClampSegment] = _field([], "piecewise polynomial θ(t), contiguous, θ continuous", per_strip=True)
    table_t_s: list[float] = _field([], "sampled times, strictly increasing", per_strip=True)
    table_theta_rad: list[float] = _field([], "sampled angles (counter-clockwise +)", per_strip=True)
    interpolation: str = _field(
        "linear", "linear | cubic (natural spline) for a table", choices=("linear", "cubic"), per_strip=True
    )
    edge_hinge: str = _field(
        "second_order",
        "second_order (the clamp-edge hinge bends the half segment below "
        "the built-in end: second order in h) | paper (the paper's model: as if clamped "
        "h/2 inside the clamp, first order)",
        choices=EDGE_HINGES,
        per_strip=True,
    )
    grip_length_mm: float = _field(
        0.0,
        "ℓ_g, length below the clamp edge that the clamp's grip stiffens (0: no grip zone; docs/model.md §5.4)",
        ge=0,
        per_strip=True,
    )
    grip_bending_factor: float = _field(
        1.0,
        "bending rigidity D in the grip zone, as a multiple of the fabric's (1: no grip effect)",
        gt=0,
        per_strip=True,
    )
    grip_hysteresis_factor: float = _field(
        1.0,
        "hysteresis amplitude in the grip zone, as a multiple of the fabric's (1: no grip effect)",
        ge=0,
        per_strip=True,
    )


@dataclass(frozen=True)
class ReleaseSection:
    """Hold-and-release start of the damped swing: the free end is carried to a held
    position, held while the strip settles, then released at t = 0."""

    enabled: bool = _field(False, "start with the hold-and-release phase")
    hold_free_end: bool = _field(
        True,
        "carry the free end to the held position and hold it; false: the free end "
        "is left free and the strip settles under its own weight (a strip with a set "
        "starts from its own hanging shape, docs/model.md §8)",
        per_strip=True,
    )
    hold_x_mm: float = _field(50.0, "held free-end x, from the clamp's lowest point", per_strip=True)
    hold_y_mm: float = _field(-80.0, "held free-end y (up +), from the clamp's lowest point", per_strip=True)
    allow_fold: bool = _field(
        False,
        "hold the free end where the strip's slack sags below it by more than a tenth of its length "
        "(a hanging chain's sag): the swing then starts from a fold, which is refused unless true",
    )
    move_time_s: float = _field(0.3, "time to carry the free end to the held position", gt=0)
    settle_time_s: float = _field(1.0, "time held before release", ge=0)
    settle_damping_per_s: float = _field(20.0, "γ while held, so the strip settles", ge=0, per_strip=True)


@dataclass(frozen=True)
class IntegratorSection:
    """Explicit time integration (paper §2.3)."""

    scheme: str = _field(
        "semi_implicit",
        " | ".join(f"{name} ({solver.label})" for name, solver in SOLVERS.items()),
        choices=tuple(SOLVERS),
    )
    dt_s: float = _field(
        1e-5,
        "time step (the paper used 1e-7); with semi_implicit below the stretching limit "
        'h·√(ρ_A/a1)/cos(π/4N), docs/model.md §9.3; "auto": the longest step stable and '
        "measured accurate, a whole fraction of the probe interval (§9.6)",
        gt=0,
        words=("auto",),
    )
    dt_chosen_by: str = _field(
        "scene",
        'how dt_s was set: "auto" when the scene asked for dt_s = "auto" '
        '(warpcloth writes the step it chose into dt_s), else "scene"',
        choices=("scene", "auto"),
    )
    precision: str = _field("float64", "float64 | float32", choices=("float64", "float32"))
    divergence_strain: float = _field(
        0.25, "|ε| beyond which a strip counts as diverged; the tensile curve must increase up to it", gt=0
    )
    reversal_memory: int = _field(
        bending_masing.DEFAULT_CAPACITY,
        "masing: open reversal points each hinge keeps (16 B each per hinge); a reversal "
        "beyond it is counted and reported (docs/model.md §4.10)",
        ge=1,
    )
    max_steps: int = _field(
        MAX_STEPS_DEFAULT,
        "steps of each strip a run may take (settling and the record together); a step that "
        "collapses (a stiffness or spacing beyond reason) is refused past it: raise it to run a long "
        "run on purpose, up to 2147483647",
        ge=1,
    )


@dataclass(frozen=True)
class RunSection:
    """Length of the recorded run and the environment."""

    duration_s: float = _field(2.0, "recorded time after t = 0 (release)", gt=0)
    gravity_m_per_s2: float = _field(9.80665, "g (0 for the beam test)", ge=0)


@dataclass(frozen=True)
class OutputSection:
    """What is recorded and how often."""

    frame_rate_hz: float = _field(60.0, "shape frames per second (the paper's video rate)", gt=0)
    probes_per_frame: int = _field(10, "probe samples per frame interval", ge=1)
    laser_height_mm: float = _field(-80.0, "height of the laser line, from the clamp's lowest point")
    loop_hinge_mm: float = _field(
        0.0,
        "arc length below the clamp's lowest point of the hinge whose curvature and "
        "moment are probed (the moment–curvature loop); 0 = the clamp-edge hinge",
        ge=0,
    )


@functools.cache
def _field_names(cls: type) -> tuple[str, ...]:
    return tuple(f.name for f in dataclasses.fields(cls))


_ATOMS = (str, int, float, bool, type(None))


def plain(value: Any) -> Any:
    """``value`` as :func:`dataclasses.asdict` gives it (dataclasses as dicts, containers
    copied, the same values), without its generic deep copy of every number: a sweep
    converts each variant's scene several times (batch keys, fingerprint, records)."""
    if isinstance(value, _ATOMS):
        return value
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {name: plain(getattr(value, name)) for name in _field_names(type(value))}
    if isinstance(value, tuple) and hasattr(value, "_fields"):  # a named tuple
        return type(value)(*(plain(v) for v in value))
    if isinstance(value, (list, tuple)):
        return type(value)(plain(v) for v in value)
    if isinstance(value, dict):
        return {plain(k): plain(v) for k, v in value.items()}
    return copy.deepcopy(value)


@dataclass(frozen=True)
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
    def edge_hinge_length(self) -> float:
        """Length (m) of strip the clamp-edge hinge bends: h/2 second order, h the paper's."""
        return self.spacing * (0.5 if self.clamp.edge_hinge == "second_order" else 1.0)

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
        return plain(self)


def batch_fields() -> list[str]:
    """Dotted names of the fields that must agree across the strips of one batch."""
    return [
        f"{section}.{f.name}"
        for section, tp in field_types(Scene).items()
        for f in dataclasses.fields(tp)
        if not f.metadata["per_strip"]
    ]


def choice_fields() -> list[str]:
    """Dotted names of the per-strip fields that are a choice among named values
    (``material.bending_law``, ...)."""
    return [
        f"{section}.{f.name}"
        for section, tp in field_types(Scene).items()
        for f in dataclasses.fields(tp)
        if f.metadata["per_strip"] and f.metadata.get("choices")
    ]


def field_types(cls: type) -> dict[str, Any]:
    """The resolved type of every field of the dataclass ``cls``."""
    return dict(_resolved_hints(cls))


@functools.cache
def _resolved_hints(cls: type) -> dict[str, Any]:
    # resolving a class's string annotations compiles each one: once per class, not per
    # scene parsed (a 10 000-variant sweep parses 10 000 scenes)
    return typing.get_type_hints(cls)
