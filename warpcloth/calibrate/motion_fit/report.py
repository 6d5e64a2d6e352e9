"""What a motion fit reports: :class:`FitResult` (values, σ, verdict, how the search went)
and the files :func:`write_fit` writes."""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from warpcloth.io.json_file import json_text
from warpcloth.io.measured import LaserTrace, SheetMarkers, TrackedShapes
from warpcloth.scene import scene_from_dict, set_field
from warpcloth.scene.step import AUTO

from . import lm
from .continuum import ContinuumEstimate
from .objective import SHIFT, FitObjective, make_objective
from .verdict import ended_at_bound, judge


@dataclass
class FitResult:
    """Best parameters, their uncertainty, and how the search went."""

    parameters: dict[str, float]
    sigma: dict[str, float]
    correlation: list[list[float]]
    rms: float
    shift_s: float
    n_residuals: int
    launches: int
    variants: int
    wall_time_s: float
    history: list[dict] = field(default_factory=list)
    converged: bool = False  # the search met its convergence test (not the iteration limit)
    at_bound: list[str] = field(default_factory=list)  # fields within 0.1 % of the range of a bound
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    sigma_bootstrap: dict[str, float] = field(default_factory=dict)  # block bootstrap (``bootstrap`` > 0)
    other_minima: list[dict] = field(default_factory=list)  # separate basins of the space-filling stage, not refined
    bootstrap_block: int = 0  # residuals per bootstrap block
    sigma_frames: dict[str, float] = field(default_factory=dict)  # robust to errors shared by a frame's points
    sigma_gauss_newton: dict[str, float] = field(default_factory=dict)  # for independent errors, when σ is robust
    frames_per_block: int = 0  # tracked frames per block of the robust σ
    noise: float = float("nan")  # measurement noise σ the RMS is judged against, SI
    noise_source: str = ""
    status: str = "failed"
    problems: list[str] = field(default_factory=list)  # why the status is not "converged"
    mesh_note: str = ""  # why the values hold at the fitted spacing only (a law whose answers depend on h)
    continuum: dict = field(default_factory=dict)  # the extrapolation's evidence (:mod:`.continuum`); {} if none
    at_spacing: dict[str, float] = field(default_factory=dict)  # the values fitted at the scene's spacing
    sigma_noise: dict[str, float] = field(default_factory=dict)  # the measurement noise's share of σ
    sigma_mesh: dict[str, float] = field(default_factory=dict)  # the discretisation's share of σ
    rms_at_spacing: float = float("nan")  # the RMS at the scene's spacing
    rms_mesh: float = 0.0  # the finest level's misfit that refining the mesh removes (m)
    spacing: dict[str, float] = field(default_factory=dict)  # the mesh best.toml reruns the values on (mm)
    dt_s: float = float("nan")  # the step best.toml reruns the values with (each level's: ``continuum``)

    def apply_continuum(self, estimate: ContinuumEstimate, objective: FitObjective) -> None:
        """Report ``estimate`` (:func:`~.continuum.continuum_limit`): the values at h → 0,
        σ_total² = σ_noise² + σ_mesh², the RMS of the finest level's run there (the
        extrapolated residual's beside it), the bounds judged there; best.toml reruns them
        on the finest level's mesh. An unresolved estimate keeps the values at the scene's
        spacing (the verdict says why)."""
        self.continuum = estimate.to_json(objective.names) | {
            "fitted_at_mm": {name: objective.spacing_of(name) for name in objective.spacing_fields}
        }
        self.at_spacing = dict(self.parameters)
        self.sigma_noise = dict(self.sigma)
        self.rms_at_spacing = self.rms
        if estimate.status != "extrapolated":
            return
        assert estimate.q is not None and estimate.sigma_mesh is not None and estimate.finest is not None
        assert estimate.residual is not None and estimate.residual_finest is not None  # set together
        q, mesh = estimate.q, estimate.sigma_mesh
        d = len(objective.free)
        self.shift_s = objective.shift_of(q)
        self.parameters = objective.values(q[:d]) | ({SHIFT: self.shift_s} if objective.align else {})
        self.sigma_mesh = dict(zip(objective.names, mesh.tolist(), strict=True))
        self.sigma = {name: math.hypot(self.sigma_noise[name], self.sigma_mesh[name]) for name in self.parameters}
        # judged on the finest level's run at these values (a run that happened), the
        # extrapolated residual's RMS beside it
        self.rms = float(np.sqrt(np.mean(estimate.residual_finest**2)))
        # the part of that run's misfit the mesh makes: the verdict counts it beside the noise
        self.rms_mesh = float(np.sqrt(np.mean((estimate.residual_finest - estimate.residual) ** 2)))
        self.continuum["rms_extrapolated_mm"] = float(np.sqrt(np.mean(estimate.residual**2))) * 1e3
        self.at_bound = ended_at_bound(objective.free, q[:d])
        self.spacing = {name: estimate.finest.spacing_of(name) for name in objective.spacing_fields}
        self.dt_s = estimate.finest.dt_s

    def to_json(self) -> dict:
        """The verdict, each parameter with its 1σ and bounds, and how the search went;
        lengths in mm, names with their units."""
        return {
            "status": self.status,
            "problems": self.problems,
            "mesh_note": self.mesh_note,
            "continuum": self.continuum,
            "rms_mm": self.rms * 1e3,
            "rms_at_spacing_mm": self.rms_at_spacing * 1e3,
            "rms_mesh_mm": self.rms_mesh * 1e3,
            "noise_mm": self.noise * 1e3,
            "noise_source": self.noise_source,
            "parameters": {
                name: {
                    "value": value,
                    "sigma": self.sigma[name],
                    "sigma_noise": self.sigma_noise.get(name, self.sigma[name]),
                    "sigma_mesh": self.sigma_mesh.get(name),
                    "at_spacing": self.at_spacing.get(name, value),
                    "at_bound": name in self.at_bound,
                    "bounds": list(self.bounds.get(name, ())),
                }
                | ({"sigma_bootstrap": self.sigma_bootstrap[name]} if self.sigma_bootstrap else {})
                | (
                    {"sigma_frames": self.sigma_frames[name], "sigma_gauss_newton": self.sigma_gauss_newton[name]}
                    if self.sigma_frames
                    else {}
                )
                for name, value in self.parameters.items()
            },
            "bootstrap_block": self.bootstrap_block,
            "frames_per_block": self.frames_per_block,
            "other_minima": self.other_minima,
            "correlation": {"names": list(self.parameters), "matrix": self.correlation},
            "n_residuals": self.n_residuals,
            "search_converged": self.converged,
            "launches": self.launches,
            "variants": self.variants,
            "wall_time_s": self.wall_time_s,
            "history": self.history,
            "spacing_mm": self.spacing,
            "dt_s": self.dt_s,
        }

    def judge(self, missing: int) -> None:
        """Set :attr:`status` and :attr:`problems` (``missing``: measured points the best
        run has no value for; :func:`warpcloth.calibrate.motion_fit.verdict.judge`)."""
        self.status, self.problems = judge(self, missing)


