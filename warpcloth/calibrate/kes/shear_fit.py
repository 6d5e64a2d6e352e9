"""A shear law fitted to a KES-FB1 shear loop (docs/model.md §17.1): the bending laws'
fitters, run on the loop in the laws' own variables.

The shear force is Fs = G φ + h(φ) with h any bending law's hysteretic part on the
shear angle. Every law is invariant under a change of unit of its variable and of its
response (h depends on K only through α K, K / K_s, K / K_w, K / K0, and scales with its
amplitude), so a fitter that reads a bending loop in 1/cm and gf·cm/cm fits a shear loop
in degrees and gf/cm exactly as it is, giving G in gf/(cm·°) for D, the force amplitude
in gf/cm for the moment's, angles in degrees for curvatures; only the names change
(:func:`warpcloth.scene.shear_field`). The verdict is the bending fit's rule (noise from
the data's 4th differences, the elastic line as the baseline, the search's edges).

The KES values G, 2HG and 2HG5 are computed from the data and, for the fitted law, along
the standard cycle 0 → +φ0 → −φ0 → 0 (φ0 the loop's largest ``|φ|``).

The laws without growing friction cannot make a loop that widens away from φ = 0: their
width at φ is 2 M0 − D1 (e^{−α(φ0+φ)} + e^{−α(φ0−φ)}) (tagawa2003, masing) or saturates
(dahl, frictional_couple), so a measured loop with 2HG5 > 2HG (common for woven fabrics,
whose yarns jam as they shear) is reproduced only by masing_growing (docs/model.md §4.11,
§17.1). The verdict therefore also compares the KES values: a fitted law that misses
the data's G by more than :data:`KES_TOLERANCE`, or its 2HG or 2HG5 by more than that plus
twice the data's noise, is ``poor_fit``, however small its RMS.
"""

from __future__ import annotations

from dataclasses import dataclass

from warpcloth import units
from warpcloth.scene import RIGIDITY_FIELD, ShearMaterial, shear_field, shear_parameters, shear_unit
from warpcloth.strip import shear_force_along_path

from ..noise import difference_noise
from ..uncertainty import value_text
from .bending_fit import STATUS_ORDER, BendingFit, bending_problems
from .kes_values import KES_SHEAR_STEP_DEG, ShearSummary, shear_summary, standard_cycle
from .laws import DEFAULT_LAW, law_fitter
from .readers import ShearLoop, shear_loop

KES_TOLERANCE = 0.05
"""A fitted shear law must reproduce the data's G, 2HG and 2HG5 within this fraction (the
widths also within twice the data's noise, from its 4th differences)."""


@dataclass(frozen=True)
class ShearFit:
    """A shear law fitted to one KES-FB1 shear loop."""

    loop: ShearLoop
    law_fit: BendingFit  # the fit in the law's own variables (bending field names)
    shear: ShearMaterial  # the fitted law and parameters, [shear] fields in KES units
    sigma: dict[str, float]  # standard uncertainty by [shear] field
    measured: ShearSummary  # the data's G, 2HG, 2HG5
    reproduced: ShearSummary  # the fitted law's, along 0 → +φ0 → −φ0 → 0

    @property
    def rms_gf_per_cm(self) -> float:
        """RMS of the fitted force against the loop's."""
        return self.law_fit.rms_gf_cm_per_cm

    def verdict(self) -> tuple[str, list[str]]:
        """Status and problems, as a bending fit's (``converged``, ``not_identifiable``,
        ``at_bound``, ``poor_fit``, ``failed``)."""
        found = bending_problems(self.law_fit, self.loop.as_law_loop(), "shear", "gf/cm", "Fs = G φ")
        noise = difference_noise([self.loop.force])
        for name, data, law in self.kes_comparison():
            if data is None or law is None:
                continue
            allowed = KES_TOLERANCE * abs(data) + (2 * noise if name != "G" else 0.0)
            if abs(law - data) > allowed:
                found.append(
                    (
                        "poor_fit",
                        f"the fitted {self.shear.law} law's {name} {law:.4g} misses the data's "
                        f"{data:.4g} by {100 * (law - data) / data:+.1f} % (allowed {allowed:.3g}): the law does "
                        "not make this loop's shape",
                    )
                )
        found.sort(key=lambda problem: STATUS_ORDER.index(problem[0]))
        return (found[0][0] if found else "converged"), [message for _, message in found]

    def describe(self, digits: int = 6) -> str:
        """The fitted parameters with their units and standard uncertainties."""
        units_of = {shear_field(p): shear_unit(p) for p in shear_parameters(self.shear.law)}
        values = {RIGIDITY_FIELD: self.shear.rigidity_gf_per_cm_deg, **self.shear.parameters}

        return ", ".join(
            value_text(name, values[name], self.sigma.get(name), units_of[name], digits) for name in values
        )

    def kes_comparison(self) -> list[tuple[str, float | None, float | None]]:
        """(value, the data's, the fitted law's) for G, 2HG and 2HG5."""
        m, r = self.measured, self.reproduced
        return [
            ("G", m.g_gf_per_cm_deg, r.g_gf_per_cm_deg),
            ("2HG", m.hg2_gf_per_cm, r.hg2_gf_per_cm),
            ("2HG5", m.hg2_5_gf_per_cm, r.hg2_5_gf_per_cm),
        ]

    def summary_table(self) -> dict:
        """The shear part of a material file's [fit] table (omitting what is undefined)."""
        status, problems = self.verdict()
        table = {
            "shear_status": status,
            "shear_file": self.loop.source,
            "shear_points": len(self.loop.angle),
            "shear_rms_gf_per_cm": self.rms_gf_per_cm,
        }
        if problems:
            table["shear_problems"] = problems
        for name, data, law in self.kes_comparison():
            key = name.lower().replace("2hg", "hg2")
            if data is not None:
                table[f"shear_{key}_data"] = data
            if law is not None:
                table[f"shear_{key}_law"] = law
        return table


def reproduced_shear_values(shear: ShearMaterial, phi0_deg: float, device: str | None = "cpu") -> ShearSummary:
    """G, 2HG and 2HG5 of a shear law along the standard cycle 0 → +φ0 → −φ0 → 0."""
    phi = standard_cycle(phi0_deg, KES_SHEAR_STEP_DEG)
    force, _ = shear_force_along_path([shear.si()], phi * units.ANGLE_DEGREE, device=device)
    return shear_summary(shear_loop(phi, force / units.SHEAR_FORCE_GF_PER_CM, "the fitted shear law"))


def fit_shear(loop: ShearLoop, law: str = DEFAULT_LAW, device: str | None = "cpu") -> ShearFit:
    """Fit G and the shear law ``law`` to the loop (see the module docstring)."""
    fit = law_fitter(law).fit(loop.as_law_loop(), device)
    names = {p.scene_field: shear_field(p) for p in shear_parameters(law)}
    values = {names[k]: float(v) for k, v in fit.parameters.items()}
    shear = ShearMaterial(law, values.pop(RIGIDITY_FIELD), values)
    sigma = {names[k]: v for k, v in fit.sigma.items()}
    return ShearFit(loop, fit, shear, sigma, shear_summary(loop), reproduced_shear_values(shear, loop.phi0, device))
