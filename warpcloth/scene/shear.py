"""A fabric's in-plane shear, as a material file's ``[shear]`` table gives it (KES-FB1
shear units), and its one conversion to SI (docs/model.md §17.1).

The shear force per width along the shear angle φ is Fs = G φ + h(φ): the same laws as
bending (kernels/law.py) with the shear angle for the curvature and the force for the
moment, so every bending law is a shear law too. The table names the law and its
parameters; the field names follow from each parameter's kind (a moment becomes a force
in gf/cm, a curvature an angle in degrees, :data:`warpcloth.units.SHEAR_UNITS`):

    [shear]
    law = "tagawa2003"
    rigidity_gf_per_cm_deg = 0.6       # G
    hysteresis_d1_gf_per_cm = 0.8
    hysteresis_alpha_per_deg = 0.6
    hysteresis_phi0_deg = 8.0

A strip does not read it; a material file that gives it describes the fabric's shear as
well (``warpcloth material fit-kes --shear``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from warpcloth import units
from warpcloth.errors import SceneError
from warpcloth.kernels import BENDING_LAWS, bending_law
from warpcloth.kernels.law import BENDING_RIGIDITY, LawParameter
from warpcloth.strip import LawParameters

SHEAR_TABLE = "shear"


def shear_field(parameter: LawParameter) -> str:
    """The ``[shear]`` field of a law parameter: its name in shear's words and units
    (``bending_rigidity`` → ``rigidity_gf_per_cm_deg``, G; ``hysteresis_k0`` →
    ``hysteresis_phi0_deg``; ``dahl_moment`` → ``dahl_force_gf_per_cm``)."""
    stem = parameter.name.replace("bending_", "").replace("moment", "force").replace("curvature", "angle")
    stem = stem.replace("k0", "phi0")
    suffix = units.SHEAR_UNITS[parameter.kind][0]
    return f"{stem}_{suffix}" if suffix else stem


RIGIDITY_FIELD = shear_field(BENDING_RIGIDITY)
"""G, the slope of the shear loop's centre line, gf/(cm·degree)."""


def shear_parameters(law: str) -> tuple[LawParameter, ...]:
    """What a shear law of ``law`` reads: the slope (G for D), then the law's own."""
    return (BENDING_RIGIDITY, *bending_law(law).parameters)


def shear_fields(law: str) -> list[str]:
    """The ``[shear]`` fields a material of shear law ``law`` gives, G first."""
    return [shear_field(p) for p in shear_parameters(law)]


def shear_unit(parameter: LawParameter) -> str:
    """A law parameter's unit as a shear parameter prints it (``gf/cm``, ``°``)."""
    return units.SHEAR_UNITS[parameter.kind][2]


@dataclass(frozen=True)
class ShearMaterial:
    """A fabric's shear law and parameters in KES-FB1 shear units (fields: :func:`shear_fields`)."""

    law: str
    rigidity_gf_per_cm_deg: float
    parameters: dict[str, float]  # the law's own, by [shear] field

    def si(self) -> tuple[float, LawParameters]:
        """G in N/(m·rad) and the law's parameters in SI (force N/m, angle rad): the one
        KES → SI conversion of shear."""
        given = {RIGIDITY_FIELD: self.rigidity_gf_per_cm_deg, **self.parameters}
        si = {
            p.name: units.from_kes(given[shear_field(p)], units.SHEAR_UNITS[p.kind][1])
            for p in shear_parameters(self.law)
        }
        return si.pop(BENDING_RIGIDITY.name), LawParameters.of(self.law, si)

    def table(self) -> dict:
        """The ``[shear]`` table of a material file."""
        return {"law": self.law, RIGIDITY_FIELD: self.rigidity_gf_per_cm_deg, **self.parameters}


def parse_shear(table: object, where: str = "") -> ShearMaterial:
    """The ``[shear]`` table of a material file (``where`` names the file, if the error is
    not located otherwise), checked: a known law, every field it reads a finite number in
    its range, no other field; else a SceneError of ``shear.<field>``."""
    where = f"{where}: " if where else ""
    if not isinstance(table, dict):
        raise SceneError(SHEAR_TABLE, f"{where}[shear] must be a table, got {table!r}")
    law = table.get("law")
    if law not in BENDING_LAWS:
        raise SceneError(f"{SHEAR_TABLE}.law", f"{where}must be one of {', '.join(BENDING_LAWS)}; got {law!r}")
    description = bending_law(law)
    expected = shear_fields(law)
    unknown = sorted(set(table) - {"law", *expected})
    if unknown:
        raise SceneError(
            f"{SHEAR_TABLE}.{unknown[0]}",
            f"{where}not a field of the {law} shear law (its fields: {', '.join(expected)})",
        )
    missing = [name for name in expected if name not in table]
    if missing:
        raise SceneError(f"{SHEAR_TABLE}.{missing[0]}", f"{where}the {law} shear law needs {', '.join(missing)}")
    bounds = {RIGIDITY_FIELD: (None, 0.0), **{shear_field(p): (p.gt, p.ge) for p in description.parameters}}
    values = {}
    for name in expected:
        value = table[name]
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise SceneError(f"{SHEAR_TABLE}.{name}", f"{where}must be a finite number, got {value!r}")
        gt, ge = bounds[name]
        if (gt is not None and not value > gt) or (ge is not None and not value >= ge):
            relation = f"> {gt:g}" if gt is not None else f"≥ {ge:g}"
            raise SceneError(f"{SHEAR_TABLE}.{name}", f"{where}must be {relation}, got {value:g}")
        values[name] = float(value)
    return ShearMaterial(law, values.pop(RIGIDITY_FIELD), values)
