"""``warpcloth run``: simulate a scene into a run directory."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from warpcloth import bodies
from warpcloth.core.result import RunResult
from warpcloth.errors import DivergenceError
from warpcloth.metrics import swing_summary
from warpcloth.runs import simulate
from warpcloth.scene import Scene, bundled_scenes, load_scene

from .options import add_device, add_no_progress, add_overrides, add_overwrite, new_file, path_text


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``run``."""
    run_p = sub.add_parser("run", help="simulate a scene and write a run directory")
    run_p.add_argument("scene", help=f"scene file, or a bundled scene: {', '.join(bundled_scenes())}")
    run_p.add_argument("--out", type=path_text, help="run directory (default: runs/<scene name>)")
    add_overrides(run_p, "a scene field by dotted name, e.g. integrator.dt_s=1e-7")
    add_device(run_p)
    add_no_progress(run_p)
    run_p.add_argument("--usd", metavar="FILE", help="also export the run as a USD stage (.usd, .usda or .usdc)")
    add_overwrite(run_p, "--out, once the new run is complete")
    run_p.set_defaults(handler=run_scene)


def run_scene(args: argparse.Namespace) -> int:
    """Simulate one scene of either body into a run directory and print what its body
    reports of it (:mod:`warpcloth.bodies`' ``summary``)."""
    if args.usd:
        from warpcloth.viz.usd import check_stage_path

        check_stage_path(args.usd, "--usd")  # before the run, not after it
        new_file(args.usd, args.overwrite, "--usd")
    scene = load_scene(args.scene, args.overrides)
    body = bodies.of_scene(scene)
    if scene.integrator.dt_chosen_by == "auto":
        print(body("describe_step", scene))
    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    try:
        result = simulate(scene, device=args.device, out=out, progress=not args.no_progress, overwrite=args.overwrite)
    except DivergenceError as exc:
        raise DivergenceError(f"{exc}\nRecorded up to the divergence: {out}", exc.diverged, exc.result) from None
    print(f"wrote {out}/ ({', '.join(sorted(p.name for p in out.iterdir()))})")
    for line in body("summary", scene, result):
        print(line)
    warning = result.memory_warning()
    if warning:
        print(f"warpcloth run: warning: {warning}", file=sys.stderr)
    if args.usd:
        print(f"wrote {body('export_usd', out, args.usd)}")
    return 0


def strip_summary(scene: Scene, result: RunResult) -> list[str]:
    """What ``run`` prints of a strip's run: its throughput, where its free end ended and
    its first period (as the sweep summary and ``warpcloth analyse`` measure it)."""
    tip = result.probe("tip_x", 0)
    lines = [
        f"{result.strip_steps:.3g} strip-steps in {result.wall_time_s:.2f} s "
        f"({result.strip_steps / result.wall_time_s:.3g} strip-steps/s)",
        f"final free end ({tip[-1] * 1e3:.2f}, {result.probe('tip_y', 0)[-1] * 1e3:.2f}) mm, "
        f"clamp angle {result.probe('clamp_angle', 0)[-1]:.4f} rad",
    ]
    summary = swing_summary(result.t, result.probe("laser_x", 0), tip, starts_at_rest=True)
    if scene.release.enabled and summary["n_half_cycles"] >= 2:  # a released swing
        lines.append(
            f"first period {summary['first_period_s']:.4f} s, first amplitude "
            f"{summary['first_amplitude_m'] * 1e3:.2f} mm, mean log decrement {summary['mean_log_decrement']:.4f} "
            f"per half-cycle over {summary['n_half_cycles'] - 1} ratios of {summary['n_half_cycles']} "
            f"half-cycles ({summary['signal']}, turning points; the sweep "
            "summary and `warpcloth analyse` measure the same way)"
        )
    elif scene.release.enabled:
        lines.append(
            f"no first period: the record ({scene.run.duration_s:g} s after the release) holds "
            f"{summary['n_half_cycles']} half-cycle(s) of the {summary['signal']} signal; a period needs two "
            "(run longer: run.duration_s)"
        )
    return lines
