"""A fabric's material as the simulation uses it: SI units only."""

from __future__ import annotations

from dataclasses import dataclass

from warpcloth.kernels import DEFAULT_BENDING_LAW, bending_law, bending_tagawa2003, packed_parameters


@dataclass(frozen=True)
class MaterialSI:
    """A material in SI units, as the kernels use it (KES → SI: :func:`warpcloth.scene.to_si`).

    ``bending_law`` names the law (kernels/laws.py); each law reads its own fields (its
    ``MATERIAL_FIELDS``) and ignores the others'.
    """

    density: float  # ρ_A, kg/m²
    tensile: tuple[float, float, float, float]  # a1..a4 of T(ε), N/m
    bending_rigidity: float  # D, N·m
    hysteresis_d1: float = 0.0  # tagawa2003 and masing: D1, N
    hysteresis_alpha: float = 0.05  # tagawa2003 and masing: α, m
    hysteresis_k0: float = 250.0  # tagawa2003 and masing: K0, 1/m
    bending_law: str = DEFAULT_BENDING_LAW
    dahl_moment: float = 0.0  # dahl: M_s, N
    dahl_curvature: float = 20.0  # dahl: K_s, 1/m
    dahl_exponent: float = 1.0  # dahl: n
    friction_moment: float = 0.0  # frictional_couple: M_f, N
    friction_width: float = 20.0  # frictional_couple: K_w, 1/m

    @property
    def hysteresis_m0(self) -> float:
        """M0 = ½ D1 (1 + e^{−2αK0}), the asymptote of the tagawa2003 hysteretic offset (N)."""
        return bending_tagawa2003.loop_asymptote(self.hysteresis_d1, self.hysteresis_alpha, self.hysteresis_k0)

    def bending_parameters(self) -> tuple[float, ...]:
        """The packed per-strip parameters of the material's bending law (kernels/laws.py)."""
        law = bending_law(self.bending_law)
        return packed_parameters(self.bending_law, *(getattr(self, name) for name in law.MATERIAL_FIELDS))
