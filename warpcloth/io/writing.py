"""One writer per result: a marker file that a process holds (an exclusive ``flock``)
while it writes a result, naming its pid.

Every command that writes a result directory or file takes the marker of that result
before it checks whether the result already exists, and keeps it until it is done: a
second process aiming at the same result finds the marker held and is refused, naming
the first; one started after the first finished finds the finished result and is
refused as an existing result. A run directory's marker is its own ``.writing``; a
result file's or another directory's is ``.<name>.writing`` beside it. The lock goes
with the process, so a killed writer's marker left on disk holds nothing.
"""

from __future__ import annotations

import atexit
import fcntl
import os
import time
from pathlib import Path

from warpcloth.errors import ArgumentError

WRITING = ".writing"
"""Marker of a run directory a process is streaming into (left behind by a killed one)."""

_HELD: dict[Path, int] = {}
"""Markers this process holds: path → the open descriptor that holds the lock."""

_CLAIMED: set[Path] = set()
"""The markers :func:`claim_result` took (released by :func:`release_claims` or at exit)."""


def marker_of(result: str | Path) -> Path:
    """The marker beside result file or directory ``result``."""
    result = Path(result).absolute()
    return result.with_name(f".{result.name}{WRITING}")


def _holder(fd: int) -> int:
    # the pid a held marker names; its holder writes it just after taking the lock, so an
    # empty marker is read again for a moment (-1 when it still names none)
    for _ in range(50):
        try:
            return int(os.pread(fd, 32, 0))
        except ValueError:
            time.sleep(0.01)
    return -1


def busy(
    result: str | Path, writer: int, argument: str, advice: str = "wait for it, or choose another"
) -> ArgumentError:
    """The refusal of ``argument`` (the caller's name for ``result``) while process
    ``writer`` writes ``result`` (-1: one whose pid is not written yet)."""
    who = f"pid {writer}" if writer > 0 else "one just starting, its pid not yet written"
    return ArgumentError(
        argument, f"{result} is being written by another warpcloth process ({who}); {advice} {argument}"
    )


def live_writer(marker: str | Path) -> int | None:
    """The pid of another running process holding ``marker``, or None (no marker, one a
    killed process left, or this process's own)."""
    marker = Path(marker).absolute()
    if marker in _HELD:
        return None
    try:
        fd = os.open(marker, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except BlockingIOError:
        return _holder(fd)
    finally:
        os.close(fd)
    return None


def hold(marker: str | Path) -> int | None:
    """Take ``marker`` for this process (created if missing, its pid written in it);
    returns None when taken, else the pid of the running process that holds it."""
    marker = Path(marker).absolute()
    if marker in _HELD:
        return None
    while True:
        fd = os.open(marker, os.O_CREAT | os.O_RDWR, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid = _holder(fd)
            os.close(fd)
            return pid
        try:
            same = os.stat(marker).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # its holder removed it between our open and our lock: take the new one
    os.ftruncate(fd, 0)
    os.pwrite(fd, str(os.getpid()).encode(), 0)
    _HELD[marker] = fd
    return None


def release(marker: str | Path) -> None:
    """Remove a marker this process holds (nothing if it holds none)."""
    marker = Path(marker).absolute()
    fd = _HELD.pop(marker, None)
    if fd is not None:
        marker.unlink(missing_ok=True)
        os.close(fd)


def claim_result(result: str | Path, argument: str) -> None:
    """Hold ``result``'s marker until this process ends, or refuse ``argument`` (the
    caller's name for ``result``) naming the running process that writes ``result`` (see
    the module docstring)."""
    marker = marker_of(result)
    if not marker.parent.is_dir():
        marker.parent.mkdir(parents=True, exist_ok=True)
    writer = hold(marker)
    if writer is not None:
        raise busy(result, writer, argument)
    _CLAIMED.add(marker)
    atexit.register(release, marker)


def release_claims() -> None:
    """Release every marker :func:`claim_result` took: the command that claimed them is over
    (its results are whole, or were never started), though the process may go on (a
    command run from Python, a test)."""
    while _CLAIMED:
        release(_CLAIMED.pop())
