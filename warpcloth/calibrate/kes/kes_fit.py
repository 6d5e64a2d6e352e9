"""One KES-FB1 and one KES-FB2 loop fitted together: the tensile quartic, the bending
law and the KES values of both (docs/model.md §13), and the material they make."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..noise import difference_noise
from .bending_tagawa2003 import BendingFit, fit_bending
from .kes_values import BendingSummary, TensileSummary, bending_summary, tensile_summary
from .readers import BendingLoop, TensileLoop
from .tensile_fit import DIVERGENCE_STRAIN, TensileFit, fit_tensile

POOR_FIT_FACTOR = 3.0  # an RMS above this many times the data's noise is not described by the model


@dataclass(frozen=True)
class KesFit:
    """Everything fitted to one KES-FB1 and one KES-FB2 loop."""

    tensile_loop: TensileLoop
    bending_loop: BendingLoop
    tensile: TensileFit
    bending: BendingFit
    tensile_kes: TensileSummary
    bending_kes: BendingSummary

    def material(self, name: str, density_g_per_cm2: float) -> dict:
        """The scene [material] fields (KES units); density and name come from elsewhere."""
        return {
            "name": name,
            "density_g_per_cm2": float(density_g_per_cm2),
            "tensile_gf_per_cm": [float(a) for a in self.tensile.coefficients],
            "bending_rigidity_gf_cm2_per_cm": float(self.bending.rigidity_gf_cm2_per_cm),
            "bending_law": "tagawa2003",
            "hysteresis_d1_gf_cm_per_cm": float(self.bending.d1_gf_cm_per_cm),
            "hysteresis_alpha_cm": float(self.bending.alpha_cm),
            "hysteresis_k0_per_cm": float(self.bending.k0_per_cm),
        }

    def verdict(self) -> tuple[str, list[str]]:
        """Status and problems, as a motion fit's (``converged``, ``at_bound``,
        ``poor_fit``, ``failed``): each curve's RMS is judged against the noise estimated
        from its own samples (4th differences), α against the edges of its search."""
        t, b = self.tensile, self.bending
        found = []
        numbers = [*t.coefficients, t.rms_gf_per_cm, b.rigidity_gf_cm2_per_cm, b.d1_gf_cm_per_cm, b.alpha_cm,
                   b.rms_gf_cm_per_cm]
        if not all(math.isfinite(float(v)) for v in numbers):
            found.append(("failed", "a fitted value is not finite"))
        if "edge of its search range" in b.note:
            found.append(("at_bound", b.note))
        for what, rms, unit, samples in (("tensile", t.rms_gf_per_cm, "gf/cm", self.tensile_loop.force),
                                         ("bending", b.rms_gf_cm_per_cm, "gf·cm/cm", self.bending_loop.moment)):
            noise = difference_noise([samples])
            if math.isfinite(noise) and noise > 0 and rms > POOR_FIT_FACTOR * noise:
                found.append(("poor_fit", f"the {what} RMS {rms:.4g} {unit} is {rms / noise:.1f}× the noise of the "
                                          f"data ({noise:.3g} {unit}, from its 4th differences): the model does not "
                                          "describe this loop"))
        return (found[0][0] if found else "converged"), [message for _, message in found]

    def summary_table(self) -> dict:
        """The [fit] table of a material file: verdict, residuals and KES values (omitted where undefined)."""
        t, b, tk, bk = self.tensile, self.bending, self.tensile_kes, self.bending_kes
        status, problems = self.verdict()
        table = {
            "status": status,
            "problems": problems or None,
            "tensile_file": self.tensile_loop.source,
            "tensile_first_column": self.tensile_loop.strain_unit,
            "tensile_loading_points": len(self.tensile_loop.strain[self.tensile_loop.loading]),
            "tensile_rms_gf_per_cm": t.rms_gf_per_cm,
            "tensile_rms_relative": t.rms_relative,
            "tensile_constrained": t.constrained,
            "bending_file": self.bending_loop.source,
            "bending_points": len(self.bending_loop.curvature),
            "bending_rms_gf_cm_per_cm": b.rms_gf_cm_per_cm,
            "bending_rms_relative": b.rms_relative,
            "emt_percent": tk.emt_percent,
            "fm_gf_per_cm": tk.fm_gf_per_cm,
            "wt_gf_cm_per_cm2": tk.wt_gf_cm_per_cm2,
            "lt": tk.lt,
            "rt_percent": tk.rt_percent,
            "b_gf_cm2_per_cm": bk.b_gf_cm2_per_cm,
            "2hb_gf_cm_per_cm": bk.hb2_gf_cm_per_cm,
        }
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in table.items() if v is not None}


def fit_kes(tensile: TensileLoop, bending: BendingLoop, max_strain: float = DIVERGENCE_STRAIN,
            device: str | None = "cpu") -> KesFit:
    """Fit the tensile quartic and the bending law, and compute the KES values of both loops."""
    return KesFit(tensile, bending, fit_tensile(tensile, max_strain), fit_bending(bending, device),
                  tensile_summary(tensile), bending_summary(bending))
