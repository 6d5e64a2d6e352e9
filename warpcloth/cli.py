"""Command line: ``warpcloth run | sweep | export-usd | plot | render`` (``--help`` on each)."""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from pathlib import Path

import warp as wp

from .analysis import first_period
from .errors import DivergenceError, SceneError
from .runner import simulate
from .scene import bundled_scenes, load_scene


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``warpcloth`` command; returns the exit status."""
    parser = argparse.ArgumentParser(prog="warpcloth", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    run_p = sub.add_parser("run", help="simulate a scene and write a run directory")
    run_p.add_argument("scene", help=f"scene file, or a bundled scene: {', '.join(bundled_scenes())}")
    run_p.add_argument("--out", help="run directory (default: runs/<scene name>)")
    run_p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene field by dotted name, e.g. integrator.dt_s=1e-7")
    run_p.add_argument("--device", default=None, help="cpu or cuda (default: Warp's preferred device)")
    run_p.add_argument("--no-progress", action="store_true", help="no progress bar")
    run_p.add_argument("--usd", metavar="FILE", help="also export the run as a USD stage (.usd, .usda or .usdc)")
    sweep_p = sub.add_parser("sweep", help="run (or resume) the [sweep] of a scene into a sweep directory")
    sweep_p.add_argument("scene", help="scene file with a [sweep] section, or a bundled one")
    sweep_p.add_argument("--out", help="sweep directory (default: runs/<scene name>); rerun to resume")
    sweep_p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                         help="override a field of the base scene")
    sweep_p.add_argument("--max-batch", type=int, default=None,
                         help="strips per batch (default: from the memory per strip and the worker count)")
    sweep_p.add_argument("--workers", type=int, default=None,
                         help="local Dask worker processes (default: one per core; 0 = run in this process)")
    sweep_p.add_argument("--scheduler", default=None, help="address of a running Dask scheduler to use instead")
    sweep_p.add_argument("--device", default=None, help="cpu or cuda, on every worker")
    sweep_p.add_argument("--frames", action="store_true", help="also store shape frames (large)")
    sweep_p.add_argument("--no-progress", action="store_true", help="no progress bar")
    _add_view_commands(sub)
    args = parser.parse_args(argv)
    wp.config.log_level = logging.WARNING  # no init banner or module-load lines

    if args.command == "sweep":
        return _sweep(args)
    if args.command in VIEW_COMMANDS:
        try:
            return VIEW_COMMANDS[args.command](args)
        except SceneError as exc:
            print(f"warpcloth {args.command}: {exc}", file=sys.stderr)
            return 2
    try:
        scene = load_scene(args.scene, args.overrides)
    except SceneError as exc:
        print(f"warpcloth: error in scene: {exc}", file=sys.stderr)
        return 2
    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    try:
        result = simulate(scene, device=args.device, out=out, progress=not args.no_progress)
    except DivergenceError as exc:
        print(f"warpcloth: {exc}\nRecorded up to the divergence: {out}", file=sys.stderr)
        return 3
    tip = result.probe("tip_x", 0)
    print(f"wrote {out}/ (probes.csv, frames.npy, frame_times.npy, scene.toml, meta.json)")
    print(f"{result.strip_steps:.3g} strip-steps in {result.wall_time_s:.2f} s "
          f"({result.strip_steps / result.wall_time_s:.3g} strip-steps/s)")
    print(f"final free end ({tip[-1] * 1e3:.2f}, {result.probe('tip_y', 0)[-1] * 1e3:.2f}) mm, "
          f"clamp angle {result.probe('clamp_angle', 0)[-1]:.4f} rad")
    if scene.release.enabled:
        period = first_period(result.t, result.probe("laser_x", 0), level=0.0)
        print(f"first swing period (laser line crossing x = 0): {period:.4f} s")
    if args.usd:
        from .recording import load_recording
        from .usd import export_usd

        print(f"wrote {export_usd(load_recording(out), args.usd)}")
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from .sweep import load_sweep
    from .sweep_runner import run_sweep

    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    try:
        sweep = load_sweep(args.scene, args.overrides)
        summary = run_sweep(sweep, out, max_batch=args.max_batch, workers=args.workers, scheduler=args.scheduler,
                            device=args.device, frames=args.frames, progress=not args.no_progress)
    except SceneError as exc:
        print(f"warpcloth: error in sweep: {exc}", file=sys.stderr)
        return 2
    n_div = int(summary["diverged"].sum())
    print(f"wrote {out}/ ({len(summary)} variants: summary.csv, summary.parquet, probes/, variants.csv); "
          f"{n_div} diverged")
    return 0


def _add_view_commands(sub: argparse._SubParsersAction) -> None:
    def selection(p: argparse.ArgumentParser) -> None:
        p.add_argument("run_dir", metavar="RUN_DIR", help="a run directory, or a sweep directory run with --frames")
        p.add_argument("--variants", help="which variants: 3, 1,4,9 or 0:50 (default: all)")
        p.add_argument("--where", help="parameter filter: 'field OP value[,...]', e.g. 'damping.gamma_per_s<0.5'")

    usd_p = sub.add_parser("export-usd", help="write a run (or sweep variants) as an animated USD stage")
    selection(usd_p)
    usd_p.add_argument("-o", "--output", required=True, help="stage file: .usd or .usdc (binary), .usda (text)")
    usd_p.add_argument("--ribbon", action="store_true", help="also write each strip as a mesh of its real width")
    usd_p.add_argument("--frames-per-clip", type=int, default=None,
                       help="split frames into value-clip layers of this many frames (default: only when large)")
    plot_p = sub.add_parser("plot", help="PNG figures of a run, or a sweep metric against parameters")
    selection(plot_p)
    plot_p.add_argument("--out", help="figure directory (default: RUN_DIR/figures)")
    plot_p.add_argument("--measured", help="CSV of a measured displacement: t (s), x (mm); overlaid on amplitude.png")
    plot_p.add_argument("--times", type=float, nargs="+", help="shape-overlay times, s after release")
    plot_p.add_argument("--metric", help="sweep: summary column to plot (e.g. first_period_s)")
    plot_p.add_argument("--x", help="sweep: parameter on the x axis (a swept field, e.g. damping.gamma_per_s)")
    plot_p.add_argument("--y", help="sweep: second parameter (heat map)")
    render_p = sub.add_parser("render", help="3D PNG frames and an animation of a run (pyvista, off screen)")
    selection(render_p)
    render_p.add_argument("--out", help="image directory (default: RUN_DIR/render)")
    render_p.add_argument("--times", type=float, nargs="+", help="times of the PNG frames, s after release")
    render_p.add_argument("--movie", default="motion.gif", help="animation file name, .gif or .mp4; 'none' for none")
    render_p.add_argument("--stride", type=int, default=1, help="animate every n-th frame (at real speed)")


def _export_usd(args: argparse.Namespace) -> int:
    from .recording import load_recording
    from .usd import export_usd

    recording = load_recording(args.run_dir, args.variants, args.where)
    out = export_usd(recording, args.output, ribbon=args.ribbon, frames_per_clip=args.frames_per_clip)
    print(f"wrote {out} ({len(recording.variants)} variants, {len(recording.frame_times)} frames)")
    return 0


def _plot(args: argparse.Namespace) -> int:
    from .plots import plot_run, plot_sweep, read_sweep_summary
    from .recording import load_recording

    out = Path(args.out or Path(args.run_dir) / "figures")
    if args.metric or args.x:
        if not (args.metric and args.x):
            raise SceneError("--metric", "a sweep plot needs both --metric and --x")
        out.mkdir(parents=True, exist_ok=True)
        name = f"{args.metric}_vs_{args.x}" + (f"_{args.y}" if args.y else "")
        path = plot_sweep(read_sweep_summary(args.run_dir), out / f"{name}.png", args.metric, args.x, args.y)
        print(f"wrote {path}")
        return 0
    recording = load_recording(args.run_dir, args.variants, args.where)
    for path in plot_run(recording, out, measured=args.measured, times=args.times):
        print(f"wrote {path}")
    return 0


def _render(args: argparse.Namespace) -> int:
    from .recording import load_recording
    from .render import render_run

    recording = load_recording(args.run_dir, args.variants, args.where)
    movie = None if args.movie == "none" else args.movie
    out = Path(args.out or Path(args.run_dir) / "render")
    for path in render_run(recording, out, times=args.times, movie=movie, stride=args.stride):
        print(f"wrote {path}")
    return 0


VIEW_COMMANDS = {"export-usd": _export_usd, "plot": _plot, "render": _render}


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
