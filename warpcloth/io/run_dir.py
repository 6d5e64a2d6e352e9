"""Run directories: results stream to disk as they are produced, and are read back.

Layout of a run directory::

    scene.toml          resolved scene (every field, defaults included); for a batch,
                        variants/NNNN.toml, one per strip
    probes.csv          one row per (t, variant); columns PROBE_COLUMNS, SI units
    frames.npy          float array (frame, variant, node, xy) of node positions, m
    frame_times.npy     (frame,) times of the frames, s
    meta.json           sizes, units, health of every strip, completeness

``meta.json`` is written first with ``"complete": false`` and rewritten at the end,
so an interrupted run is recognisable; probes.csv and frames.npy hold everything
simulated up to the interruption.
"""

from __future__ import annotations

import io
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import tomli_w

from warpcloth.errors import DataFileError, OptionError
from warpcloth.kernels import PROBE_FIELDS, PROBE_UNITS
from warpcloth.scene import Scene, read_scene_file, scene_from_dict

from .atomic import write_text_atomically
from .json_file import read_json
from .recording import Recording, per_strip_parameters, select_variants

PROBE_COLUMNS = ("t", "variant", *PROBE_FIELDS)


def write_scene(path: Path, scene: Scene) -> None:
    """Write a resolved scene as TOML."""
    path.write_text(tomli_w.dumps(scene.to_dict()))


