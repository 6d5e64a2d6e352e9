"""What the continuum estimate of a motion fit costs and how well it does (issue 34).

Records made by runs far finer than any fit uses, fitted at coarser spacings three ways:

- ``at h``: the fit at the spacing alone (``continuum=False``; what fits reported before):
  the baseline whose wall the others are compared with, in the same run;
- ``continuum``: the default (:mod:`warpcloth.calibrate.motion_fit.continuum`): the best
  point run at 2h and h/2 (h/4 if the orders disagree), the residual extrapolated by
  Richardson, Gauss–Newton steps to it;
- ``refit ladder``: a full fit at h and another at h/2, their values extrapolated by
  Richardson at order 2, σ_mesh the correction (the obvious alternative).

For each: the values, σ_noise and σ_mesh, the error in σ_total, the status and the wall
(with its ratio to ``at h``). The records:

- ``swing``: the bundled damped_swing_laser (0.625 mm run, γ 0.55, D1 0.025, σ 0.2 mm),
  fitted for γ and D1 under imex at auto's step;
- ``rotation``: the bundled impulsive_rotation_shapes (0.625 mm run, centre 4.0 mm,
  γ 0.8, σ 0.3 mm, clock 4 ms late), fitted for γ and the centre with --align-start 0.01;
- ``rotation3``: issue 34's rotation (0.625 mm run, centre 2.8 mm, γ 0.4, D1 0.05,
  σ 0.1 mm, markers s = 10 … 90 mm), fitted for γ, the centre and D1;
- ``sheet`` (``--sheet``, about a minute a spacing): the bundled shear_swing_markers
  (1.25 mm run, G 1.2, σ 0.02 mm), fitted for G.

    python benchmarks/continuum_fit.py [--cases swing rotation rotation3] [--spacings 5 2.5 1.25] [--sheet]
"""

from __future__ import annotations

import argparse
import copy
import math
import platform
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from conftest import SPACING_TRUTH, fine_rotation_markers  # noqa: E402

from warpcloth.calibrate.motion_fit import fit_motion, free_parameters  # noqa: E402
from warpcloth.calibrate.motion_fit.sheet import sheet_free_parameters  # noqa: E402
from warpcloth.io.measured import TrackedShapes, read_measurement, read_sheet_markers  # noqa: E402
from warpcloth.scene import read_scene_file, scene_from_dict, set_field  # noqa: E402
from warpcloth.scene.sheet import sheet_scene_from_dict  # noqa: E402

IMEX = {"integrator.scheme": "imex", "integrator.dt_s": "auto"}


def case(name: str):
    """(scene data, measurement, free names, truth, fit options, spacing fields) of a record."""
    if name == "swing":
        truth = {"damping.gamma_per_s": 0.55, "material.hysteresis_d1_gf_cm_per_cm": 0.025}
        return "damped_swing", read_measurement("damped_swing_laser"), "gamma,D1", truth, {}, ["strip.spacing_mm"]
    if name == "rotation":
        truth = {"clamp.rotation_centre_dy_mm": 4.0, "damping.gamma_per_s": 0.8}
        options = {"align_start_s": 0.01}
        measured = read_measurement("impulsive_rotation_shapes")
        return "impulsive_rotation", measured, "gamma,rotation_centre_dy_mm", truth, options, ["strip.spacing_mm"]
    if name == "rotation3":
        markers = fine_rotation_markers(0.625)
        keep = (markers.s >= 0.01) & (markers.s <= 0.09)
        measured = TrackedShapes(*(getattr(markers, k)[keep] for k in ("frame", "t", "s", "x", "y")))
        return "impulsive_rotation", measured, "gamma,rotation_centre_dy_mm,D1", SPACING_TRUTH, {}, ["strip.spacing_mm"]
    truth = {"shear.rigidity_gf_per_cm_deg": 1.2}
    spacing = ["sheet.spacing_warp_mm", "sheet.spacing_weft_mm"]
    return "shear_swing", read_sheet_markers("shear_swing_markers"), "G", truth, {}, spacing


def fit_at(name: str, h: float, continuum: bool):
    """One fit of record ``name`` at spacing ``h`` mm, and its wall."""
    scene, measured, free_names, truth, options, spacing = case(name)
    base = read_scene_file(scene)
    sheet = name == "sheet"
    fields = {"run.duration_s": 0.3} if sheet else IMEX | ({"run.duration_s": 0.25} if name == "rotation3" else {})
    for key, value in fields.items():
        set_field(base, key, value)
    for key in spacing:
        set_field(base, key, h)
    if sheet:
        free = sheet_free_parameters(free_names, sheet_scene_from_dict(copy.deepcopy(base)))
    else:
        free = free_parameters(free_names, scene_from_dict(copy.deepcopy(base)))
    started = time.perf_counter()
    fit = fit_motion(base, measured, free, progress=False, continuum=continuum, **options)
    return fit, time.perf_counter() - started, truth


def row(method: str, h: float, fit: tuple, truth: dict, status: str, wall: float, base: float) -> str:
    """One method's line: each value with σ_noise, σ_mesh and its error; status and wall."""
    values, noise, mesh = fit
    cells = []
    for key, value in truth.items():
        total = math.hypot(noise[key], mesh.get(key, 0.0))
        cells.append(
            f"{key.split('.')[-1]} {values[key]:.5g} (σ_noise {noise[key]:.2g}, σ_mesh "
            + (f"{mesh[key]:.2g}" if key in mesh else "—")
            + f"; {(values[key] - value) / total:+.1f} σ_total, {(values[key] / value - 1) * 100:+.2f} %)"
        )
    return f"  {method:<13} h = {h:<5g} {'; '.join(cells)}; {status}, {wall:.1f} s ({wall / base:.2f}×)"


def main() -> None:
    """Fit each record at each spacing by the three methods and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["swing", "rotation", "rotation3"])
    parser.add_argument("--spacings", nargs="+", type=float, default=[5.0, 2.5, 1.25])
    parser.add_argument("--sheet", action="store_true", help="also the sheet, fitted at 10 mm")
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    runs = [(name, h) for name in args.cases for h in args.spacings] + ([("sheet", 10.0)] if args.sheet else [])
    fit_at("rotation", 5.0, continuum=False)  # loads every kernel before anything is timed
    for name, h in runs:
        print(f"{name}:")
        plain, base_wall, truth = fit_at(name, h, continuum=False)
        noise = plain.sigma
        print(row("at h", h, (plain.parameters, noise, {}), truth, plain.status, base_wall, base_wall))
        fit, wall, _ = fit_at(name, h, continuum=True)
        print(
            row("continuum", h, (fit.parameters, fit.sigma_noise, fit.sigma_mesh), truth, fit.status, wall, base_wall)
        )
        orders = ", ".join(f"{o['order']:.2f}" for o in fit.continuum.get("observed_orders", []))
        extra = f"{fit.continuum.get('runs')} runs, {fit.continuum.get('wall_time_s', 0):.1f} s"
        print(f"      observed orders {orders}; {extra}")
        half, half_wall, _ = fit_at(name, h / 2, continuum=False)
        ladder = {k: half.parameters[k] + (half.parameters[k] - plain.parameters[k]) / 3 for k in truth}
        mesh = {k: abs(ladder[k] - half.parameters[k]) for k in truth}
        print(row("refit ladder", h, (ladder, half.sigma, mesh), truth, half.status, base_wall + half_wall, base_wall))


if __name__ == "__main__":
    main()
