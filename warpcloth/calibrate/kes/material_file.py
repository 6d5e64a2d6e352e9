"""Material files from a KES fit: a ``[material]`` table (the scene's material fields in
KES units, docs/model.md §1, and a ``source``) and an informational ``[fit]`` table
(files, residuals, KES values; docs/model.md §13)."""

from __future__ import annotations

import math
from pathlib import Path

import tomli_w

from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.io.atomic import write_text_atomically
from warpcloth.scene import MaterialSection, material_fields, parse_shear, validate_material
from warpcloth.units import check_plausible

from .bending_fit import worst_status
from .kes_fit import KesFit
from .shear_fit import ShearFit
from .tensile_fit import DIVERGENCE_STRAIN


def material_file_data(
    fit: KesFit,
    name: str,
    density_g_per_cm2: float,
    source: str,
    max_strain: float = DIVERGENCE_STRAIN,
    shear: ShearFit | None = None,
) -> dict:
    """The TOML data of a material file for a fit, checked usable up to ``max_strain``;
    with ``shear``, its ``[shear]`` table too (docs/model.md §17.1)."""
    if not (math.isfinite(density_g_per_cm2) and density_g_per_cm2 > 0):
        raise ArgumentError(
            "density_g_per_cm2", f"must be a positive mass per area in g/cm², got {density_g_per_cm2!r}"
        )
    check_plausible("areal density", density_g_per_cm2, "--density-g-per-cm2")
    material = fit.material(name, density_g_per_cm2)
    # a fit whose numbers overflowed is not written: a scene would load it as a material
    values = {f"material.{k}": v for k, v in material.items()} | {
        "the tensile RMS": fit.tensile.rms_gf_per_cm,
        "the bending RMS": fit.bending.rms_gf_cm_per_cm,
    }
    for field, value in values.items():
        numbers = value if isinstance(value, list) else [value]
        if any(isinstance(v, float) and not math.isfinite(v) for v in numbers):
            source = fit.tensile_loop.source if "tensile" in field else fit.bending_loop.source
            raise DataFileError(
                source,
                f"the fit gave {field} = {value!r}, not a finite number: no material file "
                "is written (are the numbers in the units the header says?)",
            )
    validate_material(MaterialSection(**material), max_strain, "material")
    law = material["bending_law"]
    ordered = {
        "name": name,
        "source": source,
        "bending_law": law,
        **{k: material[k] for k in material_fields(law) if k != "name"},
    }
    data = {"material": ordered, "fit": fit.summary_table()}
    if shear is not None:
        table = shear.shear.table()
        # the law's values and the fit's own numbers (an RMS that overflowed): a shear fit
        # is refused as the tensile and bending ones are
        numbers = table | shear.summary_table()
        bad = [k for k, v in numbers.items() if isinstance(v, float) and not math.isfinite(v)]
        if bad:
            raise DataFileError(
                shear.loop.source,
                f"the shear fit gave {bad[0]} = {numbers[bad[0]]!r}, not a finite number: no material file is written "
                "(are the numbers in the units the header says?)",
            )
        parse_shear(table, "the shear fit")
        data["shear"] = table
        data["fit"] |= shear.summary_table()
        # the file's one status is the least trusted of its fits
        status, problems = shear.verdict()
        data["fit"]["status"] = worst_status(data["fit"]["status"], status)
        if problems:
            data["fit"]["problems"] = [*(data["fit"].get("problems") or []), *(f"shear: {p}" for p in problems)]
    return data


def write_material_file(path: str | Path, data: dict) -> Path:
    """Write material file ``data`` (see :func:`material_file_data`) as TOML."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, tomli_w.dumps(data))
    return path
