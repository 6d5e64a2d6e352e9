"""A woven fabric's material as the sheet uses it: per direction, along the bias and in
shear, SI only."""

from __future__ import annotations

import math
from dataclasses import dataclass

from warpcloth.errors import ArgumentError
from warpcloth.kernels.law import BENDING_RIGIDITY
from warpcloth.kernels.laws import packed_parameters
from warpcloth.strip.material import LawParameters, MaterialSI

TWIST_SCALE = {"moment": None, "curvature": 0.5, "inverse_curvature": 2.0, "number": 1.0}
"""How the twist law's parameter of each kind follows from the bias's (docs/model.md §17.4):
bending on the bias by K twists each cell by κ12 = K/2, so a curvature halves and its
inverse doubles; a moment (a saturated hysteresis) is 2 M_bias − M_warp − M_weft."""


@dataclass(frozen=True)
class SheetMaterialSI:
    """Tension and bending along the warp and along the weft (each a strip's
    :class:`~warpcloth.strip.MaterialSI`, its tensile quartic and bending law), the shear
    law on the shear angle: Fs = G φ + h(φ) (G in N/(m·rad), the law's parameters in SI,
    :meth:`warpcloth.scene.ShearMaterial.si`), and the plate's coupling of the two
    directions' bending: ``bias``, bending on the bias as KES-FB2 measures it (a wide
    sample whose chucks hold it in cylindrical bending: D(45°) and the law's hysteresis;
    None: the mean of warp and weft, D12 + 2 D66 = (D11 + D22)/2), and
    ``bending_poisson_ratio`` ν, D12 = ν √(D11 D22). The twist law follows
    (:meth:`twist_law`). The areal density is the warp's; the weft's and the bias's must
    agree."""

    warp: MaterialSI
    weft: MaterialSI
    shear_rigidity: float  # G, N/(m·rad)
    shear: LawParameters
    bias: MaterialSI | None = None
    bending_poisson_ratio: float = 0.0

    def __post_init__(self) -> None:
        if self.weft.density != self.density:
            raise ArgumentError("weft", self._density_message("weft", self.weft))
        if self.bias is not None and self.bias.density != self.density:
            raise ArgumentError("bias", self._density_message("bias", self.bias))
        if not self.shear_rigidity >= 0:
            raise ArgumentError(
                "shear_rigidity", f"the shear rigidity G must be ≥ 0, got {self.shear_rigidity:g} N/(m·rad)"
            )
        if not abs(self.bending_poisson_ratio) < 1:
            raise ArgumentError(
                "bending_poisson_ratio",
                f"must lie in (−1, 1) (D12² < D11 D22: a plate whose bending energy is positive), got "
                f"{self.bending_poisson_ratio!r}",
            )
        self.twist_law()  # refuses a bias the warp and weft cannot make

    def _density_message(self, name: str, other: MaterialSI) -> str:
        return (
            f"a sheet has one areal density: the warp's is {self.density:g} kg/m², the {name}'s {other.density:g} kg/m²"
        )

    @property
    def density(self) -> float:
        """ρ_A, kg/m²."""
        return self.warp.density

    @property
    def poisson_coupling(self) -> float:
        """D12 = ν √(D11 D22), N·m."""
        return self.bending_poisson_ratio * math.sqrt(self.warp.bending_rigidity * self.weft.bending_rigidity)

    def bias_bending(self) -> MaterialSI:
        """Bending on the bias: the given ``bias``, or the mean of warp and weft (D and each
        moment averaged, the warp's other parameters)."""
        if self.bias is not None:
            return self.bias
        law = self.warp.bending.description
        values = {
            p.name: (self.warp.bending[p.name] + self.weft.bending[p.name]) / 2
            if p.kind == "moment" and self.weft.bending_law == self.warp.bending_law
            else self.warp.bending[p.name]
            for p in law.parameters
        }
        rigidity = (self.warp.bending_rigidity + self.weft.bending_rigidity) / 2
        return MaterialSI(self.density, self.warp.tensile, rigidity, LawParameters.of(law.name, values))

    def twist_law(self) -> tuple[float, LawParameters]:
        """The twist law on κ12 and its slope 4 D66 (N·m): with D(θ) = D11 c⁴ + 2(D12 + 2 D66)
        c² s² + D22 s⁴, the bias's D(45°) gives 4 D66 = 4 D_bias − D11 − D22 − 2 D12, and its
        hysteresis 2 h_bias − h_warp − h_weft by :data:`TWIST_SCALE` (docs/model.md §17.4).
        An ArgumentError naming ``bias`` where the plate would need a negative one."""
        bias = self.bias_bending()
        law = bias.bending.description
        for name, other in (("warp", self.warp), ("weft", self.weft)):
            if other.bending_law != bias.bending_law:
                raise ArgumentError(
                    "bias",
                    f"the bias's bending law {bias.bending_law!r} is not the {name}'s {other.bending_law!r}: the "
                    "twist's hysteresis is the bias's less the yarns', so the three need one law",
                )
        d11, d22 = self.warp.bending_rigidity, self.weft.bending_rigidity
        rigidity = 4 * bias.bending_rigidity - d11 - d22 - 2 * self.poisson_coupling
        least = (d11 + d22 + 2 * self.poisson_coupling) / 4
        if rigidity < -1e-12 * max(d11, d22, 1e-300):
            raise ArgumentError(
                "bias",
                f"the bending rigidity on the bias, {bias.bending_rigidity:.4g} N·m, is below (D11 + D22 + 2 D12)/4 "
                f"= {least:.4g} N·m, the least a plate with a twist rigidity D66 ≥ 0 has (D11 {d11:.4g}, D22 "
                f"{d22:.4g}, D12 {self.poisson_coupling:.4g} N·m); a softer bias needs a negative "
                "bending_poisson_ratio",
            )
        values = {}
        for p in law.parameters:
            scale = TWIST_SCALE[p.kind]
            if scale is None:
                terms = (2 * bias.bending[p.name], self.warp.bending[p.name], self.weft.bending[p.name])
                value = terms[0] - terms[1] - terms[2]
                if abs(value) <= 1e-12 * max(abs(t) for t in terms):
                    value = 0.0  # the mean's own hysteresis: none of the twist's, not round-off
            else:
                value = scale * bias.bending[p.name]
            if (p.ge is not None and value < p.ge) or (p.gt is not None and value <= p.gt):
                raise ArgumentError(
                    "bias",
                    f"the twist's {p.name} (2 × the bias's − the warp's − the weft's) is {value:.4g}, outside the "
                    f"{law.name} law's range: the bias's hysteresis must be at least the mean of the warp's and "
                    "the weft's",
                )
            values[p.name] = value
        return max(rigidity, 0.0), LawParameters.of(law.name, values)

    def shear_parameters(self) -> tuple[float, ...]:
        """The packed per-sheet parameters of the shear law (G in D's slot)."""
        return packed_parameters(self.shear.law, {BENDING_RIGIDITY.name: self.shear_rigidity, **self.shear.as_dict()})

    def twist_is_elastic(self) -> bool:
        """Whether the twist law has no hysteresis (every amplitude parameter 0): the bias's
        hysteresis is the yarns' mean, as when no [bias] is given."""
        _rigidity, law = self.twist_law()
        return all(law[p.name] == 0 for p in law.description.parameters if p.amplitude)

    def twist_parameters(self) -> tuple[float, ...]:
        """The packed per-sheet parameters of the twist law (4 D66 in D's slot)."""
        rigidity, law = self.twist_law()
        return packed_parameters(law.law, {BENDING_RIGIDITY.name: rigidity, **law.as_dict()})
