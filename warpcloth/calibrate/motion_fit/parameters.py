"""The free parameters of a motion fit: their short names, the scene fields they are, and
the box they are fitted in (default ranges, or ``bounds`` given as ``name=LOW:HIGH``)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from warpcloth.errors import ArgumentError, SceneError
from warpcloth.scene import (
    Scene,
    batch_fields,
    check_step,
    field_laws,
    hysteresis_amplitudes,
    law_aliases,
    law_fields,
    scene_from_dict,
    set_field,
)
from warpcloth.scene.step import AUTO

ALIASES = {
    "gamma": "damping.gamma_per_s",
    **law_aliases(),
    "density": "material.density_g_per_cm2",
    "rotation_centre_dx_mm": "clamp.rotation_centre_dx_mm",
    "rotation_centre_dy_mm": "clamp.rotation_centre_dy_mm",
    "hold_x_mm": "release.hold_x_mm",
    "hold_y_mm": "release.hold_y_mm",
    "K_rest": "strip.rest_curvature_per_cm",
    "grip_factor": "clamp.grip_bending_factor",
    "grip_hysteresis": "clamp.grip_hysteresis_factor",
    "grip_length": "clamp.grip_length_mm",
}
"""Short names accepted by ``--free`` (any per-strip numeric field also works by its dotted name);
a bending law's parameters (their aliases from the laws' descriptions, kernels/law.py) only
for a scene whose material uses that law."""

REST_CURVATURE_SPAN = 0.2
"""Default range of ``K_rest``: ± this (1/cm) around the scene's value, a set down to a
radius of 5 cm either way (docs/calibration.md)."""

HYSTERESIS_AMPLITUDES = hysteresis_amplitudes()
"""Fitted from 0 (no hysteresis) to 4× the scene's value by default."""


@dataclass(frozen=True)
class FreeParameter:
    """A scene field fitted within [lower, upper]."""

    name: str
    field: str
    lower: float
    upper: float
    initial: float


def initial_point(free: list[FreeParameter]) -> np.ndarray:
    """The scene's own values of ``free`` as a point of the unit box."""
    return np.array([(p.initial - p.lower) / (p.upper - p.lower) for p in free])


def _field_value(scene: Scene, name: str) -> float:
    section, key = name.split(".")
    return getattr(getattr(scene, section), key)


def free_parameters(names: str | list[str], base: Scene, bounds: str | None = None) -> list[FreeParameter]:
    """Resolve ``--free`` names (aliases or dotted fields) and ``--bounds name=lo:hi,...``.

    Default bounds: a rotation centre or held position ± 10 mm around the scene's value;
    γ from 0 to 4× the scene's value (at least 2 /s); a hysteresis amplitude (D1, M_s,
    M_f) from 0 to 4×; K_rest ± :data:`REST_CURVATURE_SPAN` around the scene's value; the
    grip length from 0 to 4× the scene's value (at least 4 h, at most the free length);
    any other positive field from ¼× to 4×.
    """
    names = [n.strip() for n in (names.split(",") if isinstance(names, str) else names) if n.strip()]
    if not names:
        raise ArgumentError("names", "name at least one parameter to fit, e.g. gamma,D1")
    given = parse_bounds(bounds)
    fixed = set(batch_fields())
    out: list[FreeParameter] = []
    for name in names:
        dotted = _fittable_field(name, base, fixed)
        value = _field_value(base, dotted)
        key = name if name in given else dotted if dotted in given else None
        if key is not None:
            lower, upper = given.pop(key)
        else:
            grip = (4 * base.strip.spacing_mm, base.strip.free_length_mm)
            lower, upper = default_range(name, dotted, value, dotted in HYSTERESIS_AMPLITUDES, grip)
        if not lower < upper:
            raise ArgumentError("bounds", f"{name}: lower bound {lower:g} must be below upper bound {upper:g}")
        if any(p.field == dotted for p in out):
            raise ArgumentError("names", f"{name} ({dotted}) is named twice")
        _check_box_is_valid(name, dotted, (lower, upper), base)
        out.append(FreeParameter(name, dotted, float(lower), float(upper), float(min(max(value, lower), upper))))
    if given:
        raise ArgumentError("bounds", f"{next(iter(given))!r} is not among the --free parameters")
    return out


