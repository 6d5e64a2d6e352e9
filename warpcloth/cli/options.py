"""Option types shared by the command groups: checked when the command line is parsed,
before anything runs."""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from pathlib import Path

from warpcloth.errors import ArgumentError, OptionError

EXIT_FIT_STATUS = {
    "converged": 0,
    "at_bound": 4,
    "poor_fit": 6,
    "not_identifiable": 7,
    "failed": 8,
    "spacing_limited": 9,
    "mesh_dependent": 10,
}
"""Exit status of a fit by its verdict: only ``converged`` is 0; every other result is
written (to look at) but must not be read as a fit."""


def device(value: str) -> str:
    """``--device``: a Warp device of this machine (checked before anything runs)."""
    from warpcloth.strip.model import machine_device

    try:
        machine_device(value)
    except ArgumentError as exc:
        raise argparse.ArgumentTypeError(exc.message) from None
    return value


DEVICE_NAME = re.compile(r"^(cpu|cuda(:\d+)?)$")


def device_name(value: str) -> str:
    """``--device`` of work that may run elsewhere (a sweep on a cluster's workers): a Warp
    device's form, whether or not this machine has it (:func:`device` checks it here)."""
    if not DEVICE_NAME.match(value):
        raise argparse.ArgumentTypeError(f"{value!r} is not a device name (cpu, cuda or cuda:N)")
    return value


def path_text(value: str) -> str:
    """A path option: not empty (an empty --out would silently mean the default)."""
    if not value.strip():
        raise argparse.ArgumentTypeError("an empty path; name a file or directory, or leave the option out")
    return value


def finite(value: str) -> float:
    """A number option that must be finite (NaN or infinity would silently mean something else)."""
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{value!r} is not a number") from None
    if not math.isfinite(number):
        raise argparse.ArgumentTypeError(f"{value!r} is not a finite number")
    return number


def positive(value: str) -> float:
    """A finite number option that must be > 0."""
    number = finite(value)
    if number <= 0:
        raise argparse.ArgumentTypeError(f"{value!r} must be positive")
    return number


def non_negative(value: str) -> float:
    """A finite number option that must be ≥ 0."""
    number = finite(value)
    if number < 0:
        raise argparse.ArgumentTypeError(f"{value!r} must not be negative")
    return number


def at_least(minimum: int) -> Callable[[str], int]:
    """An integer option type that refuses values below ``minimum``."""

    def parse(value: str) -> int:
        try:
            number = int(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{value!r} is not an integer") from None
        if number < minimum:
            raise argparse.ArgumentTypeError(f"{value} must be at least {minimum}")
        return number

    parse.__name__ = f"integer >= {minimum}"
    return parse


def add_overrides(parser: argparse.ArgumentParser, what: str) -> None:
    """``--set KEY=VALUE`` (repeatable, into ``overrides``): override ``what``'s fields."""
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE", help=f"override {what}"
    )


def add_device(parser: argparse.ArgumentParser, where: str = "", elsewhere: bool = False) -> None:
    """``--device``: the Warp device to run on (``where`` says on what, e.g. every worker);
    checked against this machine when parsed, or only for its form where the work may run
    ``elsewhere`` (the command checks it here when it runs here)."""
    parser.add_argument(
        "--device",
        type=device_name if elsewhere else device,
        default=None,
        help=f"cpu or cuda{where} (default: Warp's preferred device)",
    )


def add_no_progress(parser: argparse.ArgumentParser) -> None:
    """``--no-progress``: no progress bar."""
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_overwrite(parser: argparse.ArgumentParser, what: str) -> None:
    """``--overwrite``: replace an existing ``what`` (default: refuse it)."""
    parser.add_argument("--overwrite", action="store_true", help=f"replace an existing {what} (default: refuse)")


def figure_path(path: str | Path, overwrite: bool, option: str = "--plot") -> Path:
    """``--plot FILE``: a PNG that does not exist yet (unless ``overwrite``)."""
    out = Path(path)
    if out.suffix.lower() != ".png" or out.is_dir():
        raise OptionError(option, f"{out} must be a file ending in .png")
    return new_result(out, overwrite, option)


def new_file(path: str | Path, overwrite: bool, option: str) -> Path:
    """:func:`new_result` for a result that is one file: a directory there is refused by
    name (the atomic writer would otherwise fail on its hidden temporary file)."""
    out = Path(path)
    if out.is_dir():
        raise OptionError(option, f"{out} is a directory; {option} names the file to write")
    return new_result(out, overwrite, option)


def new_result(path: str | Path, overwrite: bool, option: str) -> Path:
    """``path`` for a result about to be written: refused when another warpcloth process is
    writing it (this one holds its marker from now until it exits:
    :mod:`warpcloth.io.writing`), or when something is there already, unless ``overwrite``
    (the writers replace it atomically, only once the new one is whole)."""
    from warpcloth.io.writing import claim_result

    out = Path(path)
    claim_result(out, option)
    exists = out.is_file() or (out.is_dir() and any(out.iterdir()))
    if exists and not overwrite:
        raise OptionError(option, f"{out} already exists; choose another {option}, or pass --overwrite")
    return out
