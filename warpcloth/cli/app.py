"""The ``warpcloth`` command: a registry of command groups and the one error boundary.

Exit codes: 0 done; 2 the input is unusable (a scene field, a data file or an option,
named in the message); 3 a run diverged (what was recorded before it is kept).
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

import warp as wp

from warpcloth.errors import DataFileError, DivergenceError, OptionError, SceneError, WarpclothError

from . import fit, material, run, sweep, view

COMMAND_GROUPS = (run, sweep, view, fit, material)
"""Each registers its subcommands with a ``handler`` (see :func:`main`)."""

EXIT_CODES = {SceneError: 2, DataFileError: 2, OptionError: 2, DivergenceError: 3}
WHAT = {SceneError: "error in scene", DataFileError: "error in data file", OptionError: "error in option"}


def parser() -> argparse.ArgumentParser:
    """The argument parser of every command."""
    top = argparse.ArgumentParser(
        prog="warpcloth", description="Batched Warp simulation of hanging fabric strips: "
        "run | sweep | export-usd | plot | render | fit | clamp | material (--help on each).")
    sub = top.add_subparsers(dest="command", required=True)
    for group in COMMAND_GROUPS:
        group.register(sub)
    return top


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``warpcloth`` command; returns the exit status."""
    args = parser().parse_args(argv)
    wp.config.log_level = logging.WARNING  # no init banner or module-load lines
    try:
        return args.handler(args)
    except DivergenceError as exc:
        print(f"warpcloth {args.command}: {exc}", file=sys.stderr)
        return EXIT_CODES[DivergenceError]
    except WarpclothError as exc:
        kind = type(exc)
        print(f"warpcloth {args.command}: {WHAT.get(kind, 'error')}: {exc}", file=sys.stderr)
        return EXIT_CODES.get(kind, 2)
