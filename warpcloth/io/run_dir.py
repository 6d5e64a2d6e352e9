"""Run directories: results stream to disk as they are produced, and are read back.

Layout of a run directory::

    scene.toml          resolved scene (every field, defaults included); for a batch,
                        variants/NNNN.toml, one per strip
    probes.csv          one row per (t, variant); columns PROBE_COLUMNS, SI units
    frames.npy          float array (frame, variant, node, xy) of node positions, m
    frame_times.npy     (frame,) times of the frames, s
    meta.json           the body ("kind": "strip"), sizes, units, health of every strip,
                        completeness

``meta.json`` is written first with ``"complete": false`` and rewritten at the end,
so an interrupted run is recognisable. After every chunk is durable (flushed and
fsynced) meta.json's ``"committed"`` says how much of the streamed files is valid: the
probe rows and bytes of probes.csv and the frames of frames.npy. A reader of an
interrupted run uses exactly that part (a torn tail written after the last commit is
ignored, not parsed); a complete run whose files disagree with it is refused.
frames.npy is written with ordinary writes, never through a memory map: on a full disk a
mapped page fails as a signal that kills the process, a write as an error that is
reported. Its space is reserved when the run starts, so a disk too small for it fails
then, before any kernel runs.
"""

from __future__ import annotations

import errno
import io
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import tomli_w

from warpcloth.core.resources import check_disk
from warpcloth.errors import ArgumentError, DataFileError, SceneError, checked_path
from warpcloth.kernels import PROBE_FIELDS, PROBE_UNITS
from warpcloth.scene import COORDINATES, Scene, read_scene_file, scene_from_dict

from .atomic import naming, write_npy_atomically, write_text_atomically
from .json_file import json_text, read_json
from .provenance import provenance
from .recording import Recording, check_time_order, per_strip_parameters, select_variants
from .writing import WRITING, busy, hold, live_writer, release

PROBE_COLUMNS = ("t", "variant", *PROBE_FIELDS)


def write_scene(path: Path, scene: Scene) -> None:
    """Write a resolved scene as TOML."""
    path.write_text(tomli_w.dumps(scene.to_dict()))


def write_scenes(directory: Path, scenes: list) -> None:
    """The resolved scene of a run of one variant (scene.toml), or of each variant of a
    batch (variants/NNNN.toml), of either body."""
    if len(scenes) == 1:
        write_scene(directory / "scene.toml", scenes[0])
        return
    (directory / "variants").mkdir(exist_ok=True)
    for i, scene in enumerate(scenes):
        write_scene(directory / "variants" / f"{i:04d}.toml", scene)


def reserve(file: io.BufferedWriter, size: int) -> None:
    """Give ``file`` its final ``size`` now: allocated on disk where the file system can
    (a full disk fails here, before the run), else a sparse extension."""
    file.flush()
    try:
        os.posix_fallocate(file.fileno(), 0, size)
    except OSError as exc:
        if exc.errno not in (errno.EOPNOTSUPP, errno.EINVAL, errno.ENOSYS):
            raise
        os.ftruncate(file.fileno(), size)


def check_output_directory(out_dir: str | Path, overwrite: bool = False) -> None:
    """Refuse an output directory that already holds something, unless ``overwrite``.

    An existing result is never replaced silently: without ``overwrite`` a non-empty
    directory is an ArgumentError of ``out``; with it, :class:`RunWriter` writes the new
    run aside and swaps it in only once complete.
    """
    out = Path(checked_path("out", out_dir))
    if out.exists() and not out.is_dir():
        raise ArgumentError("out", f"{out} is a file, not a run directory")
    if out.is_dir() and any(out.iterdir()):
        what = "a run" if (out / "meta.json").is_file() else "a sweep" if (out / "sweep.json").is_file() else "files"
        if not overwrite:
            raise ArgumentError(
                "out",
                f"{out} already holds {what}; choose another --out, or pass --overwrite "
                "(the old one is replaced only once the new run is complete)",
            )
        if what != "a run":
            raise ArgumentError(
                "out",
                f"{out} holds {what} that are not a warpcloth run; --overwrite replaces only "
                "a run directory, never other files: choose another --out",
            )