def summarise(
    objective: FitObjective,
    u: np.ndarray,
    shift: float,
    jac: np.ndarray,
    residual: np.ndarray,
    history: list[dict],
    converged: bool,
    wall: float,
) -> FitResult:
    """The fit at point ``u`` (clock offset ``shift``) with its Jacobian and residuals
    there: the values, their σ and correlation, the RMS, how the search went.

    σ is Gauss–Newton's, which holds for independent errors. Tracked points share their
    frame's errors (the camera's; the edge modes measure every arc from one free end), so
    for a strip's shapes and a sheet's markers σ is the larger of it and the frame-clustered sandwich
    (:func:`~.lm.clustered_covariance`; the correlation is then the sandwich's): compared
    in x and y, the rig's dyed edge had Gauss–Newton's σ of γ a quarter of the error it made
    (benchmarks/RESULTS.md). The sandwich's residuals hold the mesh's misfit at the fit's
    spacing too, which the continuum's σ_mesh also counts: conservative there."""
    scaled = jac / objective.ranges
    cov = lm.covariance(scaled, residual)
    sigma, correlation = lm.sigma_and_correlation(cov)
    groups = objective.residual_groups()
    robust, per_block = (None, 0) if groups is None else lm.clustered_covariance(scaled, residual, groups)
    if robust is not None:
        sigma_frames, correlation = lm.sigma_and_correlation(robust)
        gauss_newton = sigma
        sigma = np.maximum(sigma, sigma_frames)
    values = objective.values(u) | ({SHIFT: shift} if objective.align else {})
    fit = FitResult(
        values,
        dict(zip(objective.names, sigma.tolist(), strict=True)),
        correlation.tolist(),
        float(np.sqrt(np.mean(residual**2))),
        shift,
        len(residual),
        objective.launches,
        objective.variants,
        wall,
        history,
        converged,
    )
    if robust is not None:
        fit.sigma_frames = dict(zip(objective.names, sigma_frames.tolist(), strict=True))
        fit.sigma_gauss_newton = dict(zip(objective.names, gauss_newton.tolist(), strict=True))
        fit.frames_per_block = per_block
    return fit