def check_output_directory(out_dir: str | Path, overwrite: bool = False) -> None:
    """Refuse an output directory that already holds something, unless ``overwrite``.

    An existing result is never replaced silently: without ``overwrite`` a non-empty
    directory is an OptionError of ``--out``; with it, :class:`RunWriter` writes the new
    run aside and swaps it in only once complete.
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise OptionError("--out", f"{out} is a file, not a run directory")
    if out.is_dir() and any(out.iterdir()) and not overwrite:
        what = "a run" if (out / "meta.json").is_file() else "a sweep" if (out / "sweep.json").is_file() else "files"
        raise OptionError("--out", f"{out} already holds {what}; choose another --out, or pass --overwrite "
                          "(the old one is replaced only once the new run is complete)")


class RunWriter:
    """Streams one batch run into a directory (see the module docstring).

    Into a new or empty directory the run streams in place (an interrupted run reads as
    incomplete there). Over an existing result (``overwrite``) it streams into a hidden
    sibling ``.<name>.new-<pid>`` and replaces the old directory only in :meth:`close`,
    so a kill or a failure leaves the old result as it was.
    """

    def __init__(self, out_dir: str | Path, scenes: list[Scene], n_nodes: int, frame_times: np.ndarray,
                 overwrite: bool = False) -> None:
        check_output_directory(out_dir, overwrite)
        self.target = Path(out_dir)
        replacing = self.target.is_dir() and any(self.target.iterdir())
        self.dir = self.target.with_name(f".{self.target.name}.new-{os.getpid()}") if replacing else self.target
        if replacing and self.dir.exists():
            shutil.rmtree(self.dir)  # a staging directory this process left before
        self.dir.mkdir(parents=True, exist_ok=True)
        if len(scenes) == 1:
            write_scene(self.dir / "scene.toml", scenes[0])
        else:
            (self.dir / "variants").mkdir(exist_ok=True)
            for i, scene in enumerate(scenes):
                write_scene(self.dir / "variants" / f"{i:04d}.toml", scene)
        self.meta = {
            "complete": False,
            "n_variants": len(scenes),
            "n_nodes": n_nodes,
            "n_clamped": scenes[0].n_clamped,
            "spacing_m": scenes[0].spacing,
            "probe_columns": list(PROBE_COLUMNS),
            "probe_units": {"t": "s", "variant": "index", **PROBE_UNITS},
            "frames": {"file": "frames.npy", "shape": [len(frame_times), len(scenes), n_nodes, 2],
                       "axes": ["frame", "variant", "node", "xy"], "unit": "m",
                       "times_file": "frame_times.npy"},
            "diverged": [],
        }
        self._write_meta()
        np.save(self.dir / "frame_times.npy", frame_times)
        self.frames = np.lib.format.open_memmap(self.dir / "frames.npy", mode="w+", dtype=np.float64,
                                                shape=(len(frame_times), len(scenes), n_nodes, 2))
        # Frames never reached (an interrupted run, strips stopped by a divergence) read
        # as NaN, never as a strip collapsed onto the origin.
        self.frames[:] = np.nan
        self.probes = open(self.dir / "probes.csv", "w")  # noqa: SIM115 - closed in close()
        self.probes.write(",".join(PROBE_COLUMNS) + "\n")

    def _write_meta(self) -> None:
        write_text_atomically(self.dir / "meta.json", json.dumps(self.meta, indent=2))

    def write_probes(self, t: np.ndarray, variant: np.ndarray, values: np.ndarray) -> None:
        """Append rows: times, variant indices and values ``[row, field]``."""
        rows = np.column_stack([t, variant, values])
        fmt = ["%.10g", "%d"] + ["%.17g"] * values.shape[1]
        np.savetxt(self.probes, rows, fmt=fmt, delimiter=",")
        self.probes.flush()

    def write_frames(self, first: int, frames: np.ndarray) -> None:
        """Store frames ``[frame, variant, node, xy]`` starting at frame index ``first``."""
        self.frames[first : first + len(frames)] = frames
        self.frames.flush()

    def close(self, diverged: list[dict], extra: dict) -> None:
        """Finish the files and mark the run complete."""
        self.probes.close()
        self.frames.flush()
        del self.frames
        self.meta["diverged"] = diverged
        self.meta.update(extra)
        self.meta["complete"] = True
        self._write_meta()
        if self.dir != self.target:
            # Swap: the old result moves aside, the complete new one takes its name, then
            # the old goes. Killed between the two renames, both survive (hidden names).
            old = self.target.with_name(f".{self.target.name}.old-{os.getpid()}")
            os.replace(self.target, old)
            os.replace(self.dir, self.target)
            shutil.rmtree(old)
            self.dir = self.target


def read_probes(path: Path, complete: bool) -> pd.DataFrame:
    """The probe rows of run directory ``path``.

    Rows are appended whole and flushed, so only an interrupted write can leave a partial
    last line (a number cut before its exponent would read orders of magnitude wrong): it
    is dropped from an incomplete run and refused in one that claims to be complete.
    """
    file = path / "probes.csv"
    text = file.read_text()
    if text and not text.endswith("\n"):
        if complete:
            raise DataFileError(file, "its last row is torn although meta.json says the run is complete")
        text = text[: text.rfind("\n") + 1]
    try:
        table = pd.read_csv(io.StringIO(text))
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise DataFileError(file, f"is not a probe table: {exc}") from None
    if list(table.columns) != list(PROBE_COLUMNS):
        raise DataFileError(file, f"has columns {', '.join(map(str, table.columns))}; a run writes "
                            f"{', '.join(PROBE_COLUMNS)}")
    return table


def read_run(path: Path, variants: str | None = None, where: str | None = None) -> Recording:
    """Selected variants of a run directory as a Recording (an interrupted run: the frames it reached)."""
    meta = read_json(path / "meta.json")
    if meta["n_variants"] == 1:
        scenes = [scene_from_dict(read_scene_file(path / "scene.toml"))]
    else:
        scenes = [scene_from_dict(read_scene_file(path / "variants" / f"{i:04d}.toml"))
                  for i in range(meta["n_variants"])]
    parameters = per_strip_parameters(scenes)
    parameters.insert(0, "variant", np.arange(len(scenes)))
    chosen = select_variants(parameters, variants, where)
    frames = np.asarray(np.load(path / "frames.npy", mmap_mode="r")[:, chosen])
    times = np.load(path / "frame_times.npy")
    if not meta["complete"]:
        # An interrupted run: keep the frames it reached.
        reached = np.nonzero(np.isfinite(frames).any(axis=(1, 2, 3)))[0]
        if not len(reached):
            raise DataFileError(path, "the run was interrupted before its first frame")
        frames, times = frames[: reached[-1] + 1], times[: reached[-1] + 1]
    probes = read_probes(path, bool(meta["complete"]))
    return Recording(path, chosen, [scenes[i] for i in chosen], times, frames, probes[probes["variant"].isin(chosen)],
                     parameters.iloc[chosen].reset_index(drop=True), bool(meta["complete"]))
