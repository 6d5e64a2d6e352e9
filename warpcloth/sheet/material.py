"""A woven fabric's material as the sheet uses it: per direction and in shear, SI only."""

from __future__ import annotations

from dataclasses import dataclass

from warpcloth.errors import ArgumentError
from warpcloth.kernels.law import BENDING_RIGIDITY
from warpcloth.kernels.laws import packed_parameters
from warpcloth.strip.material import LawParameters, MaterialSI


@dataclass(frozen=True)
class SheetMaterialSI:
    """Tension and bending along the warp and along the weft (each a strip's
    :class:`~warpcloth.strip.MaterialSI`, its tensile quartic and bending law), and the shear
    law on the shear angle: Fs = G φ + h(φ) (G in N/(m·rad), the law's parameters in SI,
    :meth:`warpcloth.scene.ShearMaterial.si`). The areal density is the warp's; the weft's
    must agree."""

    warp: MaterialSI
    weft: MaterialSI
    shear_rigidity: float  # G, N/(m·rad)
    shear: LawParameters

    def __post_init__(self) -> None:
        if self.warp.density != self.weft.density:
            raise ArgumentError(
                "weft",
                f"a sheet has one areal density: the warp's is {self.warp.density:g} kg/m², the weft's "
                f"{self.weft.density:g} kg/m²",
            )
        if not self.shear_rigidity >= 0:
            raise ArgumentError(
                "shear_rigidity", f"the shear rigidity G must be ≥ 0, got {self.shear_rigidity:g} N/(m·rad)"
            )

    @property
    def density(self) -> float:
        """ρ_A, kg/m²."""
        return self.warp.density

    def shear_parameters(self) -> tuple[float, ...]:
        """The packed per-sheet parameters of the shear law (G in D's slot)."""
        return packed_parameters(self.shear.law, {BENDING_RIGIDITY.name: self.shear_rigidity, **self.shear.as_dict()})
