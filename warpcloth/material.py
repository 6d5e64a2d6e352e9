"""Fabric materials: the illustrative default, validation, and conversion to SI."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import units
from .errors import SceneError

if TYPE_CHECKING:
    from .scene import MaterialSection

DEFAULT_MATERIAL = {
    "name": "wool90-nylon10 (illustrative, MODEL.md; not the paper's measured curves)",
    "density_g_per_cm2": 2.03e-2,
    "tensile_gf_per_cm": [2000.0, 0.0, 0.0, 2.93e7],
    "bending_rigidity_gf_cm2_per_cm": 0.10,
    "hysteresis_d1_gf_cm_per_cm": 0.04,
    "hysteresis_alpha_cm": 5.0,
    "hysteresis_k0_per_cm": 2.5,
}
"""MODEL.md's illustrative wool 90 % / nylon 10 % (warp direction). The paper's
measured Fig. 8 curves are not in its text, so these numbers are plausible, not measured."""


@dataclass(frozen=True)
class MaterialSI:
    """A material in SI units, as the kernels use it."""

    density: float  # kg/m²
    tensile: tuple[float, float, float, float]  # N/m
    bending_rigidity: float  # D, N·m
    hysteresis_d1: float  # N
    hysteresis_alpha: float  # m
    hysteresis_k0: float  # 1/m

    @property
    def hysteresis_m0(self) -> float:
        """M0 = ½ D1 (1 + e^{−2αK0}), the asymptote of the hysteretic offset (N)."""
        return 0.5 * self.hysteresis_d1 * (1.0 + math.exp(-2.0 * self.hysteresis_alpha * self.hysteresis_k0))


def to_si(section: MaterialSection) -> MaterialSI:
    """Convert a KES-unit material section to SI (the only KES → SI conversion)."""
    return MaterialSI(
        density=section.density_g_per_cm2 * units.AREAL_DENSITY_G_PER_CM2,
        tensile=tuple(a * units.TENSILE_GF_PER_CM for a in section.tensile_gf_per_cm),
        bending_rigidity=section.bending_rigidity_gf_cm2_per_cm * units.RIGIDITY_GF_CM2_PER_CM,
        hysteresis_d1=section.hysteresis_d1_gf_cm_per_cm * units.MOMENT_GF_CM_PER_CM,
        hysteresis_alpha=section.hysteresis_alpha_cm * units.LENGTH_CM,
        hysteresis_k0=section.hysteresis_k0_per_cm * units.CURVATURE_PER_CM,
    )


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
    a = section.tensile_gf_per_cm
    if len(a) != 4:
        raise SceneError(f"{prefix}.tensile_gf_per_cm", f"needs the 4 coefficients a1..a4, got {len(a)}")
    slope, strain = tensile_slope_minimum(a, max_strain)
    if not slope > 0:
        raise SceneError(f"{prefix}.tensile_gf_per_cm",
                         f"T(ε) with a = {a} is not increasing at ε = {strain:.4g} (dT/dε = {slope:.4g} "
                         f"gf/cm); it must increase on [0, integrator.divergence_strain = {max_strain:g}]")
