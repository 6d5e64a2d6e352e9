"""KES ↔ SI conversion: the one place where Kawabata units meet SI.

Everything inside warpcloth is SI (m, kg, s, N). Materials are entered in the units
of the Kawabata Evaluation System (KES-FB) instruments and converted here, once.
"""

from __future__ import annotations

GF_TO_N = 9.80665e-3
"""One gram-force in newtons."""

TENSILE_GF_PER_CM = GF_TO_N / 1e-2
"""Tensile force per width: gf/cm → N/m (× 0.980665)."""

MOMENT_GF_CM_PER_CM = GF_TO_N
"""Bending moment per width (M, 2HB, D1): gf·cm/cm → N·m/m = N (× 9.80665e-3)."""

RIGIDITY_GF_CM2_PER_CM = GF_TO_N * 1e-2
"""Bending rigidity per width (B, D): gf·cm²/cm → N·m²/m = N·m (× 9.80665e-5)."""

CURVATURE_PER_CM = 100.0
"""Curvature: 1/cm → 1/m."""

LENGTH_CM = 1e-2
"""Length (hysteresis steepness α): cm → m."""

AREAL_DENSITY_G_PER_CM2 = 10.0
"""Mass per area: g/cm² → kg/m²."""

LENGTH_MM = 1e-3
"""Scene lengths: mm → m."""

STRAIN_PERCENT = 1e-2
"""Strain written in % (KES-FB1 EMT, tensile CSVs) → fraction."""

SHEAR_FORCE_GF_PER_CM = GF_TO_N / 1e-2
"""In-plane shear force per width (KES-FB1 shear Fs, 2HG, 2HG5): gf/cm → N/m (× 0.980665)."""

ANGLE_DEGREE = 0.017453292519943295
"""Shear angle φ: degree → rad (π/180)."""

PER_DEGREE = 1.0 / ANGLE_DEGREE
"""An inverse shear angle: 1/degree → 1/rad."""

SHEAR_RIGIDITY_GF_PER_CM_DEG = SHEAR_FORCE_GF_PER_CM / ANGLE_DEGREE
"""Shear rigidity per width (KES G): gf/(cm·degree) → N/(m·rad)."""

BENDING_UNITS = {
    "rigidity": ("RIGIDITY_GF_CM2_PER_CM", "gf·cm²/cm"),
    "moment": ("MOMENT_GF_CM_PER_CM", "gf·cm/cm"),
    "curvature": ("CURVATURE_PER_CM", "cm⁻¹"),
    "inverse_curvature": ("LENGTH_CM", "cm"),
    "number": ("", ""),
}
"""A law parameter's bending unit by its kind (:data:`warpcloth.kernels.law.KINDS`, and D's
``rigidity``): the constant above that converts its scene field to SI, its unit as printed."""


def from_kes(value: float, constant: str) -> float:
    """``value`` in KES units converted to SI by the constant of this module named
    ``constant`` (empty: a pure number): what :data:`BENDING_UNITS` and
    :data:`SHEAR_UNITS` name, applied in this one place."""
    return value * globals()[constant] if constant else value


SHEAR_UNITS = {
    "rigidity": ("gf_per_cm_deg", "SHEAR_RIGIDITY_GF_PER_CM_DEG", "gf/(cm·°)"),
    "moment": ("gf_per_cm", "SHEAR_FORCE_GF_PER_CM", "gf/cm"),
    "curvature": ("deg", "ANGLE_DEGREE", "°"),
    "inverse_curvature": ("per_deg", "PER_DEGREE", "1/°"),
    "number": ("", "", ""),
}
"""A law parameter's shear unit by its kind (:data:`warpcloth.kernels.law.KINDS`): the
field-name suffix, the constant above that converts it to SI, the unit as printed. The
law acts on the shear angle as on the curvature, its force as on the moment."""


MEASURED_UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
    "length": {"m": 1.0, "cm": 1e-2, "mm": LENGTH_MM, "um": 1e-6, "µm": 1e-6},
    "angle": {"rad": 1.0, "mrad": 1e-3, "deg": 0.017453292519943295},
}
"""Units a measured-data header may name per quantity (``t_ms``, ``x_m``, ``theta [deg]``),
and each one's factor to SI (s, m, rad)."""

PLAUSIBLE = {
    "areal density": (1e-3, 0.2, "g/cm²", "10–2000 g/m², gauze to heavy canvas"),
    "largest tensile strain": (
        1e-3,
        1.0,
        "(fraction)",
        "0.1–100 %: a KES-FB1 loop to 500 gf/cm stretches a fabric by a few to some tens of percent",
    ),
    "largest shear force": (
        1e-3,
        200.0,
        "gf/cm",
        "a KES-FB1 shear loop to ±8° reads a fraction of a gf/cm (gauze) to some tens (heavy canvas)",
    ),
    "record length": (0.01, 3600.0, "s", "a swing is measured for seconds to minutes"),
    "sampling interval": (
        1e-7,
        0.1,
        "s",
        "a swing of a fraction of a second's period is sampled every few milliseconds or more often",
    ),
    "largest displacement": (0.1, 2000.0, "mm", "a hanging strip swings by millimetres to some hundreds of them"),
    "largest clamp angle": (1e-3, 20.0, "rad", "a clamp turns by a fraction of a turn to a few turns"),
}
"""Plausible ranges of physical inputs: quantity → (low, high, unit, why). A finite value
outside is used as given, with a :class:`~warpcloth.errors.PlausibilityWarning` naming the
value and the range (docs/promises.md, "Implausible inputs are named")."""


def check_plausible(quantity: str, value: float, where: str, hint: str = "") -> None:
    """Warn (:class:`~warpcloth.errors.PlausibilityWarning`) when ``value`` of ``quantity``
    (in :data:`PLAUSIBLE`'s unit), given by ``where``, lies outside its plausible range;
    ``hint`` says what it more likely is."""
    import warnings

    from .errors import PlausibilityWarning

    low, high, unit, why = PLAUSIBLE[quantity]
    if not low <= abs(value) <= high:
        warnings.warn(
            f"{where}: {quantity} {value:.4g} {unit} is outside the plausible {low:g} to {high:g} {unit} "
            f"({why}); used as given{' (' + hint + ')' if hint else ''}",
            PlausibilityWarning,
            stacklevel=3,
        )
