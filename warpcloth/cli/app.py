"""The ``warpcloth`` command: a registry of command groups and the one error boundary.

Exit codes: 0 done; 2 the input is unusable (a scene field, a data file or an option,
named in the message, or work too large for this machine's free memory or disk, with
what to change); 3 a run diverged (what was recorded before it is kept); 4 a fit
ended on a bound (written, but not a fit); 5 a file could not be read or written (full
disk, file-size limit, permissions: what was committed before is kept); 130 interrupted
(Ctrl-C: what was written is kept).
"""

from __future__ import annotations

import argparse
import errno
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from warpcloth.errors import (
    ArgumentError,
    DataFileError,
    DivergenceError,
    EnvironmentSettingError,
    LongRunWarning,
    OptionError,
    PlausibilityWarning,
    ResourceError,
    SceneError,
    WarpclothError,
)
from warpcloth.kernels.exp_lanes import requested_width
from warpcloth.kernels.law import LawRegistryError
from warpcloth.strip.model import init_warp_quietly

from . import analyse, fit, material, run, scene, sweep, track, view
from .flags import as_option
from .interrupt import EXIT_INTERRUPTED, EXIT_UNUSABLE_INPUT, interrupted_at_start

COMMAND_GROUPS = (run, sweep, view, fit, material, analyse, scene, track)
"""Each registers its subcommands with a ``handler`` (see :func:`main`)."""

WHAT = (
    (SceneError, "error in scene"),
    (DataFileError, "error in data file"),
    (OptionError, "error in option"),
    (EnvironmentSettingError, "error in environment variable"),
    (ResourceError, "too large"),
)
EXIT_DIVERGED = 3
STREAMING = ("run", "sweep")
"""Commands whose results stream to disk (the rest write each file whole, atomically)."""
EXIT_IO = 5
FULL = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)


def _version() -> str:
    import importlib.metadata

    try:
        return importlib.metadata.version("warpcloth")
    except importlib.metadata.PackageNotFoundError:
        return "(not installed)"


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose refusal is one line, as every other error of warpcloth's
    is (argparse prints its whole usage first: 17 lines for ``warpcloth track``); its
    subcommands' parsers are of the same class."""

    def error(self, message: str) -> NoReturn:
        """Print ``PROG: error: MESSAGE (PROG --help lists the options)`` and exit 2."""
        self.exit(2, f"{self.prog}: error: {message} ({self.prog} --help lists the options)\n")


def parser() -> argparse.ArgumentParser:
    """The argument parser of every command."""
    top = OneLineParser(
        prog="warpcloth",
        description="Batched Warp simulation of hanging fabric strips: "
        "run | sweep | export-usd | plot | render | fit | clamp | material | analyse | scene | track (--help on each).",
    )
    top.add_argument("--version", action="version", version=f"warpcloth {_version()}")
    top.add_argument("--verbose", action="store_true", help="let Warp print its banner, module loads and CUDA notices")
    sub = top.add_subparsers(dest="command", required=True)
    for group in COMMAND_GROUPS:
        group.register(sub)
    return top


def show_warnings_as_lines(command: str) -> None:
    """Print each :class:`~warpcloth.errors.PlausibilityWarning` and
    :class:`~warpcloth.errors.LongRunWarning` as one line
    ``warpcloth COMMAND: warning: ...`` (no source line), each text once; NumPy's
    RuntimeWarnings are not shown."""

    def show(message: Warning | str, category: type[Warning], *_: object, **__: object) -> None:
        if issubclass(category, PlausibilityWarning | LongRunWarning):
            if str(message) not in seen:
                seen.add(str(message))
                print(f"warpcloth {command}: warning: {message}", file=sys.stderr)
        else:
            shown(message, category, *_, **__)

    seen: set[str] = set()
    # NumPy's overflow notices are not for the user: every number warpcloth reports or
    # writes is checked finite, and a non-finite one is an error that says so
    warnings.simplefilter("ignore", RuntimeWarning)
    shown = warnings.showwarning
    warnings.showwarning = show


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``warpcloth`` command; returns the exit status."""
    argv = track.route(sys.argv[1:] if argv is None else argv)
    try:
        init_warp_quietly(verbose="--verbose" in argv)  # before parsing: a --device option starts Warp
        args = parser().parse_args(argv)
    except KeyboardInterrupt:
        return interrupted_at_start()
    show_warnings_as_lines(args.command)
    try:
        return _run_handler(args)
    finally:
        from warpcloth.io.writing import release_claims

        release_claims()  # the command is over: a later one in this process may write there


def _run_handler(args: argparse.Namespace) -> int:
    # the command, its failures mapped to one line and an exit status each
    try:
        requested_width()  # a bad WARPCLOTH_EXP_LANES is refused before any command starts
        return args.handler(args)
    except DivergenceError as exc:
        print(f"warpcloth {args.command}: {exc}", file=sys.stderr)
        return EXIT_DIVERGED
    except LawRegistryError as exc:  # a law's fitter, loaded when first needed
        print(f"warpcloth {args.command}: {exc}", file=sys.stderr)
        return EXIT_UNUSABLE_INPUT
    except WarpclothError as exc:
        if isinstance(exc, ArgumentError):
            exc = as_option(exc)  # the library names its argument; the user typed an option
        what = next((text for kind, text in WHAT if isinstance(exc, kind)), "error")
        print(f"warpcloth {args.command}: {what}: {exc}", file=sys.stderr)
        return EXIT_UNUSABLE_INPUT
    except KeyboardInterrupt:
        # Everything finished so far is on disk; an interrupted run directory says
        # "complete": false in its meta.json, a sweep resumes from its finished batches.
        if args.command in STREAMING:
            out = getattr(args, "out", None)
            where = f" in {out}" if out else ""
            print(
                f"warpcloth {args.command}: interrupted; what was written so far is kept{where} and marked incomplete",
                file=sys.stderr,
            )
        else:
            print(
                f"warpcloth {args.command}: interrupted; its files are written whole or not at all, so nothing "
                "was replaced or left half-written",
                file=sys.stderr,
            )
        return EXIT_INTERRUPTED
    except OSError as exc:
        # a file that cannot be read or written (missing directory, no permission, full disk)
        where = f": {exc.filename}" if exc.filename else ""
        advice = (
            "; free space (or raise the file-size limit) and rerun: what was committed before is kept, "
            "an unfinished run is marked incomplete"
            if exc.errno in FULL
            else ""
        )
        print(f"warpcloth {args.command}: I/O error: {exc.strerror or exc}{where}{advice}", file=sys.stderr)
        return EXIT_IO
