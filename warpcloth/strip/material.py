"""A fabric's material as the simulation uses it: SI units only."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from warpcloth.errors import ArgumentError
from warpcloth.kernels import DEFAULT_BENDING_LAW, bending_law, packed_parameters
from warpcloth.kernels.law import BENDING_RIGIDITY, BendingLaw


@dataclass(frozen=True)
class LawParameters:
    """A bending law and its own parameters in SI, by the names its description gives
    (:class:`warpcloth.kernels.law.LawParameter`; D, which every law reads, is the
    material's ``bending_rigidity``)."""

    law: str
    values: tuple[tuple[str, float], ...] = ()

    @classmethod
    def of(cls, law: str, values: Mapping[str, float] | None = None) -> LawParameters:
        """The parameters of ``law`` from ``values`` (SI, by name); an ArgumentError naming
        ``values`` for a name the law does not have or a parameter it lacks."""
        description = bending_law(law)
        values = dict(values or {})
        unknown = sorted(set(values) - {p.name for p in description.parameters})
        if unknown:
            raise ArgumentError(
                "values",
                f"the {law} law has no parameter {unknown[0]!r}; it has "
                f"{', '.join(p.name for p in description.parameters) or 'none'}",
            )
        missing = [p.name for p in description.parameters if p.name not in values]
        if missing:
            raise ArgumentError("values", f"the {law} law needs {', '.join(missing)}")
        return cls(law, tuple((p.name, float(values[p.name])) for p in description.parameters))

    @property
    def description(self) -> BendingLaw:
        """The law's description (kernels/law.py)."""
        return bending_law(self.law)

    def __getitem__(self, name: str) -> float:
        """The parameter ``name`` (SI); an ArgumentError naming ``name`` and the law's
        parameters if the law has no such one."""
        for key, value in self.values:
            if key == name:
                return value
        known = ", ".join(key for key, _ in self.values) or "none"
        raise ArgumentError("name", f"the {self.law} law has no parameter {name!r}; it has {known}")

    def __getattr__(self, name: str) -> float:
        # material.bending.dahl_moment reads as the law's own parameter
        if name.startswith("_") or name in ("law", "values"):
            raise AttributeError(name)
        try:
            return self[name]
        except ArgumentError as exc:
            raise AttributeError(exc.message) from None

    def replace(self, **values: float) -> LawParameters:
        """The same law with some of its parameters changed (SI, by name)."""
        return LawParameters.of(self.law, {**self.as_dict(), **values})

    def as_dict(self) -> dict[str, float]:
        """The parameters by SI name."""
        return dict(self.values)


ELASTIC = LawParameters.of(
    DEFAULT_BENDING_LAW, {"hysteresis_d1": 0.0, "hysteresis_alpha": 0.05, "hysteresis_k0": 250.0}
)
"""The default law without hysteresis (D1 = 0): M = D K."""


@dataclass(frozen=True)
class MaterialSI:
    """A material in SI units, as the kernels use it (KES → SI: :func:`warpcloth.scene.to_si`).

    ``bending`` is the bending law with its own parameters; D, the slope every law has,
    is ``bending_rigidity``.
    """

    density: float  # ρ_A, kg/m²
    tensile: tuple[float, float, float, float]  # a1..a4 of T(ε), N/m
    bending_rigidity: float  # D, N·m
    bending: LawParameters = ELASTIC

    @property
    def bending_law(self) -> str:
        """The name of the material's bending law."""
        return self.bending.law

    def bending_parameters(self) -> tuple[float, ...]:
        """The packed per-strip parameters of the material's bending law (kernels/laws.py)."""
        values = {BENDING_RIGIDITY.name: self.bending_rigidity, **self.bending.as_dict()}
        return packed_parameters(self.bending.law, values)
