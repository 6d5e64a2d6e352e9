"""The bending laws' fitters, and every law fitted to one KES-FB2 loop and compared
(docs/model.md §13.5).

:data:`LAW_FITTERS` has one :class:`~.bending_fit.LawFitter` per law of
``kernels/laws.py``. :func:`compare_laws` fits each to the loop and ranks them by Akaike's
information criterion, AIC = n ln(SSE/n) + 2k (and shows the Bayesian BIC = n ln(SSE/n)
+ k ln n), for Gaussian residuals of one unknown variance, k the law's free parameters
(tagawa2003 3: D, D1, α, its K0 being fixed by the data; dahl 4: D, M_s, K_s, n;
frictional_couple 3: D, M_f, K_w; masing 3: D, D1, α), n the loop's points. It also gives the KES values B and
2HB each fitted law reproduces along the standard cycle 0 → +K0 → −K0 → 0, beside the
data's own.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass

import numpy as np

from warpcloth import units
from warpcloth.errors import ArgumentError
from warpcloth.kernels import BENDING_LAWS, DEFAULT_BENDING_LAW
from warpcloth.kernels.law import BENDING_RIGIDITY, BendingLaw, LawRegistryError
from warpcloth.scene import to_si
from warpcloth.strip import moment_along_path

from ..noise import difference_noise, poor_fit_ratio
from .bending_fit import AIC_TIE, BendingFit, LawFitter, bending_problems
from .kes_values import BendingSummary, bending_summary, standard_cycle
from .readers import BendingLoop, bending_loop


def _fitter_of(law: BendingLaw) -> LawFitter:
    # The fitter the law's description names (module:attribute): calibrate sits above the
    # kernels, so the description can only name it.
    module, _, attribute = law.fitter.partition(":")
    try:
        fitter = getattr(importlib.import_module(module), attribute)
    except (ImportError, AttributeError) as exc:  # noqa: B014 - a broken fitter module, or no such name
        raise LawRegistryError(
            f"the {law.name} bending law names its KES fitter {law.fitter!r}, which cannot be loaded: {exc}"
        ) from exc
    if not isinstance(fitter, LawFitter) or fitter.law != law.name:
        raise LawRegistryError(f"the {law.name} bending law's KES fitter {law.fitter!r} is not a LawFitter of that law")
    fields = {p.field for p in fitter.parameters}
    expected = {BENDING_RIGIDITY.scene_field, *(p.scene_field for p in law.parameters)}
    if fields != expected:
        raise LawRegistryError(
            f"the {law.name} bending law's KES fitter {law.fitter!r} fits "
            f"{', '.join(sorted(fields))}; the law's [material] fields are "
            f"{', '.join(sorted(expected))}"
        )
    return fitter


LAW_FITTERS: dict[str, LawFitter] = {name: _fitter_of(law) for name, law in BENDING_LAWS.items()}
"""The fitter of each bending law, in the kernels' order (from the laws' descriptions)."""

DEFAULT_LAW = DEFAULT_BENDING_LAW
"""What ``fit-kes`` fits without ``--law``: the paper's law."""

ALL_LAWS = "all"
"""``--law all``: fit every law and compare them."""


SAME_EXPONENT = 0.05
"""A dahl fit with ``|n − 1|`` below this is the paper's law."""

LIKELIHOOD_RATIO_95 = 3.841
"""The 95 % point of χ² with one degree of freedom: dahl (n free) against tagawa2003 (n = 1)."""


def law_fitter(law: str) -> LawFitter:
    """The fitter of the bending law ``law``; an ArgumentError of ``law`` names the known ones."""
    if law not in LAW_FITTERS:
        raise ArgumentError("law", f"unknown bending law {law!r}; known: {', '.join(LAW_FITTERS)}")
    return LAW_FITTERS[law]


def selected_laws(law: str) -> list[str]:
    """The laws ``law`` (``--law``) asks for: one by name, or every one for ``all``."""
    if law == ALL_LAWS:
        return list(LAW_FITTERS)
    if law not in LAW_FITTERS:
        raise ArgumentError(
            "law",
            f"unknown bending law {law!r}; known: {', '.join(LAW_FITTERS)}, or "
            f"{ALL_LAWS} (fit every one and compare them)",
        )
    return [law]


