"""Materials: KES → SI (the one conversion), physical validity, and material files
(bundled by name, or a path ending in .toml) that fill a scene's [material]."""

from __future__ import annotations

import copy
import dataclasses
import functools
import importlib.resources
from pathlib import Path

import numpy as np

from warpcloth import units
from warpcloth.errors import SceneError
from warpcloth.kernels import BENDING_LAWS, DEFAULT_BENDING_LAW, bending_law
from warpcloth.kernels.law import BENDING_RIGIDITY, LawParameter
from warpcloth.kernels.laws import LAW_PARAMETERS
from warpcloth.strip import LawParameters, MaterialSI

from .keys import field_line
from .parse import coerce_value, parse_section, parse_toml, read_toml_text
from .schema import MaterialSection
from .shear import SHEAR_TABLE, ShearMaterial, parse_shear

MATERIAL_FILE_KEY = "material.from_file"
WEFT_TABLE = "weft"
"""A material file's table of the weft direction's tensile and bending fields, where they
differ from [material]'s (the warp's); the woven sheet reads it, a strip ignores it."""
BIAS_TABLE = "bias"
"""A material file's or sheet scene's table of bending on the bias, as KES-FB2 measures it
(a sample cut at 45°: its B and the law's hysteresis), and the bending Poisson ratio; the
woven sheet derives its twist from it (docs/model.md §17.4), a strip ignores it."""
ONE_PER_FABRIC = ("name", "density_g_per_cm2", "from_file")
"""[material] fields that have no per-direction value: a woven fabric has one areal density."""


def si_value(parameter: LawParameter, value: float) -> float:
    """A law parameter's scene value (KES units) in SI, by the unit its description names."""
    return units.from_kes(value, units.BENDING_UNITS[parameter.kind][0])


def to_si(section: MaterialSection) -> MaterialSI:
    """Convert a KES-unit material section to SI (the only KES → SI conversion of a material)."""
    law = bending_law(section.bending_law)
    return MaterialSI(
        density=section.density_g_per_cm2 * units.AREAL_DENSITY_G_PER_CM2,
        tensile=tuple(a * units.TENSILE_GF_PER_CM for a in section.tensile_gf_per_cm),
        bending_rigidity=si_value(BENDING_RIGIDITY, getattr(section, BENDING_RIGIDITY.scene_field)),
        bending=LawParameters.of(
            law.name, {p.name: si_value(p, getattr(section, p.scene_field)) for p in law.parameters}
        ),
    )


def field_laws(dotted: str) -> tuple[str, ...]:
    """The bending laws whose parameter the scene field ``dotted`` (``material.dahl_exponent``)
    is; empty for a field every law reads, or one outside [material]."""
    section, _, key = dotted.partition(".")
    return LAW_PARAMETERS[key][1] if section == "material" and key in LAW_PARAMETERS else ()


def law_fields(law: str) -> list[str]:
    """The [material] fields that are parameters of the bending law ``law`` (not of every law)."""
    return [p.scene_field for p in bending_law(law).parameters]


def law_aliases() -> dict[str, str]:
    """Every law parameter's short name (``Ms``), D's included, and its dotted scene field."""
    return {
        p.alias: f"material.{p.scene_field}"
        for p in (BENDING_RIGIDITY, *(parameter for parameter, _ in LAW_PARAMETERS.values()))
    }


def hysteresis_amplitudes() -> tuple[str, ...]:
    """The dotted scene fields that set the size of a law's hysteresis (0 = elastic)."""
    return tuple(f"material.{field}" for field, (p, _) in LAW_PARAMETERS.items() if p.amplitude)


def tensile_slope_minimum(coefficients: list[float], max_strain: float) -> tuple[float, float]:
    """Smallest dT/dε of the quartic on [0, max_strain] and the strain where it occurs.

    The minimum of a cubic slope lies at an end or where T'' = 0, so it is found exactly.
    """
    a1, a2, a3, a4 = coefficients
    slope = np.polynomial.Polynomial([a1, 2 * a2, 3 * a3, 4 * a4])
    candidates = [0.0, max_strain]
    candidates += [r.real for r in slope.deriv().roots() if abs(r.imag) < 1e-12 and 0 < r.real < max_strain]
    values = [(float(slope(e)), e) for e in candidates]
    return min(values)


