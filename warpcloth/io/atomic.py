"""The one way warpcloth writes a finished file: to a temporary name in the same
directory, flushed to disk, then renamed over the target. A kill or a full disk leaves
either the old file or none, never a torn one that reads as valid."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path


def write_atomically(path: str | Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(temporary_path)``, then move the result onto ``path``; returns ``path``.

    The temporary name keeps ``path``'s suffix, so writers that choose a format by
    suffix (USD, matplotlib) write the right one; it starts with a dot, so an
    interrupted write leaves only a hidden file that no reader looks at.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        write(tmp)
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


def write_text_atomically(path: str | Path, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def write_files_atomically(directory: str | Path, writers: dict[str, Callable[[Path], None]]) -> list[Path]:
    """Write several files of one result: every file is prepared under its temporary name
    before any is renamed into place, so a failure while preparing leaves the old set."""
    directory = Path(directory)
    staged = {name: directory / f".{Path(name).stem}.{os.getpid()}.tmp{Path(name).suffix}" for name in writers}
    try:
        for name, write in writers.items():
            write(staged[name])
            with open(staged[name], "rb") as fh:
                os.fsync(fh.fileno())
        for name, tmp in staged.items():
            os.replace(tmp, directory / name)
    finally:
        for tmp in staged.values():
            tmp.unlink(missing_ok=True)
    return [directory / name for name in writers]