class StreamedDirectory:
    """Where a run streams: the staging, the one-writer marker and the final swap that
    every streamed run directory (a strip batch's, a sheet's) shares.

    Into a new or empty directory the run streams in place (an interrupted run reads as
    incomplete there). Over an existing result (``overwrite``) it streams into a hidden
    sibling ``.<name>.new-<pid>`` and replaces the old directory only in :meth:`finish`,
    so a kill or a failure leaves the old result as it was. ``disk_bytes`` is checked
    free before anything is written (``disk_what`` and ``disk_advice`` say it).
    """

    def __init__(self, out_dir: str | Path, overwrite: bool, disk_bytes: int, disk_what: str, disk_advice: str) -> None:
        check_output_directory(out_dir, overwrite)
        self.target = Path(out_dir).absolute()
        writer = live_writer(self.target / WRITING)
        if writer is not None:
            raise busy(out_dir, writer, "out")
        replacing = self.target.is_dir() and any(self.target.iterdir())
        self.dir = self.target.with_name(f".{self.target.name}.new-{os.getpid()}") if replacing else self.target
        if replacing and self.dir.exists():
            shutil.rmtree(self.dir)  # a staging directory this process left before
        check_disk(self.target, disk_bytes, disk_what, disk_advice)
        self.dir.mkdir(parents=True, exist_ok=True)
        # One writer per directory: a second process that passed the emptiness check at
        # the same moment finds the marker and stops instead of interleaving its rows.
        writer = hold(self.dir / WRITING)
        if writer is not None:
            raise busy(self.target, writer, "out")
        if any(p.name != WRITING for p in self.dir.iterdir()):
            # another writer finished here between the emptiness check and the marker
            release(self.dir / WRITING)
            raise ArgumentError(
                "out",
                f"{self.target} already holds a run (written meanwhile by another process); "
                "choose another --out, or pass --overwrite",
            )

    def finish(self) -> None:
        """Release the marker and, over an old result, swap the complete new one in."""
        release(self.dir / WRITING)
        if self.dir != self.target:
            # Swap: the old result moves aside, the complete new one takes its name, then
            # the old goes. Killed between the two renames, both survive (hidden names).
            old = self.target.with_name(f".{self.target.name}.old-{os.getpid()}")
            os.replace(self.target, old)
            os.replace(self.dir, self.target)
            shutil.rmtree(old, ignore_errors=True)  # the new result is in place; the old copy goes if it can
            self.dir = self.target


class StreamedFrames:
    """frames.npy written as a run goes, by ordinary writes at known offsets (its space
    reserved at once, see the module docstring); frames never reached read as NaN."""

    def __init__(self, path: Path, shape: tuple[int, ...]) -> None:
        self.path = path
        self.shape = shape
        self.file = open(path, "wb")  # noqa: SIM115 - closed in close()
        np.lib.format.write_array_header_1_0(self.file, {"descr": "<f8", "fortran_order": False, "shape": shape})
        self.offset = self.file.tell()
        self.frame_bytes = int(np.prod(shape[1:])) * 8
        with naming(path):
            reserve(self.file, self.offset + shape[0] * self.frame_bytes)
        self.written = 0

    def write(self, first: int, frames: np.ndarray) -> None:
        """Store ``frames`` from frame index ``first`` on."""
        self._write_block(first, np.ascontiguousarray(frames, dtype="<f8"))
        self.written = max(self.written, first + len(frames))

    def _write_block(self, first: int, block: np.ndarray) -> None:
        with naming(self.path):
            self.file.seek(self.offset + first * self.frame_bytes)
            self.file.write(block.tobytes())

    def sync(self) -> None:
        """Make what was written durable."""
        with naming(self.path):
            self.file.flush()
            os.fsync(self.file.fileno())

    def fill(self) -> None:
        """Frames never reached (every strip stopped by a divergence) read as NaN, never
        as a shape collapsed onto the origin."""
        missing = self.shape[0] - self.written
        if missing:
            self._write_block(self.written, np.full((missing, *self.shape[1:]), np.nan))
            self.written = self.shape[0]

    def close(self) -> None:
        """Close the file (after the last :meth:`sync`)."""
        self.file.close()


