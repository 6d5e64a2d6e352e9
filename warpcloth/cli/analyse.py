"""``warpcloth analyse``: the swing metrics of measured traces, runs and sweeps, side by side."""

from __future__ import annotations

import argparse
from pathlib import Path

from .options import add_overwrite, finite, new_file

COLUMNS = (
    "source",
    "variant",
    "from_s",
    "to_s",
    "signal",
    "first_period_s",
    "first_period_u_s",
    "first_amplitude_mm",
    "mean_log_decrement",
    "n_half_cycles",
    "log_decrement",
)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``analyse``."""
    p = sub.add_parser(
        "analyse",
        help="first period (± its standard uncertainty for measured traces), amplitudes "
        "and decrements of measured traces, runs and sweeps, measured one way (the sweep summary's)",
    )
    p.add_argument(
        "inputs",
        nargs="+",
        metavar="INPUT",
        help="a measured laser trace 't_s, x_mm' (or a bundled one by name), a run directory or a sweep directory",
    )
    p.add_argument(
        "--in-motion",
        action="store_true",
        help="measured traces do not start at rest at their t = 0 (default: they start at the release)",
    )
    p.add_argument(
        "--from",
        dest="t_from",
        type=finite,
        metavar="S",
        help="compare from this time, s (default: the latest start among the inputs)",
    )
    p.add_argument(
        "--to",
        dest="t_to",
        type=finite,
        metavar="S",
        help="compare up to this time, s (default: the earliest end among the inputs: their overlap)",
    )
    p.add_argument("--csv", help="also write the table as CSV")
    add_overwrite(p, "--csv file")
    p.set_defaults(handler=analyse_command)


def analyse_command(args: argparse.Namespace) -> int:
    """Print (and optionally write) one row per measured trace and per run or sweep variant."""
    import pandas as pd

    from warpcloth.calibrate.analysis import analyse

    out = new_file(args.csv, args.overwrite, "--csv") if args.csv else None
    rows = analyse(args.inputs, starts_at_rest=not args.in_motion, t_from=args.t_from, t_to=args.t_to)
    table = pd.DataFrame(rows, columns=list(COLUMNS))
    table["variant"] = table["variant"].astype("Int64")  # empty for a measured trace
    shown = table.drop(columns="log_decrement")
    # a simulation's period has no uncertainty: blank, not NaN
    shown["first_period_u_s"] = [f"{u:.2g}" if pd.notna(u) else "" for u in shown["first_period_u_s"]]
    lower, upper = rows[0]["from_s"], rows[0]["to_s"]
    chosen = "chosen by --from/--to" if args.t_from is not None or args.t_to is not None else "the inputs' overlap"
    with pd.option_context("display.max_columns", None, "display.width", 180, "display.max_colwidth", 48):
        print(shown.to_string(index=False, float_format=lambda v: f"{v:.5g}"))
    print(f"every input measured on t = {lower:g} … {upper:g} s ({chosen})")
    if out is not None:
        from warpcloth.io.atomic import write_atomically

        write_atomically(Path(out), lambda p: table.to_csv(p, index=False))
        print(f"wrote {out}")
    return 0