def validate_material(section: MaterialSection, max_strain: float, prefix: str) -> None:
    """Raise SceneError unless the material is physically usable up to ``max_strain``."""
    for f in dataclasses.fields(MaterialSection):
        laws = f.metadata.get("laws", ())
        if laws and section.bending_law not in laws and getattr(section, f.name) != f.default:
            law = " or ".join(laws)
            origin = (
                (
                    f" (set by the scene or by its material file {section.from_file!r}: a material file "
                    "gives the fields of its own law)"
                )
                if section.from_file
                else ""
            )
            raise SceneError(
                f"{prefix}.{f.name}",
                f"= {getattr(section, f.name)!r} is a parameter of the "
                f"{law} bending law, but {prefix}.bending_law is {section.bending_law!r} (whose "
                f"parameters are {', '.join(law_fields(section.bending_law))}){origin}; set "
                f'{prefix}.bending_law = "{laws[0]}", use a material of that law, or leave the field '
                "out",
            )
    a = section.tensile_gf_per_cm
    if len(a) != 4:
        raise SceneError(f"{prefix}.tensile_gf_per_cm", f"needs the 4 coefficients a1..a4, got {len(a)}")
    slope, strain = tensile_slope_minimum(a, max_strain)
    if not slope > 0:
        raise SceneError(
            f"{prefix}.tensile_gf_per_cm",
            f"T(ε) with a = {a} is not increasing at ε = {strain:.4g} (dT/dε = {slope:.4g} "
            f"gf/cm); it must increase on [0, integrator.divergence_strain = {max_strain:g}]",
        )


def bundled_materials() -> list[str]:
    """Names of the material files shipped with warpcloth (``scenes/materials/*.toml``)."""
    root = importlib.resources.files("warpcloth.scenes") / "materials"
    return sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml"))


def material_fields(law: str | None = None) -> list[str]:
    """The [material] fields a material file gives (every one but ``from_file``); for
    ``law``, only those that law reads (the common ones and its own parameters)."""
    return [
        f.name
        for f in dataclasses.fields(MaterialSection)
        if f.name not in ("from_file", "bending_law")
        and (law is None or not f.metadata.get("laws") or law in f.metadata["laws"])
    ]


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
            text = read_toml_text(path)
        except OSError as exc:
            raise SceneError(
                MATERIAL_FILE_KEY,
                f"cannot read material file {ref!r}: {exc.strerror} (a path is "
                f"relative to the scene file; a bundled material is named without .toml: "
                f"{', '.join(bundled_materials())})",
            ) from None
    else:
        resource = importlib.resources.files("warpcloth.scenes") / "materials" / f"{ref}.toml"
        if not ref or not resource.is_file():
            raise SceneError(
                MATERIAL_FILE_KEY,
                f"no bundled material {ref!r} (bundled: "
                f"{', '.join(bundled_materials())}; a material file is a path ending in .toml)",
            )
        text = resource.read_text()
        where = f"bundled material {ref}"
    return copy.deepcopy(_checked_material(text, where))


@functools.lru_cache(maxsize=64)
def _checked_material(text: str, where: str) -> dict:
    # Keyed by the file's text: a sweep of thousands of variants naming one material file
    # reads it each time but parses and validates it once (0.6 ms a variant), and an
    # edited file is a new key. A refusal raises, and is not cached.
    data = parse_toml(text, where, MATERIAL_FILE_KEY)
    extra = sorted(set(data) - {"material", "fit", SHEAR_TABLE, WEFT_TABLE, BIAS_TABLE})
    if extra:
        raise SceneError(
            MATERIAL_FILE_KEY,
            f"{where}: unknown top-level entry {extra[0]!r}; a material file "
            "has a [material] and optionally a [weft], a [bias], a [shear] and a [fit] table",
        )
    material = data.get("material")
    if not isinstance(material, dict) or not isinstance(data.get("fit", {}), dict):
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: needs a [material] table (and [fit], if any, a table)")
    # a file without bending_law predates the other laws: the paper's
    law = material.get("bending_law", DEFAULT_BENDING_LAW)
    if not isinstance(law, str) or law not in BENDING_LAWS:
        raise SceneError(
            MATERIAL_FILE_KEY, f"{where}: material.bending_law must be one of {', '.join(BENDING_LAWS)}; got {law!r}"
        )
    missing = [k for k in [*material_fields(law), "source"] if k not in material]
    if missing:
        # a field under another name is most often another unit (bending_rigidity_N_m):
        # name it beside what is missing
        unknown = sorted(set(material) - {*material_fields(), "source", "bending_law", "from_file"})
        instead = f" (it has {', '.join(unknown)}, which no field is called: a field's unit is part of its name)"
        raise SceneError(
            MATERIAL_FILE_KEY,
            f"{where}: [material] lacks {', '.join(missing)}{instead if unknown else ''}; a material file "
            f"gives every field its bending law ({law}) reads, so that nothing silently comes from "
            "the default material",
        )
    source = material["source"]
    if not isinstance(source, str) or not source.strip():
        raise SceneError(
            MATERIAL_FILE_KEY, f"{where}: material.source must say where the numbers come from, got {source!r}"
        )
    if "from_file" in material:
        raise SceneError(MATERIAL_FILE_KEY, f"{where}: a material file cannot refer to another (from_file)")
    try:
        parse_section(MaterialSection, {k: v for k, v in material.items() if k != "source"}, "material")
        if SHEAR_TABLE in data:
            parse_shear(data[SHEAR_TABLE])
        if WEFT_TABLE in data:
            parse_weft(data[WEFT_TABLE])
        if BIAS_TABLE in data:
            parse_bias(data[BIAS_TABLE])
    except SceneError as exc:
        line = field_line(text, exc.field)
        raise SceneError(MATERIAL_FILE_KEY, f"{where}{f', line {line}' if line else ''}: {exc}") from None
    return data