@dataclass(frozen=True)
class StreamedTable:
    """A CSV table a run streams: its ``file``, ``columns`` and their printf ``formats``;
    meta.json's ``committed`` records ``<key>_rows`` and ``<key>_bytes`` of it."""

    file: str
    columns: tuple[str, ...]
    formats: tuple[str, ...]
    key: str


def probe_table(index: str, fields: tuple[str, ...]) -> StreamedTable:
    """probes.csv: one row per (t, body) with ``index`` naming the body's column."""
    return StreamedTable("probes.csv", ("t", index, *fields), ("%.10g", "%d", *["%.17g"] * len(fields)), "probe")


class StreamedRun:
    """What every run writer shares: the declared tables and frames.npy streamed into a
    :class:`StreamedDirectory`, each chunk made durable and then recorded as committed in
    meta.json, and the close that marks the run complete (see the module docstring). A
    body's writer declares its tables and meta and turns the runner's samples into rows
    (:meth:`write_samples`); it is a :class:`~warpcloth.core.runner.Sink`."""

    def __init__(
        self,
        place: StreamedDirectory,
        meta: dict,
        tables: tuple[StreamedTable, ...],
        frame_times: np.ndarray,
        frames_shape: tuple[int, ...],
    ) -> None:
        self.place = place
        self.dir = place.dir
        self.meta = meta
        self.meta["committed"] = {f"{t.key}_{what}": 0 for t in tables for what in ("rows", "bytes")} | {"frames": 0}
        self._write_meta()
        write_npy_atomically(self.dir / "frame_times.npy", frame_times)
        self.frames = StreamedFrames(self.dir / "frames.npy", frames_shape)
        self.tables = {t.file: t for t in tables}
        self.files = {}
        for t in tables:
            self.files[t.file] = open(self.dir / t.file, "w", newline="\n")  # noqa: SIM115 - closed in close()
            self.files[t.file].write(",".join(t.columns) + "\n")
        self.commit({})

    def _write_meta(self) -> None:
        write_text_atomically(self.dir / "meta.json", json_text(self.meta, indent=2))

    @property
    def probe_fields(self) -> tuple[str, ...]:
        """The probes probes.csv has columns for (after ``t`` and the body's index)."""
        return self.tables["probes.csv"].columns[2:]

    def append(self, file: str, rows: np.ndarray) -> int:
        """Append ``rows`` to table ``file`` (not yet committed); how many."""
        with naming(self.dir / file):
            np.savetxt(self.files[file], rows, fmt=list(self.tables[file].formats), delimiter=",")
        return len(rows)

    def commit(self, rows: dict[str, int]) -> None:
        """Make what was written durable, then record it (``rows`` appended per file)."""
        for file, handle in self.files.items():
            with naming(self.dir / file):
                handle.flush()
                os.fsync(handle.fileno())
        self.frames.sync()
        committed = self.meta["committed"]
        for file, table in self.tables.items():
            committed[f"{table.key}_rows"] += rows.get(file, 0)
            committed[f"{table.key}_bytes"] = self.files[file].tell()
        committed["frames"] = self.frames.written
        self._write_meta()

    def probe_rows(self, t: np.ndarray, probes: np.ndarray, valid: np.ndarray) -> np.ndarray:
        """The rows of probes.csv for the valid (sample, body) of ``probes[sample, field,
        body]`` at ``t``, sample by sample (rows after a divergence are never written)."""
        sample, body = np.nonzero(valid)
        return np.column_stack([t[sample], body, probes[sample, :, body]])

    def write_samples(
        self, t: np.ndarray, probes: np.ndarray, tables: dict[str, np.ndarray], valid: np.ndarray
    ) -> None:
        """Append the valid samples' probe rows (a body with other tables extends this)."""
        self.commit({"probes.csv": self.append("probes.csv", self.probe_rows(t, probes, valid))})

    def write_frames(self, first: int, frames: np.ndarray) -> None:
        """Store frames ``[frame, body, node, component]`` from frame index ``first`` on."""
        self.frames.write(first, frames)
        self.commit({})

    def close(self, diverged: list, extra: dict) -> None:
        """Finish the files and mark the run complete."""
        self.frames.fill()
        self.commit({})
        for handle in self.files.values():
            handle.close()
        self.frames.close()
        self.meta["diverged"] = [d.as_dict() for d in diverged]
        self.meta.update(extra)
        self.meta["provenance"] = provenance(extra.get("device"))
        self.meta["complete"] = True
        self._write_meta()
        self.place.finish()
        self.dir = self.place.dir


