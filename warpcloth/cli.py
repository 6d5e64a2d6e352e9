"""Command line: ``warpcloth run SCENE [--out DIR] [--set key=value ...] [--device cpu|cuda]``."""

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
    args = parser.parse_args(argv)
    wp.config.log_level = logging.WARNING  # no init banner or module-load lines

    if args.command == "sweep":
        return _sweep(args)
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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
