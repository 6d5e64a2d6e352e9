"""What a motion fit's result may be read as: its status (:data:`STATUSES`), the
parameters that ended on a bound, the noise its RMS is judged against, whether the strip's
spacing limits it (:mod:`.continuum`), and, before any fit, what experiments can
determine at all (:func:`weighted_jacobian`, :func:`identifiability`)."""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from warpcloth.errors import ArgumentError, PlausibilityWarning
from warpcloth.io.measured import LaserTrace, SheetMarkers, TrackedShapes
from warpcloth.scene import scene_from_dict

from ..noise import difference_noise, poor_fit_ratio
from . import lm
from .objective import Objective
from .parameters import FreeParameter, free_parameters, initial_point

if TYPE_CHECKING:
    from .report import FitResult

STATUSES = ("converged", "spacing_limited", "mesh_dependent", "at_bound", "poor_fit", "not_identifiable", "failed")
"""Verdicts of a fit, from the only one that is a fit to the worst (see the package docstring)."""
AT_BOUND = 1e-3  # a parameter this close to a bound, as a fraction of its range, ended on it
NOT_IDENTIFIABLE_CORRELATION = 0.95
NOISE_GIVEN_FACTOR = 10.0
"""A given noise σ above this many times the one the data show is named (a calibration's
systematic error can make the right σ a few times the random one, not ten)."""


def ended_at_bound(free: list[FreeParameter], u: np.ndarray) -> list[str]:
    """The fields of the unit-box point ``u`` within :data:`AT_BOUND` of a bound: the
    optimum lies beyond, so the value is not an estimate and its σ from the local Jacobian
    means nothing."""
    return [p.field for p, ui in zip(free, u, strict=True) if min(ui, 1.0 - ui) <= AT_BOUND]


def judged_noise(
    measurement: LaserTrace | TrackedShapes | SheetMarkers, noise: float | None, residual: np.ndarray | None = None
) -> tuple[float, str]:
    """The noise σ (m) a fit's RMS is judged against, and where it comes from: ``noise``
    if given; else, for shapes ``warpcloth track`` wrote, the uncertainty it stated for
    each point (u_mm: sensor noise, the outline's misfit and the calibration), RMS over the
    points; else estimated. Markers (a strip's or a sheet's) are records sampled coarsely
    against their motion, whose clamp jerks at its pieces' ends: the data's 4th
    differences read that motion as noise (0.11 mm on the bundled video against its
    0.003 mm, twice the true σ on the bundled sheet), so with the fit's ``residual`` at
    the best point their noise is estimated from the residuals' 4th differences instead,
    the model's motion removed and a smooth misfit left to the RMS. A laser trace, sampled
    finely, is judged by its own (:func:`measurement_noise`)."""
    if noise is not None:
        return float(noise), "given"
    if isinstance(measurement, TrackedShapes) and measurement.u is not None:
        return (
            float(np.sqrt(np.mean(measurement.u**2))),
            "the tracker's stated uncertainty u_mm, its RMS over the points",
        )
    if isinstance(measurement, SheetMarkers | TrackedShapes) and residual is not None:
        per_axis = residual.reshape(-1, 2 if isinstance(measurement, TrackedShapes) else len(measurement.axes))
        marker = measurement.s if isinstance(measurement, TrackedShapes) else measurement.marker
        series = [per_axis[marker == k, a] for k in np.unique(marker) for a in range(per_axis.shape[1])]
        return difference_noise(series), "estimated from the 4th differences of the fit's residuals"
    return measurement_noise(measurement), "estimated from the data's 4th differences"


