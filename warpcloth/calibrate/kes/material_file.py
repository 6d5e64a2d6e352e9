"""Material files from a KES fit: a ``[material]`` table (the scene's material fields in
KES units, docs/model.md §1, and a ``source``) and an informational ``[fit]`` table
(files, residuals, KES values; docs/model.md §13)."""

from __future__ import annotations

import math
from pathlib import Path

import tomli_w

from warpcloth.errors import OptionError
from warpcloth.io.atomic import write_text_atomically
from warpcloth.scene import MaterialSection, material_fields, validate_material

from .kes_fit import KesFit
from .tensile_fit import DIVERGENCE_STRAIN


def material_file_data(fit: KesFit, name: str, density_g_per_cm2: float, source: str,
                       max_strain: float = DIVERGENCE_STRAIN) -> dict:
    """The TOML data of a material file for a fit, checked usable up to ``max_strain``."""
    if not (math.isfinite(density_g_per_cm2) and density_g_per_cm2 > 0):
        raise OptionError("--density-g-per-cm2", f"must be a positive mass per area in g/cm², got "
                          f"{density_g_per_cm2!r}")
    material = fit.material(name, density_g_per_cm2)
    validate_material(MaterialSection(**material), max_strain, "material")
    law = material["bending_law"]
    ordered = {"name": name, "source": source, "bending_law": law,
               **{k: material[k] for k in material_fields(law) if k != "name"}}
    return {"material": ordered, "fit": fit.summary_table()}


def write_material_file(path: str | Path, data: dict) -> Path:
    """Write material file ``data`` (see :func:`material_file_data`) as TOML."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text_atomically(path, tomli_w.dumps(data))
    return path