def write_fit(
    fit: FitResult,
    objective_base: dict,
    measurement: LaserTrace | TrackedShapes | SheetMarkers,
    out: str | Path,
    device: str | None = None,
    inputs: dict | None = None,
) -> list[Path]:
    """Write the fit: ``best.toml`` (reruns the best fit with the scene's own duration and
    output), ``fit.json`` (with ``inputs``, e.g. the measured file and its checksum, the
    seed, and the provenance), ``history.csv``, ``residuals.csv`` and ``overlay.png``.

    The best fit is rerun and every file prepared under a temporary name before any is
    renamed into place, so a failure leaves no mixture of old and new files."""
    import pandas as pd
    import tomli_w

    from warpcloth.io.atomic import write_files_atomically
    from warpcloth.io.provenance import provenance
    from warpcloth.viz.plots import plot_fit_overlay

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    best = copy.deepcopy(objective_base)
    best.pop("sweep", None)
    for name, value in fit.parameters.items():
        if name != SHIFT:
            set_field(best, name, value)
    for name, value in fit.spacing.items():  # the finest level's mesh, where the continuum values belong
        set_field(best, name, value)
    if math.isfinite(fit.dt_s):
        chosen_by = best.get("integrator", {}).get("dt_s") == AUTO
        set_field(best, "integrator.dt_s", fit.dt_s)  # the step the RMS was measured at
        set_field(best, "integrator.dt_chosen_by", AUTO if chosen_by else "scene")
    scene = scene_from_dict(copy.deepcopy(best))
    objective = make_objective(best, measurement, [], abs(fit.shift_s), device)
    result = objective.run(np.zeros((1, 0)))
    residual = objective.residuals(result, 0, fit.shift_s, penalise=False)
    if isinstance(measurement, SheetMarkers):
        r = residual.reshape(-1, len(measurement.axes))
        table = pd.DataFrame(
            {"t_s": measurement.t, "marker": measurement.marker}
            | {f"residual_{axis}_mm": r[:, a] * 1e3 for a, axis in enumerate(measurement.axes)}
        )
    elif isinstance(measurement, LaserTrace):
        table = pd.DataFrame(
            {
                "t_s": measurement.t,
                "measured_x_mm": measurement.x * 1e3,
                "simulated_x_mm": (measurement.x + residual) * 1e3,
                "residual_mm": residual * 1e3,
            }
        )
    else:
        r = residual.reshape(-1, 2)
        # a curve's residuals are across the strip and along it less the frame's mean (ALONG_COLUMN)
        names = ("residual_x_mm", "residual_y_mm")
        if measurement.u_along is not None:
            names = ("residual_across_mm", "residual_along_less_frame_mean_mm")
        table = pd.DataFrame(
            {
                "frame": measurement.frame,
                "t_s": measurement.t,
                "s_mm": measurement.s * 1e3,
                names[0]: r[:, 0] * 1e3,
                names[1]: r[:, 1] * 1e3,
            }
        )
    return write_files_atomically(
        out,
        {
            "best.toml": lambda p: p.write_text(tomli_w.dumps(scene.to_dict())),
            "fit.json": lambda p: p.write_text(
                json_text(fit.to_json() | {"inputs": inputs or {}, "provenance": provenance(device)})
            ),
            "history.csv": lambda p: pd.DataFrame(fit.history).to_csv(p, index=False),
            "residuals.csv": lambda p: table.to_csv(p, index=False),
            "overlay.png": lambda p: plot_fit_overlay(result, objective, measurement, fit, p),
        },
    )