def judge(fit: FitResult, missing: int) -> tuple[str, list[str]]:
    """The status of ``fit`` and its problems (``missing``: measured points the best run
    has no value for). Problems are listed in order of precedence and the status is the
    first's: a result that is not an estimate (failed, at_bound) before one whose
    parameters are not separated or whose model does not fit, and the iteration limit
    last (a fit at a bound that also ran out of iterations is reported at_bound)."""
    names = list(fit.parameters)
    corr = np.asarray(fit.correlation, dtype=float)
    found: list[tuple[str, str]] = []
    if missing or not math.isfinite(fit.rms):
        found.append(
            (
                "failed",
                f"the best run has no value for {missing} of the {fit.n_residuals} measured "
                "points (the strip misses the laser line or diverged)"
                if missing
                else f"the RMS is {fit.rms}",
            )
        )
    for name in fit.at_bound:
        low, high = fit.bounds[name]
        found.append(
            (
                "at_bound",
                f"{name} = {fit.parameters[name]:.6g} ended on a bound ({low:g}:{high:g}); "
                "the optimum lies outside, so it is not an estimate: widen --bounds or fix "
                "the model",
            )
        )
    if not all(math.isfinite(v) for v in fit.sigma.values()):
        found.append(("not_identifiable", "the Jacobian is singular: some parameter does not change the fit"))
    for i in range(len(names)):
        for j in range(i):
            if abs(corr[i, j]) > NOT_IDENTIFIABLE_CORRELATION:
                found.append(
                    (
                        "not_identifiable",
                        f"{names[i]} and {names[j]} are correlated {corr[i, j]:+.3f}: "
                        "the data do not separate them; fix one, or measure what "
                        "distinguishes them",
                    )
                )
    # judged on a run that happened (the finest level's, at the reported values) against
    # the noise and the misfit that mesh still makes (what refining it removes): the
    # continuum model is what the values claim, and a model error does not refine away
    ratio = poor_fit_ratio(fit.rms, math.hypot(fit.noise, fit.rms_mesh))
    if ratio is not None:
        mesh = f" and the mesh's share {fit.rms_mesh * 1e3:.3g} mm" if fit.rms_mesh else ""
        found.append(
            (
                "poor_fit",
                f"the RMS {fit.rms * 1e3:.4g} mm is {ratio:.1f}× the "
                f"measurement noise {fit.noise * 1e3:.3g} mm ({fit.noise_source}){mesh}: the "
                "model with these free parameters does not explain the data",
            )
        )
    if fit.mesh_note:
        found.append(("mesh_dependent", f"{fit.mesh_note}; these are not fabric properties"))
    else:
        found += [("spacing_limited", problem) for problem in continuum_problems(fit.continuum)]
    if not fit.converged:
        found.append(("failed", "the search stopped at its iteration limit before converging (raise --max-iterations)"))
    return found[0][0] if found else "converged", [message for _, message in found]


def continuum_problems(continuum: dict) -> list[str]:
    """Why a fit's values are not its continuum limit (fit.json's ``continuum``,
    :mod:`.continuum`); [] when they are."""
    if continuum.get("status") == "extrapolated":
        return []
    if continuum.get("status") == "not requested":
        return [
            "the values are the fit at the scene's spacing, whose error nobody estimated (continuum "
            "estimate not requested); they are the mesh's as much as the fabric's"
        ]
    if not continuum:
        return ["the continuum estimate could not run: the fit at the scene's spacing misses measured points"]
    return [f"no continuum estimate: {continuum['note']}; the values are the fit at the scene's spacing"]


def measured_series(measurement: LaserTrace | TrackedShapes | SheetMarkers) -> list[np.ndarray]:
    """A measurement's coordinates as series in time (m): the laser's x; each marker's (or
    arc length's) coordinates, one series per axis."""
    if isinstance(measurement, LaserTrace):
        return [measurement.x]
    if isinstance(measurement, SheetMarkers):
        return [
            measurement.position[measurement.marker == k, a]
            for k in np.unique(measurement.marker)
            for a in range(len(measurement.axes))
        ]
    order = np.lexsort((measurement.frame, measurement.s))
    s = measurement.s[order]
    starts = np.flatnonzero(np.r_[True, np.diff(s) != 0, True])
    pieces = [slice(a, b) for a, b in zip(starts[:-1], starts[1:], strict=True)]
    return [measurement.x[order][p] for p in pieces] + [measurement.y[order][p] for p in pieces]


def measurement_noise(measurement: LaserTrace | TrackedShapes | SheetMarkers) -> float:
    """σ of a measurement's noise from the data alone (each marker coordinate a series)."""
    return difference_noise(measured_series(measurement))