def reproduced_kes_values(fits: list[BendingFit], k0_per_cm: float, device: str | None = "cpu") -> list[BendingSummary]:
    """B and 2HB of each fitted law along the standard cycle 0 → +K0 → −K0 → 0 (one launch)."""
    k = standard_cycle(k0_per_cm)
    moment, _ = moment_along_path(
        [to_si(f.material_section()) for f in fits], (k * units.CURVATURE_PER_CM)[:, None], device=device
    )
    return [
        bending_summary(bending_loop(k, moment[:, j] / units.MOMENT_GF_CM_PER_CM, "the fitted law"))
        for j in range(len(fits))
    ]


def _number(value: float | None, spec: str) -> str:
    return "n/a" if value is None else format(value, spec)


@dataclass(frozen=True)
class LawComparison:
    """Several bending laws fitted to one loop (see the module docstring)."""

    loop: BendingLoop
    fits: dict[str, BendingFit]  # law → its fit, in LAW_FITTERS order
    reproduced: dict[str, BendingSummary]  # law → B, 2HB of the fitted law along the standard cycle
    measured: BendingSummary  # the data's own B, 2HB

    def delta_aic(self) -> dict[str, float]:
        """AIC of each law minus the lowest."""
        best = min(f.aic() for f in self.fits.values())
        return {law: f.aic() - best for law, f in self.fits.items()}

    def delta_bic(self) -> dict[str, float]:
        """BIC of each law minus the lowest."""
        best = min(f.bic() for f in self.fits.values())
        return {law: f.bic() - best for law, f in self.fits.items()}

    def ranking(self) -> list[str]:
        """The laws from the lowest AIC up (a tie goes to fewer free parameters)."""
        return sorted(self.fits, key=lambda law: (self.fits[law].aic(), self.fits[law].free_parameters))

    @property
    def recommended(self) -> str:
        """The law with the lowest AIC."""
        return self.ranking()[0]

    def status(self, law: str) -> tuple[str, list[str]]:
        """The verdict of one law's fit to the loop (``converged``, ``not_identifiable``,
        ``at_bound``, ``poor_fit``, ``failed``)."""
        found = bending_problems(self.fits[law], self.loop)
        return (found[0][0] if found else "converged"), [message for _, message in found]

    def inner_rms(self, law: str) -> float | None:
        """RMS (gf·cm/cm) of the law's fit over the record's partial cycles; None without any."""
        start = self.loop.inner_start
        if start is None:
            return None
        residual = self.fits[law].moment[start:] - self.loop.moment[start:]
        return float(np.sqrt(np.mean(residual**2)))

    def inner_delta(self) -> dict[str, float]:
        """Over the partial cycles alone, n ln(SSE_law / SSE_best) of each law's fit to the
        whole record (the likelihood-ratio term of ΔAIC there; the fits' parameters are
        the same ones, so no penalty); empty without partial cycles."""
        start = self.loop.inner_start
        if start is None:
            return {}
        n = len(self.loop.moment) - start
        sse = {law: max(n * self.inner_rms(law) ** 2, 1e-300) for law in self.fits}
        best = min(sse.values())
        return {law: n * math.log(value / best) for law, value in sse.items()}

    def inner_loop_verdict(self) -> str:
        """Which laws' inner loops the record's partial cycles bear out, or why the loop
        cannot say (it has none)."""
        start = self.loop.inner_start
        if start is None:
            return (
                "this loop has no partial cycles, and a major loop does not determine how a law treats inner "
                "loops (tagawa2003 and masing share it exactly, a dahl of n = 1 too): which law's inner loops "
                "are the fabric's needs a KES-FB2 record with partial cycles (e.g. kes_fb2_inner_loops)"
            )
        delta = self.inner_delta()
        noise = difference_noise([self.loop.moment])
        best = min(delta, key=delta.get)
        ties = [law for law, d in delta.items() if d < AIC_TIE]
        listed = ", ".join(f"{law} {d:+.1f}" for law, d in sorted(delta.items(), key=lambda item: item[1]))
        head = (
            f"partial cycles from {self.loop.row_label} {self.loop.rows[start]} on "
            f"({len(self.loop.moment) - start} points), n ln(SSE/SSE_best) there: {listed}"
        )
        ratio = self.inner_rms(best) / noise
        if poor_fit_ratio(self.inner_rms(best), noise) is not None:
            return f"{head}; no law describes them (the best, {best}, at {ratio:.1f}× the noise {noise:.3g} gf·cm/cm)"
        if len(ties) == len(delta):
            return f"{head}; they do not tell the laws' inner loops apart (every law within {AIC_TIE:g})"
        return (
            f"{head}; the inner loops are {' and '.join(ties)}'s (RMS {ratio:.2f}× the noise there), the other "
            f"law(s) worse by ≥ {AIC_TIE:g}"
        )

    def same_as_tagawa2003(self) -> str | None:
        """Why the dahl fit is the paper's law (n within 0.05 of 1, or not significantly
        different from 1 by the likelihood ratio against the tagawa2003 fit); None if not
        (or either law was not fitted)."""
        if "dahl" not in self.fits or "tagawa2003" not in self.fits or self.status("dahl")[0] == "not_identifiable":
            return None  # without hysteresis in the loop, n means nothing
        dahl, paper = self.fits["dahl"], self.fits["tagawa2003"]
        n = dahl.parameters["dahl_exponent"]
        ratio = max(dahl.points * 2 * math.log(paper.rms_gf_cm_per_cm / max(dahl.rms_gf_cm_per_cm, 1e-300)), 0.0)
        if abs(n - 1) < SAME_EXPONENT:
            return f"dahl's n = {n:.3g} is within {SAME_EXPONENT:g} of 1"
        if ratio < LIKELIHOOD_RATIO_95:
            return (
                f"dahl's n = {n:.3g} is within its uncertainty of 1 (the likelihood ratio of dahl over tagawa2003, "
                f"n ln(SSE_tagawa2003 / SSE_dahl) = {ratio:.2f}, is below {LIKELIHOOD_RATIO_95}, the 95 % point "
                "of χ² with 1 degree of freedom)"
            )
        return None

    def caveats(self) -> list[str]:
        """The recommendation and what it does not say."""
        ranking, delta = self.ranking(), self.delta_aic()
        best = ranking[0]
        lines = [
            f"recommended by AIC: {best}"
            + (f" (next: {ranking[1]}, ΔAIC {delta[ranking[1]]:.2f})" if len(ranking) > 1 else " (the only law fitted)")
        ]
        ties = [law for law in ranking[1:] if delta[law] < AIC_TIE]
        if ties:
            lines.append(
                f"{', '.join(ties)} {'is' if len(ties) == 1 else 'are'} within ΔAIC < {AIC_TIE:g} of {best}: "
                "not a preference; the loop does not tell these laws apart"
            )
        same = self.same_as_tagawa2003()
        if same:
            lines.append(
                f"{same}: dahl with n = 1 is tagawa2003 (M_s = M0, K_s = 1/α), so on this loop the two are the same law"
            )
        lines.append(self.inner_loop_verdict())
        if all(self.status(law)[0] == "not_identifiable" for law in self.fits):
            lines.append(
                "no law's hysteresis is determined by this loop: the elastic line M = D K fits it as well, "
                "so the ranking says nothing; measure a loop with a visible width (2HB above the noise)"
            )
        lines.append(
            "a quasi-static KES-FB2 loop says nothing about rate effects: check the choice against a "
            "measured swing (warpcloth fit)"
        )
        return lines

    def rows(self) -> list[dict]:
        """One row per law (and one of the measured KES values), for a CSV table."""
        fields = list(dict.fromkeys(p.field for law in self.fits for p in LAW_FITTERS[law].parameters))
        delta_aic, delta_bic = self.delta_aic(), self.delta_bic()
        rows = []
        for law, fit in self.fits.items():
            rows.append(
                {
                    "law": law,
                    "recommended": law == self.recommended,
                    "status": self.status(law)[0],
                    "free_parameters": fit.free_parameters,
                    "points": fit.points,
                    "rms_gf_cm_per_cm": fit.rms_gf_cm_per_cm,
                    "rms_relative": fit.rms_relative,
                    "aic": fit.aic(),
                    "bic": fit.bic(),
                    "delta_aic": delta_aic[law],
                    "delta_bic": delta_bic[law],
                    "inner_rms_gf_cm_per_cm": self.inner_rms(law),
                    "inner_delta": self.inner_delta().get(law),
                    "b_gf_cm2_per_cm": self.reproduced[law].b_gf_cm2_per_cm,
                    "2hb_gf_cm_per_cm": self.reproduced[law].hb2_gf_cm_per_cm,
                    **{name: fit.parameters.get(name) for name in fields},
                }
            )
        rows.append(
            {
                "law": "measured",
                "b_gf_cm2_per_cm": self.measured.b_gf_cm2_per_cm,
                "2hb_gf_cm_per_cm": self.measured.hb2_gf_cm_per_cm,
            }
        )
        return rows

    def table(self) -> str:
        """The comparison as printed text: one line per law, then the measured KES values."""
        delta_aic, delta_bic = self.delta_aic(), self.delta_bic()
        width = max(len(law) for law in [*self.fits, "measured"])
        head = (
            f"{'law':<{width}}  k  {'RMS gf·cm/cm':>12}  {'AIC':>9}  {'BIC':>9}  {'ΔAIC':>7}  {'ΔBIC':>7}  "
            f"{'B gf·cm²/cm':>11}  {'2HB gf·cm/cm':>12}  {'status':<9}  parameters"
        )
        lines = [head]
        for law, fit in self.fits.items():
            kes = self.reproduced[law]
            lines.append(
                f"{law:<{width}}  {fit.free_parameters}  {fit.rms_gf_cm_per_cm:>12.5g}  {fit.aic():>9.2f}  "
                f"{fit.bic():>9.2f}  {delta_aic[law]:>7.2f}  {delta_bic[law]:>7.2f}  "
                f"{_number(kes.b_gf_cm2_per_cm, '>11.5g')}  {_number(kes.hb2_gf_cm_per_cm, '>12.5g')}  "
                f"{self.status(law)[0]:<9}  {LAW_FITTERS[law].describe(fit)}"
            )
        lines.append(
            f"{'measured':<{width}}  {'':>1}  {'':>12}  {'':>9}  {'':>9}  {'':>7}  {'':>7}  "
            f"{_number(self.measured.b_gf_cm2_per_cm, '>11.5g')}  "
            f"{_number(self.measured.hb2_gf_cm_per_cm, '>12.5g')}  (the data's own KES values)"
        )
        return "\n".join(lines)

    def fit_table(self) -> dict:
        """What a material file's [fit] table records of the comparison."""
        delta = self.delta_aic()
        return {
            "bending_law_chosen_by": f"lowest AIC among {', '.join(self.fits)}",
            "bending_comparison": {
                law: {
                    "aic": f.aic(),
                    "bic": f.bic(),
                    "delta_aic": delta[law],
                    "rms_gf_cm_per_cm": f.rms_gf_cm_per_cm,
                    "status": self.status(law)[0],
                }
                | (
                    {"inner_rms_gf_cm_per_cm": self.inner_rms(law), "inner_delta": self.inner_delta()[law]}
                    if self.loop.inner_start is not None
                    else {}
                )
                for law, f in self.fits.items()
            },
        }


def compare_laws(loop: BendingLoop, laws: list[str] | None = None, device: str | None = "cpu") -> LawComparison:
    """Fit each of ``laws`` (default: every one) to the loop and compare them."""
    laws = list(LAW_FITTERS) if laws is None else laws
    fits = {law: law_fitter(law).fit(loop, device) for law in laws}
    reproduced = reproduced_kes_values(list(fits.values()), loop.k0, device)
    return LawComparison(loop, fits, dict(zip(fits, reproduced, strict=True)), bending_summary(loop))
