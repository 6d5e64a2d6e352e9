"""Where a result came from: written into every result file that has metadata, so a
number in a paper can be traced to the code, the command and the machine that made it."""

from __future__ import annotations

import datetime
import hashlib
import importlib.metadata
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np


def _version(package: str) -> str | None:
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return None


def _git_commit() -> str | None:
    # the checkout the package runs from, if it is one (an installed wheel is not)
    here = Path(__file__).resolve().parent
    try:
        done = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5)
    except (OSError, subprocess.SubprocessError):
        return None
    if done.returncode != 0:
        return None
    try:
        dirty = subprocess.run(
            ["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
            capture_output=True,
            text=True,
            timeout=5,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return done.stdout.strip() + "-unknown-state"
    return done.stdout.strip() + ("-dirty" if dirty else "")


def _default_device() -> str:
    from warpcloth.strip.model import machine_device  # starts Warp quietly, as a run does

    return machine_device(None).alias


def file_checksum(path: str | Path) -> dict:
    """A file's path and SHA-256, to name the exact data a result was computed from."""
    path = Path(path)
    return {"path": str(path), "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}


def provenance(device: str | None = None, **extra: object) -> dict:
    """Versions, git commit, command line, date (UTC), host and device, plus ``extra``."""
    return {
        "warpcloth": _version("warpcloth"),
        "warp": _version("warp-lang"),
        "numpy": np.__version__,
        "python": platform.python_version(),
        "git_commit": _git_commit(),
        "command": [Path(sys.argv[0]).name, *sys.argv[1:]],
        "date_utc": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "host": platform.node(),
        "device": device or _default_device(),
    } | extra