def check_given_noise(measurement: LaserTrace | TrackedShapes | SheetMarkers, noise: float | None) -> None:
    """Refuse a given noise σ (m) as large as the measured motion itself (every model would
    fit within it, so the RMS could judge nothing), and warn of one above
    :data:`NOISE_GIVEN_FACTOR` × the noise the data show: the fit's status is judged
    against it, so a poor fit may read as converged."""
    if noise is None:
        return
    if not (isinstance(noise, int | float) and math.isfinite(noise) and noise > 0):
        raise ArgumentError("noise", f"a noise σ is a positive number of metres, got {noise!r}")
    series = measured_series(measurement)
    spread = float(np.sqrt(np.mean(np.concatenate([(x - x.mean()) ** 2 for x in series]))))
    if noise >= spread:
        raise ArgumentError(
            "noise",
            f"{noise * 1e3:.4g} mm is as large as the measured motion itself (its RMS about the mean, "
            f"{spread * 1e3:.3g} mm): any model would fit within it, so the fit could judge nothing; give the "
            "measurement's σ (or leave it out: it is estimated from the data)",
        )
    shown = measurement_noise(measurement)
    if noise > NOISE_GIVEN_FACTOR * shown:
        warnings.warn(
            f"--noise {noise * 1e3:.4g} mm is {noise / shown:.3g}× the noise the data's 4th differences show "
            f"({shown * 1e3:.3g} mm); the fit's RMS is judged against the value given, so a fit that does not "
            "explain the data may read as converged",
            PlausibilityWarning,
            stacklevel=3,
        )


@dataclass
class Identifiability:
    """What an experiment (or several together) can determine about the free parameters at a
    point, before any fit: the Gauss–Newton σ and correlation for measurement noise σ_m, and
    the pairs correlated beyond :data:`NOT_IDENTIFIABLE_CORRELATION` (the fit's
    ``not_identifiable`` verdict)."""

    names: list[str]
    sigma: dict[str, float]
    correlation: np.ndarray
    not_identifiable: list[tuple[str, str, float]]

    def table(self) -> str:
        """The correlation matrix as text, with σ and the pairs the data do not separate."""
        width = max(len(n) for n in self.names)
        lines = [" " * width + "  " + " ".join(f"{i:>6d}" for i in range(len(self.names))) + "   σ"]
        for i, name in enumerate(self.names):
            row = " ".join(f"{c:+6.3f}" for c in self.correlation[i])
            lines.append(f"{name:<{width}}  {row}   {self.sigma[name]:.3g}")
        lines += [f"not identifiable: {a} and {b} correlated {c:+.3f}" for a, b, c in self.not_identifiable]
        return "\n".join(lines)


def weighted_jacobian(
    base: dict,
    measurement: LaserTrace | TrackedShapes,
    noise: float,
    names: str | list[str],
    bounds: str | None = None,
    device: str | None = None,
) -> tuple[list[str], np.ndarray]:
    """The fields of the ``--free`` parameters ``names`` and ∂r/∂(field value) / σ_m of the
    experiment (raw scene ``base``, its ``measurement``, noise σ_m in m) at the scene's own
    values: one batched launch of the central-difference stencil, as the fit takes it."""
    free = free_parameters(names, scene_from_dict(copy.deepcopy(base)), bounds)
    objective = Objective(base, measurement, free, 0.0, device)
    u = initial_point(free)
    rows, pairs = lm.stencil(u)
    result = objective.run(np.vstack([u, *rows]))
    return objective.names, objective.jacobian(result, pairs, 0, 0.0) / objective.ranges / noise


def identifiability(blocks: list[tuple[list[str], np.ndarray]]) -> Identifiability:
    """σ and correlation of the parameters from experiments' :func:`weighted_jacobian`
    blocks, stacked as one fit of all their residuals would stack them (the same fields in
    each). A correlation beyond :data:`NOT_IDENTIFIABLE_CORRELATION`, or a singular
    Jacobian, is a pair the data do not separate (docs/calibration.md, "What the data
    determine")."""
    fields = blocks[0][0]
    other = next((k for k, (f, _) in enumerate(blocks) if f != fields), None)
    if other is not None:
        raise ArgumentError(
            "blocks",
            f"every experiment must have the same free parameters, in the same order: block {other} has "
            f"{', '.join(blocks[other][0])}, block 0 {', '.join(fields)}",
        )
    sigma, correlation = lm.sigma_and_correlation(lm.covariance(np.vstack([j for _, j in blocks])))
    pairs = [
        (fields[i], fields[j], float(correlation[i, j]))
        for i in range(len(fields))
        for j in range(i)
        if not abs(correlation[i, j]) <= NOT_IDENTIFIABLE_CORRELATION
    ]
    return Identifiability(fields, dict(zip(fields, sigma.tolist(), strict=True)), correlation, pairs)