def _fittable_field(name: str, base: Scene, fixed: set[str]) -> str:
    # The dotted scene field ``name`` stands for, if it is a per-strip number of this law.
    dotted = ALIASES.get(name, name)
    if (
        dotted.count(".") != 1
        or not hasattr(base, dotted.split(".")[0])
        or not hasattr(getattr(base, dotted.split(".")[0]), dotted.split(".")[1])
    ):
        raise ArgumentError("names", f"{name!r} is neither a scene field nor one of {', '.join(ALIASES)}")
    value = _field_value(base, dotted)
    if dotted in fixed or isinstance(value, (bool, str, list)):
        raise ArgumentError(
            "names",
            f"{name} ({dotted}) cannot vary between the strips of one batch or is not "
            "a number; only per-strip numeric fields can be fitted",
        )
    laws = field_laws(dotted)
    if laws and base.material.bending_law not in laws:
        raise ArgumentError(
            "names",
            f"{name} ({dotted}) is a parameter of the {' or '.join(laws)} bending law, "
            "but the scene's "
            f"material uses {base.material.bending_law} (whose parameters are "
            f"{', '.join(law_fields(base.material.bending_law))}); set material.bending_law to "
            "fit it",
        )
    return dotted


def default_range(
    name: str, dotted: str, value: float, amplitude: bool = False, grip_limits: tuple[float, float] | None = None
) -> tuple[float, float]:
    """The range a field is fitted in when --bounds does not give one (:func:`free_parameters`'
    doc; a sheet's too): ``amplitude`` says the field sets a law's hysteresis, ``grip_limits``
    the shortest upper bound and the longest of a grip length (mm)."""
    centre = "rotation_centre" in dotted or "hold_" in dotted or dotted.startswith("clamp.centre_")
    if dotted.endswith("_mm") and centre:
        return value - 10.0, value + 10.0
    if dotted == "damping.gamma_per_s":
        return 0.0, max(4 * value, 2.0)
    if dotted == "strip.rest_curvature_per_cm":
        return value - REST_CURVATURE_SPAN, value + REST_CURVATURE_SPAN
    if dotted == "clamp.grip_length_mm" and grip_limits is not None:
        return 0.0, min(max(4 * value, grip_limits[0]), grip_limits[1])
    if amplitude and value > 0:
        return 0.0, 4 * value
    if value > 0:
        return value / 4, value * 4
    raise ArgumentError(
        "bounds", f"{name} is {value:g} in the scene, so no default range; give --bounds {name}=LOW:HIGH"
    )


def _check_box_is_valid(name: str, dotted: str, bounds: tuple[float, float], base: Scene) -> None:
    # Every point of the box must be a valid scene: both ends are checked.
    for bound in bounds:
        data = base.to_dict()
        set_field(data, dotted, float(bound))
        if base.integrator.dt_chosen_by == AUTO:  # the fit chooses its step over the box
            set_field(data, "integrator.dt_s", AUTO)
        try:
            check_step(scene_from_dict(data))
        except SceneError as exc:
            raise ArgumentError("bounds", f"{name} = {bound:g} is not a valid scene: {exc}") from None


def parse_bounds(text: str | None) -> dict[str, tuple[float, float]]:
    """``--bounds name=LOW:HIGH,...`` as ``{name: (low, high)}``; an ArgumentError for an item that is not."""
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        try:
            name, span = item.split("=")
            lo, hi = span.split(":")
            out[name.strip()] = (float(lo), float(hi))
        except ValueError:
            raise ArgumentError("bounds", f"{item.strip()!r} is not name=LOW:HIGH (e.g. gamma=0:2)") from None
    return out
