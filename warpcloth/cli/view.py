"""``warpcloth export-usd | plot | render``: look at a run or at sweep variants."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from warpcloth import bodies
from warpcloth.errors import OptionError
from warpcloth.viz import DPI, FORMATS

from .flags import flag_of
from .options import add_overwrite, at_least, finite, new_file, new_result, path_text, positive


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``export-usd``, ``plot`` and ``render``."""

    def selection(p: argparse.ArgumentParser) -> None:
        p.add_argument(
            "run_dir",
            metavar="RUN_DIR",
            help="a run directory (a strip's or a sheet's), or a sweep directory run with --frames",
        )
        p.add_argument("--variants", help="which variants: 3, 1,4,9 or 0:50 (default: all)")
        p.add_argument("--where", help="parameter filter: 'field OP value[,...]', e.g. 'damping.gamma_per_s<0.5'")

    usd_p = sub.add_parser("export-usd", help="write a run (or sweep variants) as an animated USD stage")
    selection(usd_p)
    usd_p.add_argument(
        "-o", "--output", type=path_text, required=True, help="stage file: .usd or .usdc (binary), .usda (text)"
    )
    usd_p.add_argument("--ribbon", action="store_true", help="also write each strip as a mesh of its real width")
    usd_p.set_defaults(handler=export_usd_command)
    add_overwrite(usd_p, "stage -o")
    usd_p.add_argument(
        "--frames-per-clip",
        type=at_least(1),
        default=None,
        help="split frames into value-clip layers of this many frames (default: only when large)",
    )
    plot_p = sub.add_parser("plot", help="figures of a run, or a sweep metric against parameters")
    selection(plot_p)
    plot_p.set_defaults(handler=plot_command)
    plot_p.add_argument("--out", type=path_text, help="figure directory (default: RUN_DIR/figures)")
    add_overwrite(plot_p, "figure directory --out")
    plot_p.add_argument(
        "--measured",
        help="a measured CSV, drawn on the figure of its kind: a laser trace (t, x) on "
        "amplitude, a clamp encoder (t, theta: column 2 headed theta/angle) on clamp_angle, tracked "
        "markers (frame, t, s, x, y) on shapes",
    )
    plot_p.add_argument(
        "--from",
        dest="t_from",
        type=finite,
        metavar="S",
        help="draw the time series (and a "
        "--measured trace or encoder) from this time, s (default: the start of their overlap)",
    )
    plot_p.add_argument(
        "--to", dest="t_to", type=finite, metavar="S", help="…up to this time, s (default: the end of their overlap)"
    )
    plot_p.add_argument("--format", choices=FORMATS, default="png", help="figure file format (default: png)")
    plot_p.add_argument("--dpi", type=positive, default=DPI, help=f"resolution of raster output (default: {DPI})")
    plot_p.add_argument(
        "--times",
        type=finite,
        nargs="+",
        help="shape-overlay times, s from t = 0 (the release, "
        "or the start of the clamp motion) (default: nine over the first half swing)",
    )
    plot_p.add_argument("--metric", help="sweep: summary column to plot (e.g. first_period_s)")
    plot_p.add_argument("--x", help="sweep: parameter on the x axis (a swept field, e.g. damping.gamma_per_s)")
    plot_p.add_argument("--y", help="sweep: second parameter (heat map)")
    render_p = sub.add_parser("render", help="3D PNG frames and an animation of a run (pyvista, off screen)")
    selection(render_p)
    render_p.set_defaults(handler=render_command)
    render_p.add_argument("--out", type=path_text, help="image directory (default: RUN_DIR/render)")
    add_overwrite(render_p, "image directory --out")
    render_p.add_argument(
        "--times",
        type=finite,
        nargs="+",
        help="times of the PNG frames, s from t = 0 (the "
        "release, or the start of the clamp motion) (default: six spread over the run)",
    )
    render_p.add_argument(
        "--movie", default="motion.gif", help="animation file name, .gif or .mp4; 'none' for none (default: motion.gif)"
    )
    render_p.add_argument(
        "--stride", type=at_least(1), default=1, help="animate every n-th frame, at real speed (default: 1)"
    )


def export_usd_command(args: argparse.Namespace) -> int:
    """Write a run as an animated USD stage (its body's way: :mod:`warpcloth.bodies`)."""
    return bodies.of_run(args.run_dir)("usd_command", args)


