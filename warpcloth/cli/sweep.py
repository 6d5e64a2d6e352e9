"""``warpcloth sweep``: run or resume the [sweep] of a scene."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from warpcloth.scene import Sweep

from warpcloth.io import PROBE_RECORDS

from .options import add_device, add_no_progress, add_overrides, at_least, path_text


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``sweep``."""
    sweep_p = sub.add_parser("sweep", help="run (or resume) the [sweep] of a scene into a sweep directory")
    sweep_p.add_argument("scene", help="scene file with a [sweep] section, or a bundled one")
    sweep_p.add_argument("--out", type=path_text, help="sweep directory (default: runs/<scene name>); rerun to resume")
    add_overrides(sweep_p, "a field of the base scene")
    sweep_p.add_argument(
        "--max-batch",
        type=at_least(1),
        default=None,
        help="strips (or sheets) per batch (default: from the memory per variant and the worker count)",
    )
    sweep_p.add_argument(
        "--workers",
        type=at_least(0),
        default=None,
        help="threads running batches side by side in this process (default: one per core; 0 = one "
        "batch after another)",
    )
    sweep_p.add_argument(
        "--scheduler",
        default=None,
        help="address of a running Dask scheduler to use instead (default: none, threads in this process)",
    )
    add_device(sweep_p, ", on every worker (checked here unless --scheduler names a cluster)", elsewhere=True)
    sweep_p.add_argument("--frames", action="store_true", help="also store shape frames (large)")
    sweep_p.add_argument(
        "--probes",
        choices=list(PROBE_RECORDS),
        default="summary",
        help="what to keep of each variant's probe series: "
        + "; ".join(f"{name}: {what}" for name, what in PROBE_RECORDS.items())
        + " (default: summary)",
    )
    sweep_p.add_argument(
        "--max-variants",
        type=at_least(1),
        default=None,
        help="refuse a sweep of more variants than this (default: 100000)",
    )
    add_no_progress(sweep_p)
    sweep_p.set_defaults(handler=run_sweep_command)


def strip_sweep_steps(sweep: Sweep) -> list[str]:
    """The step each scheme and probe interval of a strip sweep runs at, where ``dt_s = "auto"`` chose it."""
    from warpcloth.scene.step import choose_step, requesting_auto

    groups: dict[tuple[str, float], list] = {}  # one step per scheme and probe interval
    for s in sweep.scenes:
        if s.integrator.dt_chosen_by == "auto":
            groups.setdefault((s.integrator.scheme, s.output_interval), []).append(s)
    return [
        choose_step(requesting_auto(chosen))
        .describe()
        .replace(
            "auto:",
            f"auto, for the {len(chosen)} {scheme} variants:"
            if len(groups) > 1
            else f"auto, for all {len(chosen)} variants:",
            1,
        )
        for (scheme, _), chosen in groups.items()
    ]


def strip_sweep_warnings(summary: object) -> list[str]:
    """What a strip sweep warns of beyond its last line: nothing (a diverged strip's metrics
    are measured on what it recorded, and the summary says when it diverged)."""
    return []


def run_sweep_command(args: argparse.Namespace) -> int:
    """Expand the sweep, run its missing batches, report the summary."""
    from warpcloth import bodies
    from warpcloth.io.writing import claim_result
    from warpcloth.scene.sweep import MAX_VARIANTS, load_sweep
    from warpcloth.strip.model import machine_device
    from warpcloth.sweeps import run_sweep

    out = Path(args.out or Path("runs") / Path(args.scene).stem)
    if args.scheduler is None:
        # the batches run in this process: its machine must have the device
        machine_device(args.device)
    sweep = load_sweep(
        args.scene, args.overrides, max_variants=args.max_variants or MAX_VARIANTS, progress=not args.no_progress
    )
    body = bodies.named(sweep.kind)
    for line in body("sweep_steps", sweep):
        print(line)
    # claimed as --out here, so a sweep another process is writing is refused naming the option
    claim_result(out, "--out")
    summary = run_sweep(
        sweep,
        out,
        max_batch=args.max_batch,
        workers=args.workers,
        scheduler=args.scheduler,
        device=args.device,
        frames=args.frames,
        probes=args.probes,
        progress=not args.no_progress,
    )
    n_div = int(summary["diverged"].sum())
    for line in body("sweep_warnings", summary):
        print(f"warpcloth sweep: warning: {line}", file=sys.stderr)
    evenness = (
        ""
        if sweep.discrepancy is None
        else f"; its random sample's centred L2 discrepancy is {sweep.discrepancy:.3g} (lower is more even)"
    )
    stored = ["summary.csv", "summary.parquet"]
    stored += [] if args.probes == "none" else [f"probes/ ({args.probes})"]
    stored += ["frames/"] if args.frames else []
    print(f"wrote {out}/ ({len(summary)} variants: {', '.join([*stored, 'variants.csv'])}); {n_div} diverged{evenness}")
    if "reversal_overflows" in summary and summary["reversal_overflows"].fillna(0).any():
        full = summary.loc[summary["reversal_overflows"].fillna(0) > 0, "variant"].tolist()
        print(
            f"warpcloth sweep: warning: the masing reversal memory was full in {len(full)} variant(s) "
            f"({', '.join(map(str, full[:8]))}{' …' if len(full) > 8 else ''}; summary column reversal_overflows): "
            "their inner loops were traced without hysteresis; raise integrator.reversal_memory",
            file=sys.stderr,
        )
    return 0
