"""Opening what a run or a sweep wrote: the directory's own files say which it is."""

from __future__ import annotations

import os
from pathlib import Path

from warpcloth.errors import ArgumentTypeError, DataFileError

from .recording import Recording
from .run_dir import read_run
from .sweep_dir import read_sweep


def load_recording(path: str | Path, variants: str | None = None, where: str | None = None) -> Recording:
    """Open a run directory or a sweep directory (chosen by its files) and select variants.

    ``variants`` is a selection as for :func:`~warpcloth.io.recording.parse_variants`; ``where``
    a parameter filter as for :func:`~warpcloth.io.recording.filter_variants`; both may be given (the filter applies to
    the selection).
    """
    if not isinstance(path, (str, os.PathLike)):
        raise ArgumentTypeError("path", f"load_recording takes the path of a run or sweep directory, got {path!r}")
    path = Path(path)
    if (path / "sweep.json").is_file():
        return read_sweep(path, variants, where)
    if (path / "meta.json").is_file():
        return read_run(path, variants, where)
    raise DataFileError(path, "is neither a run directory (meta.json) nor a sweep directory (sweep.json)")