class RunWriter(StreamedRun):
    """Streams one batch run of strips into a directory (see the module docstring)."""

    def __init__(
        self, out_dir: str | Path, scenes: list[Scene], n_nodes: int, frame_times: np.ndarray, overwrite: bool = False
    ) -> None:
        n_samples = (len(frame_times) - 1) * scenes[0].output.probes_per_frame + 1
        row_bytes = 16 + 24 * len(PROBE_FIELDS)  # "%.17g" fields of at most 24 characters
        place = StreamedDirectory(
            out_dir,
            overwrite,
            16 * len(frame_times) * len(scenes) * n_nodes + n_samples * len(scenes) * row_bytes,
            "the run's frames.npy and probes.csv",
            "free space, choose another --out, or record less "
            "(output.probes_per_frame, output.frame_rate_hz, run.duration_s)",
        )
        write_scenes(place.dir, scenes)
        frames_shape = (len(frame_times), len(scenes), n_nodes, 2)
        meta = {
            "kind": "strip",
            "complete": False,
            "n_variants": len(scenes),
            "n_nodes": n_nodes,
            "n_clamped": scenes[0].n_clamped,
            "spacing_m": scenes[0].spacing,
            "probe_columns": list(PROBE_COLUMNS),
            "probe_units": {"t": "s", "variant": "index", **PROBE_UNITS},
            "coordinates": COORDINATES,
            "frames": {
                "file": "frames.npy",
                "shape": list(frames_shape),
                "axes": ["frame", "variant", "node", "xy"],
                "unit": "m",
                "times_file": "frame_times.npy",
            },
            "diverged": [],
        }
        super().__init__(place, meta, (probe_table("variant", PROBE_FIELDS),), frame_times, frames_shape)


def read_probes(path: Path, meta: dict) -> pd.DataFrame:
    """The committed probe rows of run directory ``path`` (see the module docstring).

    Only the part of probes.csv that meta.json records as committed is parsed: rows
    written after the last commit (a torn tail, where a number cut before its exponent
    would read orders of magnitude wrong) are ignored in an interrupted run; a complete
    run whose file is not exactly its committed size is refused.
    """
    committed = meta["committed"]
    numbers = read_committed_csv(
        path / "probes.csv", committed["probe_rows"], committed["probe_bytes"], meta["complete"], PROBE_COLUMNS
    )
    check_index_column(path / "probes.csv", numbers["variant"].to_numpy(), meta["n_variants"], "variant")
    numbers["variant"] = numbers["variant"].astype(int)
    check_time_order(path / "probes.csv", numbers["t"].to_numpy(), numbers["variant"].to_numpy(), line_offset=2)
    return numbers


