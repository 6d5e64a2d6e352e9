"""A fabric's material as the simulation uses it: SI units only."""

from __future__ import annotations

from dataclasses import dataclass

from warpcloth.kernels import bending_tagawa2003


@dataclass(frozen=True)
class MaterialSI:
    """A material in SI units, as the kernels use it (KES → SI: :func:`warpcloth.scene.to_si`)."""

    density: float  # ρ_A, kg/m²
    tensile: tuple[float, float, float, float]  # a1..a4 of T(ε), N/m
    bending_rigidity: float  # D, N·m
    hysteresis_d1: float  # N
    hysteresis_alpha: float  # m
    hysteresis_k0: float  # 1/m

    @property
    def hysteresis_m0(self) -> float:
        """M0 = ½ D1 (1 + e^{−2αK0}), the asymptote of the hysteretic offset (N)."""
        return bending_tagawa2003.loop_asymptote(self.hysteresis_d1, self.hysteresis_alpha, self.hysteresis_k0)

    def bending_parameters(self) -> tuple[float, ...]:
        """The packed per-strip parameters of the tagawa2003 bending law."""
        return bending_tagawa2003.packed_parameters(self.bending_rigidity, self.hysteresis_d1,
                                                    self.hysteresis_alpha, self.hysteresis_k0)