def parse_weft(table: object, prefix: str = WEFT_TABLE) -> dict:
    """The ``[weft]`` table of a material file or sheet scene, checked: [material] fields
    other than :data:`ONE_PER_FABRIC`, each valid as a [material] field; else a SceneError
    of ``weft.<field>``. Returns the table."""
    if not isinstance(table, dict):
        raise SceneError(prefix, f"[{prefix}] must be a table, got {table!r}")
    for key in table:
        if key in ONE_PER_FABRIC:
            raise SceneError(
                f"{prefix}.{key}",
                "has one value per fabric, in [material]; [weft] gives only the weft's tensile and bending fields",
            )
    parse_section(MaterialSection, table, prefix)
    return table


BIAS_ONLY = ("bending_poisson_ratio",)
"""[bias] fields that are not [material] fields."""


def parse_bias(table: object, prefix: str = BIAS_TABLE) -> dict:
    """The ``[bias]`` table of a material file or sheet scene, checked: the bending fields
    of [material] (not its tensile ones) and ``bending_poisson_ratio``; else a SceneError
    of ``bias.<field>``. Returns the table."""
    if not isinstance(table, dict):
        raise SceneError(prefix, f"[{prefix}] must be a table, got {table!r}")
    for key in table:
        if key in ONE_PER_FABRIC or key == "tensile_gf_per_cm":
            raise SceneError(
                f"{prefix}.{key}",
                "is not a bias field: [bias] gives bending on the bias (bending_rigidity_gf_cm2_per_cm and the "
                "law's hysteresis, as KES-FB2 measures a sample cut at 45°) and bending_poisson_ratio",
            )
    ratio = table.get("bending_poisson_ratio", 0.0)
    if isinstance(ratio, bool) or not isinstance(ratio, int | float) or not abs(ratio) < 1:
        raise SceneError(
            f"{prefix}.bending_poisson_ratio",
            f"must be a number in (−1, 1) (D12 = ν √(D11 D22), D12² < D11 D22), got {ratio!r}",
        )
    parse_section(MaterialSection, {k: v for k, v in table.items() if k not in BIAS_ONLY}, prefix)
    return table


def material_shear(ref: str | Path) -> ShearMaterial | None:
    """The shear of a material file or bundled material (its ``[shear]``), or None when it
    gives none (docs/model.md §17.1)."""
    data = read_material_file(ref)
    return parse_shear(data[SHEAR_TABLE], str(ref)) if SHEAR_TABLE in data else None


def with_material_file(data: dict) -> dict:
    """Raw scene ``data`` with the [material] fields it leaves unset taken from its
    ``material.from_file`` (unchanged when it names none or sets every field)."""
    # The material file fills only what the scene leaves unset; a resolved scene sets
    # every field, so the file is not even read (it may have moved since the run).
    material = data.get("material")
    if not isinstance(material, dict) or "from_file" not in material:
        return data
    ref = coerce_value(material["from_file"], str, MATERIAL_FILE_KEY, {})
    missing = [k for k in [*material_fields(), "bending_law"] if k not in material]
    if not missing:
        return data
    if not ref.strip():
        raise SceneError(
            MATERIAL_FILE_KEY,
            f"{ref!r} names no material file, and the scene leaves "
            f"{', '.join(missing)} to it; give a bundled material name or a path ending in .toml",
        )
    values = read_material_file(ref)["material"]
    values = {"bending_law": DEFAULT_BENDING_LAW, **values}
    return {**data, "material": {**{k: values[k] for k in [*missing, "bending_law"] if k in values}, **material}}
