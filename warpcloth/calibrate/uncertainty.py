"""Which fitted values the data determine: each with its 1σ from the fit's covariance, or
marked "not determined" (the project's rule: never a confident wrong number).

A fit can describe its data within the noise while some of its parameters are not fixed
by them: a quartic's coefficients over a short piece trade against each other, a flat
onset against them all. :func:`judge` tells them apart from the covariance
s² (JᵀJ)⁻¹ (:func:`warpcloth.calibrate.motion_fit.lm.covariance`): a value is not
determined when it lies within :data:`DETERMINED_SIGMAS` σ of 0 (of its scale, for a time),
or when its multiple correlation with the other parameters exceeds
:data:`DETERMINED_CORRELATION`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .motion_fit.lm import sigma_and_correlation

DETERMINED_SIGMAS = 3.0
"""A value is determined when it lies at least this many σ from 0 (a time, whose 0 is the
record's clock: when its σ is below 1 / this of its own scale, e.g. the pieces it bounds)."""
DETERMINED_CORRELATION = 0.99
"""Beyond this multiple correlation with the other parameters (R² = 1 − 1/(C⁻¹)ᵢᵢ of the
correlation matrix C) a value is not determined: the data fix a combination, not it, and
its linearised σ (then ≥ 7× what it would be with the others known) understates how far
it can move. A clamp quartic's onset trades with a1…a3 together, with none of them alone
beyond 0.95, so the pairwise correlations miss it (on the bundled encoder the onset reads
8 ms against a true 0, its profile's 1σ some 7 ms, its linearised σ 2.8 ms)."""


@dataclass(frozen=True)
class FittedValue:
    """One reported value of a fit: its 1σ, and whether the data determine it, with the
    reason when they do not."""

    name: str
    value: float
    sigma: float
    unit: str
    determined: bool
    why: str = ""

    def text(self) -> str:
        """``name = value ± σ unit``, both to σ's second significant digit, or the value
        (4 significant digits) marked "not determined" and why."""
        unit = f" {self.unit}" if self.unit else ""
        if self.determined:
            decimals = max(0, 1 - math.floor(math.log10(self.sigma))) if self.sigma > 0 else 6
            return f"{self.name} = {self.value:.{decimals}f} ± {self.sigma:.{decimals}f}{unit}"
        return f"{self.name} = {self.value:.4g}{unit}: not determined ({self.why})"


def from_sigma(name: str, value: float, sigma: float, unit: str) -> FittedValue:
    """A value derived from the parameters (its σ propagated), judged by σ alone: a
    function of the others is correlated with them by construction."""
    if not math.isfinite(sigma):
        return FittedValue(name, value, sigma, unit, False, "its σ is not finite: the data do not fix it")
    small = sigma * DETERMINED_SIGMAS <= abs(value)
    return FittedValue(name, value, sigma, unit, small, "" if small else f"σ {sigma:.2g} {unit}; within 3σ of 0")


def judge(
    names: Sequence[str],
    units: Sequence[str],
    values: np.ndarray,
    cov: np.ndarray,
    scales: dict[int, tuple[float, str]] | None = None,
) -> list[FittedValue]:
    """Each parameter's value, 1σ (the diagonal of ``cov``) and whether it is determined.
    ``scales`` maps a parameter's index to the scale its σ is judged against instead of
    its value, and what that scale is (a time's: the pieces it bounds). A singular
    covariance (NaN) leaves every value not determined."""
    scales = scales or {}
    sigma, correlation = sigma_and_correlation(cov)
    try:
        inflation = np.diag(np.linalg.inv(correlation))  # 1 / (1 − R²) of each parameter
        multiple = np.sqrt(np.clip(1 - 1 / inflation, 0, 1))
    except np.linalg.LinAlgError:
        multiple = np.full(len(values), np.nan)
    out = []
    for i, (name, unit, value) in enumerate(zip(names, units, values, strict=True)):
        others = np.abs(np.nan_to_num(correlation[i]))
        others[i] = 0.0
        j = int(np.argmax(others))
        scale, what = scales.get(i, (abs(value), "within 3σ of 0"))
        if not (np.isfinite(sigma[i]) and np.isfinite(multiple[i])):
            why = "the Jacobian is singular: the data do not fix it"
        elif len(values) > 1 and multiple[i] > DETERMINED_CORRELATION:
            why = (
                f"it trades with the other parameters, multiple correlation {multiple[i]:.6f}; "
                f"most with {names[j]}, {correlation[i, j]:+.2f}"
            )
        elif sigma[i] * DETERMINED_SIGMAS > scale:
            why = f"σ {sigma[i]:.2g} {unit}; {what}"
        else:
            why = ""
        out.append(FittedValue(name, float(value), float(sigma[i]), unit, not why, why))
    return out


def value_text(symbol: str, value: float, sigma: float | None, unit: str, digits: int = 6) -> str:
    """``symbol value ± σ unit`` for a fitted value; a value with no σ (``None``) is the
    data's, not fitted, and says so; a NaN or infinite σ (a singular Jacobian, a shape
    with no amplitude to act on) is marked not determined instead of printed bare."""
    unit = f" {unit}" if unit else ""
    if sigma is None:
        return f"{symbol} {value:.{digits}g}{unit} (the data's, not fitted)"
    if not math.isfinite(sigma):
        return f"{symbol} {value:.{digits}g}{unit} (not determined: no finite σ)"
    return f"{symbol} {value:.{digits}g} ± {sigma:.2g}{unit}"
