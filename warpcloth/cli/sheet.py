"""What the command line does with a sheet: the lines ``run`` and ``sweep`` print of it and
how ``plot``, ``render`` and ``export-usd`` draw its run directory (the sheet's hooks in
:mod:`warpcloth.bodies`; the strip's are beside their commands)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from warpcloth.core.result import RunResult
from warpcloth.runs import sheet_result_metrics
from warpcloth.scene.sheet import SheetScene
from warpcloth.scene.sweep import Sweep

from .options import new_file, new_result
from .view import refuse_strip_options, render_target


def sheet_summary(scene: SheetScene, result: RunResult) -> list[str]:
    """What ``run`` prints of a sheet run (:func:`~warpcloth.metrics.sheet_metrics`, as a
    sheet sweep's summary holds it): its throughput; each marker's peak displacement from
    its start, sideways (z) and out of the plane (x), in mm; the probed cell's peak shear
    angle (°); the energy budget's largest drift against the work the clamp did."""
    metrics = sheet_result_metrics(scene, result, 0)
    lines = [
        f"{result.node_steps:.3g} node-steps in {result.wall_time_s:.2f} s "
        f"({result.node_steps / result.wall_time_s:.3g} node-steps/s)"
    ]
    start = result.markers[0, 0]
    for k in range(result.markers.shape[2]):
        m = {name: metrics[f"marker_{k}_{name}"] for name in ("peak_z_mm", "peak_z_against_clamp_mm", "peak_x_mm")}
        lines.append(
            f"marker {k} (at y = {round(start[k, 1] * 1e3, 1) + 0.0:.1f} mm, "
            f"z = {round(start[k, 2] * 1e3, 1) + 0.0:.1f} mm at t = 0): "
            f"peak sideways (z) {m['peak_z_mm']:.3f} mm ({m['peak_z_against_clamp_mm']:.3f} mm against the "
            f"clamp), out of plane (x) {m['peak_x_mm']:.3f} mm"
        )
    lines.append(f"probed cell: peak shear angle {metrics['peak_shear_angle_deg']:.4f}°")
    drift, relative = metrics["energy_drift_J"], metrics["energy_drift_relative"]
    scale = float(np.nanmax(np.abs(result.probe("drive_work", 0))))
    part = f" ({relative:.2g} of the clamp's work {scale:.3g} J)" if np.isfinite(relative) else ""
    lines.append(f"energy budget: largest drift {drift:.3g} J{part}")
    return lines


def sheet_usd_command(args: argparse.Namespace) -> int:
    """``export-usd`` of a sheet run: the sheet as an animated mesh."""
    from warpcloth.io.sheet_run_dir import read_sheet_run
    from warpcloth.viz.usd import export_sheet_usd

    refuse_strip_options(args, ("variants", "where", "ribbon", "frames_per_clip"))
    run = read_sheet_run(args.run_dir)
    out = export_sheet_usd(run, new_file(args.output, args.overwrite, "-o"))
    print(f"wrote {out} (a sheet of {run.meta['n_nodes']} nodes, {len(run.frame_times)} frames)")
    return 0


def sheet_plot_command(args: argparse.Namespace) -> int:
    """``plot`` of a sheet run: its markers, shear and energy figures."""
    from warpcloth.io.sheet_run_dir import read_sheet_run
    from warpcloth.viz.figures.sheet import SheetSetting, plot_sheet_run

    refuse_strip_options(args, ("variants", "where", "measured", "t_from", "t_to", "times", "metric", "x", "y"))
    out = new_result(args.out or Path(args.run_dir) / "figures", args.overwrite, "--out")
    run = read_sheet_run(args.run_dir)
    setting = SheetSetting.of_scene(run.scene, run.path.resolve().name, run.rest_positions)
    for path in plot_sheet_run(run.samples(), setting, out, fmt=args.format, dpi=args.dpi):
        print(f"wrote {path}")
    return 0


def sheet_render(args: argparse.Namespace) -> list[Path]:
    """``render`` of a sheet run: the sheet's mesh."""
    from warpcloth.io.sheet_run_dir import read_sheet_run
    from warpcloth.viz.render import render_sheet_run

    refuse_strip_options(args, ("variants", "where"))
    run = read_sheet_run(args.run_dir)
    out, movie = render_target(args)
    return render_sheet_run(run, out, times=args.times, movie=movie, stride=args.stride)


def sheet_sweep_steps(sweep: Sweep) -> list[str]:
    """The step each group of a sheet sweep's variants runs at, where ``dt_s = "auto"`` chose it."""
    from warpcloth.scene.sheet import AUTO_FRACTION

    steps: dict[float, int] = {}
    for scene in sweep.scenes:
        if scene.integrator.dt_chosen_by == "auto":
            steps[scene.integrator.dt_s] = steps.get(scene.integrator.dt_s, 0) + 1
    return [
        f"integrator.dt_s = auto, for {count} of the {len(sweep.scenes)} variants: {dt:.4e} s (the shortest "
        f"of theirs: {AUTO_FRACTION:g} of the variant's linearised stability estimate, a whole fraction of "
        "the probe interval)"
        for dt, count in sorted(steps.items())
    ]


def sheet_sweep_warnings(summary: object) -> list[str]:
    """What a sheet sweep warns of: diverged variants, whose metrics are NaN."""
    gone = summary.loc[summary["diverged"], "variant"].tolist()
    if not gone:
        return []
    return [
        f"{len(gone)} sheet variant(s) diverged ({', '.join(map(str, gone[:8]))}"
        f"{' …' if len(gone) > 8 else ''}); their metrics in the summary are NaN, and diverged_time_s, "
        "diverged_phase and diverged_quantity say when and how"
    ]
