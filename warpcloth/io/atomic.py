"""The one way warpcloth writes a finished file: to a temporary name in the same
directory, flushed to disk, then renamed over the target. A kill or a full disk leaves
either the old file or none, never a torn one that reads as valid."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterator
from pathlib import Path


@contextlib.contextmanager
def naming(path: str | Path) -> Iterator[None]:
    """Give an OSError raised inside without a file name (a write that hit a full disk or
    a file-size limit) the name of ``path``, so its one-line message says which file."""
    try:
        yield
    except OSError as exc:
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        raise


def write_atomically(path: str | Path, write: Callable[[Path], None]) -> Path:
    """Call ``write(temporary_path)``, then move the result onto ``path``; returns ``path``.

    The temporary name keeps ``path``'s suffix, so writers that choose a format by
    suffix (USD, matplotlib) write the right one; it starts with a dot, so an
    interrupted write leaves only a hidden file that no reader looks at.
    """
    path = Path(path)
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp{path.suffix}")
    try:
        with naming(path):
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


def write_npy_atomically(path: str | Path, array: object) -> Path:
    """Write ``array`` as a .npy file at exactly ``path`` atomically."""
    import numpy as np

    def save(tmp: Path) -> None:
        with open(tmp, "wb") as fh:  # a handle, so numpy never appends ".npy" to the name
            np.save(fh, array)

    return write_atomically(path, save)


def write_files_atomically(directory: str | Path, writers: dict[str, Callable[[Path], object]]) -> list[Path]:
    """Write several files of one result: every file is prepared under its temporary name
    before any is renamed into place, so a failure while preparing leaves the old set."""
    directory = Path(directory)
    staged = {name: directory / f".{Path(name).stem}.{os.getpid()}.tmp{Path(name).suffix}" for name in writers}
    try:
        for name, write in writers.items():
            with naming(directory / name):
                write(staged[name])
                with open(staged[name], "rb") as fh:
                    os.fsync(fh.fileno())
        for name, tmp in staged.items():
            os.replace(tmp, directory / name)
    finally:
        for tmp in staged.values():
            tmp.unlink(missing_ok=True)
    return [directory / name for name in writers]