def read_committed_csv(file: Path, rows: int, size: int, complete: bool, columns: tuple[str, ...]) -> pd.DataFrame:
    """The committed part of a streamed CSV table (``rows`` rows, ``size`` bytes, as the
    run's meta.json records), of exactly ``columns``, every cell a number; a DataFrame."""
    with open(file, "rb") as fh:
        data = fh.read()
    if complete and len(data) != size:
        raise DataFileError(
            file,
            f"holds {len(data)} bytes but meta.json records {size} for "
            "the complete run: the file was truncated or changed",
        )
    if len(data) < size:
        raise DataFileError(
            file,
            f"is shorter ({len(data)} bytes) than its committed part ({size} bytes): the file was truncated",
        )
    text = data[:size].decode("utf-8", errors="replace")
    try:
        numbers = pd.read_csv(io.StringIO(text))
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DataFileError(file, f"is not a table of the run: {exc}") from None
    if list(numbers.columns) != list(columns):
        raise DataFileError(
            file, f"has columns {', '.join(map(str, numbers.columns))}; a run writes {', '.join(columns)}"
        )
    if numbers.empty:
        return numbers.astype(float)  # the header alone: the run recorded no sample (it stopped first)
    damaged = [c for c in numbers.columns if not pd.api.types.is_numeric_dtype(numbers[c])]
    if damaged:
        # only a changed file gets here: find its first cell that is not a number
        column = list(columns).index(damaged[0])
        row = int(
            np.flatnonzero(pd.to_numeric(numbers[damaged[0]], errors="coerce").isna() & numbers[damaged[0]].notna())[0]
        )
        raise DataFileError(
            file,
            f"{damaged[0]} is {numbers.iat[row, column]!r}, not a number: the file was changed after the run",
            row + 2,
        )
    if complete and len(numbers) != rows:
        raise DataFileError(file, f"holds {len(numbers)} rows but meta.json records {rows} for the complete run")
    return numbers


def _check_meta(path: Path, meta: dict) -> None:
    # meta.json says what the other files must be; a run whose files disagree is damaged
    file = path / "meta.json"
    if meta.get("kind") == "sheet":
        raise DataFileError(
            file,
            "is a sheet run's; `warpcloth plot`, `render` and `export-usd` take a sheet run, and "
            "warpcloth.io.sheet_run_dir.read_sheet_run reads it",
        )
    if "committed" not in meta:
        raise DataFileError(
            file,
            "has no record of the committed rows and frames (written by an older "
            "warpcloth); rerun the scene to read it",
        )
    if meta.get("coordinates") != COORDINATES:
        raise DataFileError(
            file,
            "does not say its positions are from the clamp edge (an older warpcloth measured "
            "them from the clamp's top); rerun the scene to read it",
        )
    committed = meta["committed"]
    checks = [
        (isinstance(meta.get("complete"), bool), "complete must be true or false"),
        (isinstance(meta.get("n_variants"), int) and meta["n_variants"] >= 1, "n_variants must be a count ≥ 1"),
        (isinstance(meta.get("n_nodes"), int) and meta["n_nodes"] >= 3, "n_nodes must be a count ≥ 3"),
        (meta.get("probe_columns") == list(PROBE_COLUMNS), "probe_columns differ from what a run writes"),
        (
            isinstance(committed, dict)
            and all(
                isinstance(committed.get(k), int) and committed[k] >= 0 for k in ("probe_rows", "probe_bytes", "frames")
            ),
            "committed must give probe_rows, probe_bytes and frames as counts ≥ 0",
        ),
    ]
    for ok, why in checks:
        if not ok:
            raise DataFileError(file, f"{why}: the run directory is damaged")