def strip_usd_command(args: argparse.Namespace) -> int:
    """``export-usd`` of a strip's run or a sweep: the selected variants as curves."""
    from warpcloth.io.load import load_recording
    from warpcloth.viz.usd import export_usd

    recording = load_recording(args.run_dir, args.variants, args.where)
    out = export_usd(
        recording,
        new_file(args.output, args.overwrite, "-o"),
        ribbon=args.ribbon,
        frames_per_clip=args.frames_per_clip,
    )
    print(f"wrote {out} ({len(recording.variants)} variants, {len(recording.frame_times)} frames)")
    return 0


def plot_command(args: argparse.Namespace) -> int:
    """Figures of a run, or one sweep metric against parameters (its body's way)."""
    return bodies.of_run(args.run_dir)("plot_command", args)


def strip_plot_command(args: argparse.Namespace) -> int:
    """``plot`` of a strip's run, or one sweep metric against parameters."""
    from warpcloth.io.load import load_recording
    from warpcloth.io.recording import select_summary_rows
    from warpcloth.viz.plots import plot_run, plot_sweep, read_sweep_summary

    out = new_result(args.out or Path(args.run_dir) / "figures", args.overwrite, "--out")
    if args.metric or args.x:
        if not (args.metric and args.x):
            raise OptionError("--metric", "a sweep plot needs both --metric and --x")
        name = f"{args.metric}_vs_{args.x}" + (f"_{args.y}" if args.y else "")
        summary = read_sweep_summary(args.run_dir)
        total = json.loads((Path(args.run_dir) / "sweep.json").read_text())["n_variants"]
        chosen = select_summary_rows(summary, args.variants, args.where, total)
        out.mkdir(parents=True, exist_ok=True)
        path = plot_sweep(chosen, out / f"{name}.{args.format}", args.metric, args.x, args.y, dpi=args.dpi)
        print(f"wrote {path}" + (f" ({len(chosen)} of the variants)" if len(chosen) < len(summary) else ""))
        if len(summary) < total:
            print(
                f"note: the sweep has not finished: the figure shows the {len(summary)} of its {total} variants "
                "done so far (run the sweep again to complete it)"
            )
        return 0
    recording = load_recording(args.run_dir, args.variants, args.where)
    for path in plot_run(
        recording,
        out,
        measured=args.measured,
        times=args.times,
        kes=material_kes_values(recording),
        fmt=args.format,
        dpi=args.dpi,
        t_from=args.t_from,
        t_to=args.t_to,
    ):
        print(f"wrote {path}")
    return 0


def material_kes_values(recording: object, variant: int = 0) -> object:
    """B and 2HB a KES-FB2 would read off the first variant's material loop (±K0)."""
    import numpy as np

    from warpcloth import units
    from warpcloth.calibrate.kes import BendingLoop, bending_summary
    from warpcloth.viz.plots import kes_loop

    k, m = kes_loop(recording, variant)
    return bending_summary(
        BendingLoop(
            k / units.CURVATURE_PER_CM,
            m / units.MOMENT_GF_CM_PER_CM,
            np.arange(1, len(k) + 1),
            "the material's KES-FB2 loop",
        )
    )


def render_command(args: argparse.Namespace) -> int:
    """Off-screen 3D PNG frames and an animation (its body's way)."""
    for path in bodies.of_run(args.run_dir)("render", args):
        print(f"wrote {path}")
    return 0


def render_target(args: argparse.Namespace) -> tuple[Path, str | None]:
    """Where ``render`` writes (``--out``, made new) and the animation it was asked for."""
    out = new_result(args.out or Path(args.run_dir) / "render", args.overwrite, "--out")
    return out, None if args.movie == "none" else args.movie


def strip_render(args: argparse.Namespace) -> list[Path]:
    """``render`` of a strip's run: the selected variants' frames."""
    from warpcloth.io.load import load_recording
    from warpcloth.viz.render import render_run

    recording = load_recording(args.run_dir, args.variants, args.where)
    out, movie = render_target(args)
    return render_run(recording, out, times=args.times, movie=movie, stride=args.stride)


def refuse_strip_options(args: argparse.Namespace, names: tuple[str, ...]) -> None:
    """An OptionError naming the first of the options ``names`` (argparse destinations) that
    was given: they select or draw a strip's run or a sweep, and RUN_DIR is a sheet run."""
    given = [name for name in names if getattr(args, name) not in (None, False)]
    if given:
        raise OptionError(
            flag_of(given[0]),
            f"is for a strip's run or a sweep; {args.run_dir} is a sheet run (docs/guide.md, Woven sheets)",
        )
