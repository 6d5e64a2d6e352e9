"""One KES-FB1 and one KES-FB2 loop fitted together: the tensile quartic, the bending
law and the KES values of both (docs/model.md §13), and the material they make."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .bending_fit import STATUS_ORDER, BendingFit, bending_problems, poor_fit
from .kes_values import BendingSummary, TensileSummary, bending_summary, tensile_summary
from .laws import DEFAULT_LAW, law_fitter
from .readers import BendingLoop, TensileLoop
from .tensile_fit import DIVERGENCE_STRAIN, TensileFit, fit_tensile


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
            "bending_law": self.bending.law,
            **{k: float(v) for k, v in self.bending.parameters.items()},
        }

    def verdict(self) -> tuple[str, list[str]]:
        """Status and problems, as a motion fit's (``converged``, ``at_bound``,
        ``poor_fit``, ``failed``): each curve's RMS is judged against the noise estimated
        from its own samples (4th differences), the bending law's shape parameters against
        the edges of their search."""
        t = self.tensile
        found = []
        if not all(math.isfinite(float(v)) for v in [*t.coefficients, t.rms_gf_per_cm]):
            found.append(("failed", "a fitted tensile value is not finite"))
        why = poor_fit("tensile", t.rms_gf_per_cm, "gf/cm", self.tensile_loop.force)
        if why is not None:
            found.append(("poor_fit", why))
        found += bending_problems(self.bending, self.bending_loop)
        found.sort(key=lambda problem: STATUS_ORDER.index(problem[0]))
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
            "bending_law": self.bending.law,
            "bending_free_parameters": self.bending.free_parameters,
            "bending_rms_gf_cm_per_cm": b.rms_gf_cm_per_cm,
            "bending_rms_relative": b.rms_relative,
            "bending_aic": b.aic(),
            "bending_bic": b.bic(),
            "emt_percent": tk.emt_percent,
            "fm_gf_per_cm": tk.fm_gf_per_cm,
            "wt_gf_cm_per_cm2": tk.wt_gf_cm_per_cm2,
            "lt": tk.lt,
            "rt_percent": tk.rt_percent,
            "b_gf_cm2_per_cm": bk.b_gf_cm2_per_cm,
            "2hb_gf_cm_per_cm": bk.hb2_gf_cm_per_cm,
        }
        return {k: (float(v) if isinstance(v, np.floating) else v) for k, v in table.items() if v is not None}


def fit_kes(
    tensile: TensileLoop,
    bending: BendingLoop,
    max_strain: float = DIVERGENCE_STRAIN,
    device: str | None = "cpu",
    law: str = DEFAULT_LAW,
    bending_fit: BendingFit | None = None,
) -> KesFit:
    """Fit the tensile quartic and the bending law ``law`` (a name in ``LAW_FITTERS``:
    tagawa2003, dahl, frictional_couple), and compute the KES values of both loops.

    ``bending_fit``: the bending law already fitted to ``bending`` (e.g. by
    :func:`~warpcloth.calibrate.kes.compare_laws`), used instead of fitting ``law``.
    """
    if bending_fit is None:
        bending_fit = law_fitter(law).fit(bending, device)
    return KesFit(
        tensile,
        bending,
        fit_tensile(tensile, max_strain),
        bending_fit,
        tensile_summary(tensile),
        bending_summary(bending),
    )