def read_run_scenes(path: Path, n_variants: int, parse: Callable[[Path], Any], count: str = "n_variants") -> list:
    """The scenes a run directory stores, each read by ``parse`` (a file → a scene): one
    scene.toml for one variant, variants/NNNN.toml for more, as meta.json's ``count``
    (``n_variants``) says; a DataFileError naming the file when the directory holds others or a copy no
    longer reads as a scene (the run's copy, not a scene of the user's)."""
    stored = sorted(p.name for p in (path / "variants").glob("*.toml")) if (path / "variants").is_dir() else []
    if n_variants == 1 and (path / "scene.toml").is_file() and not stored:
        files = [path / "scene.toml"]
    elif n_variants > 1 and stored == [f"{i:04d}.toml" for i in range(n_variants)]:
        files = [path / "variants" / name for name in stored]
    else:
        held = (
            f"{len(stored)} variant scene(s) in variants/"
            if stored
            else "one scene.toml"
            if (path / "scene.toml").is_file()
            else "no scene file"
        )
        raise DataFileError(
            path / "meta.json",
            f"{count} is {n_variants}, but the run directory holds {held}: "
            "meta.json or the directory was changed after the run",
        )
    scenes = []
    for file in files:
        try:
            scenes.append(parse(file))
        except SceneError as exc:
            raise DataFileError(
                file,
                f"is the run's copy of its scene and this warpcloth refuses it ({exc}): the run directory was "
                "changed after the run, or a warpcloth with other rules wrote it (meta.json's provenance says "
                "which); rerun the scene with this one to read it",
            ) from None
    return scenes


def check_frame_times(file: Path, times: np.ndarray) -> None:
    """Refuse stored frame times that are not finite and strictly increasing (a changed
    frame_times.npy: every frame would be shown at another time)."""
    finite = np.isfinite(times)
    if not finite.all():
        k = int(np.argmin(finite))
        raise DataFileError(file, f"frame {k} has t = {times[k]}, not a time: the run directory is damaged")
    later = np.diff(times) > 0
    if not later.all():
        first = int(np.argmin(later))
        raise DataFileError(
            file,
            f"frame {first + 1} at t = {times[first + 1]:.10g} s does not come after frame {first} at "
            f"{times[first]:.10g} s: the frame times are out of order, so the run directory is damaged",
        )


def check_index_column(file: Path, values: np.ndarray, count: int, column: str, line_offset: int = 2) -> None:
    """Refuse a stored table whose ``column`` holds an index outside 0 … ``count`` − 1 (a
    row of a variant, sheet or marker the run does not have)."""
    bad = np.flatnonzero((values < 0) | (values >= count) | (values != np.round(values)))
    if len(bad):
        raise DataFileError(
            file,
            f"{column} is {values[bad[0]]:g}, but the run has {count} (0 to {count - 1}): the file was changed "
            "after the run",
            int(bad[0]) + line_offset,
        )


def read_run(path: Path, variants: str | None = None, where: str | None = None) -> Recording:
    """Selected variants of a run directory as a Recording (an interrupted run: the frames it reached)."""
    meta = read_json(path / "meta.json")
    _check_meta(path, meta)
    scenes = read_run_scenes(path, meta["n_variants"], lambda file: scene_from_dict(read_scene_file(file)))
    parameters = per_strip_parameters(scenes)
    parameters.insert(0, "variant", np.arange(len(scenes)))
    chosen = select_variants(parameters, variants, where)
    # An interrupted run: the frames it committed.
    reached = meta["committed"]["frames"]
    if not reached:
        raise DataFileError(path, "the run was interrupted before its first frame")
    try:
        stored = np.load(path / "frames.npy", mmap_mode="r")
        recorded = len(np.load(path / "frame_times.npy"))
    except (ValueError, OSError, EOFError) as exc:
        raise DataFileError(
            path / "frames.npy", f"cannot be read as the run's frames ({exc}): the run directory is damaged"
        ) from None
    expected = (recorded, meta["n_variants"], meta["n_nodes"], 2)
    if stored.shape != expected or reached > expected[0]:
        raise DataFileError(
            path / "frames.npy",
            f"holds frames of shape {stored.shape}, but the run recorded "
            f"{expected} ({reached} committed): the run directory is damaged",
        )
    frames = np.asarray(stored[:reached, chosen])
    times = np.load(path / "frame_times.npy")[:reached]
    check_frame_times(path / "frame_times.npy", times)
    probes = read_probes(path, meta)
    return Recording(
        path,
        chosen,
        [scenes[i] for i in chosen],
        times,
        frames,
        probes[probes["variant"].isin(chosen)],
        parameters.iloc[chosen].reset_index(drop=True),
        bool(meta["complete"]),
    )
