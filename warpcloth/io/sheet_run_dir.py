"""Sheet run directories: a woven sheet's results stream to disk as they are produced
(with the strip's staging, marker, commit and swap, :mod:`.run_dir`), and are read back.

Layout of a sheet run directory::

    scene.toml          the resolved sheet scene (every field, the material's included)
    probes.csv          one row per (t, sheet): t, sheet, SHEET_PROBE_FIELDS; SI units
    markers.csv         long form, one row per (t, sheet, marker): t, sheet, marker, x, y, z (m)
    frames.npy          float array (frame, sheet, node, xyz) of node positions, m
    frame_times.npy     (frame,) times of the frames, s
    geometry.npz        lattice [node, (i, j)], rest_positions [node, xyz] (m), clamped
                        [node], faces [face, 4] (the mesh's quads, corners in loop order),
                        cells [cell, 4] (the cells the kernels shear and twist, in their order)
    meta.json           kind "sheet", sizes, units, coordinates, the markers' nodes,
                        health, completeness and what is committed

As for a strip's run, meta.json says ``"complete": false`` until the end, and
``"committed"`` how many rows and bytes of each CSV file and how many frames are durable;
a reader of an interrupted run uses exactly that part.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from warpcloth.errors import DataFileError
from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS, SHEET_PROBE_UNITS, SHEET_PROBES
from warpcloth.scene.sheet import SheetScene, read_sheet_scene
from warpcloth.scene.sheet_build import marker_nodes, sheet_geometry
from warpcloth.sheet import SheetGeometry

from .atomic import naming
from .json_file import read_json
from .recording import check_time_order
from .run_dir import (
    StreamedDirectory,
    StreamedRun,
    StreamedTable,
    check_frame_times,
    check_index_column,
    probe_table,
    read_committed_csv,
    read_run_scenes,
    write_scenes,
)

SHEET_COORDINATES = "x out of the sheet's rest plane, y up, z across, m, from the middle of the clamp edge (at rest)"
"""The frame of every position a sheet run stores, written into its meta.json."""
SHEET_PROBE_COLUMNS = ("t", "sheet", *SHEET_PROBE_FIELDS)
MARKER_COLUMNS = ("t", "sheet", "marker", "x", "y", "z")
ROW_BYTES = 24  # a "%.17g" field at most
GEOMETRY_ARRAYS = ("lattice", "rest_positions", "clamped", "faces", "cells")


def mesh_faces(geometry: SheetGeometry) -> np.ndarray:
    """The sheet's quads ``[face, 4]``, corners (i, j), (i+1, j), (i+1, j+1), (i, j+1) in loop
    order: every lattice cell whose four corners are nodes (the cut's cells, the clamped
    ones included)."""
    index = {(int(i), int(j)): k for k, (i, j) in enumerate(geometry.lattice)}
    faces = [
        (k, index[(i + 1, j)], index[(i + 1, j + 1)], index[(i, j + 1)])
        for (i, j), k in index.items()
        if (i + 1, j) in index and (i, j + 1) in index and (i + 1, j + 1) in index
    ]
    return np.array(sorted(faces), dtype=np.int32).reshape(-1, 4)


MARKER_TABLE = StreamedTable("markers.csv", MARKER_COLUMNS, ("%.10g", "%d", "%d", "%.17g", "%.17g", "%.17g"), "marker")


class SheetRunWriter(StreamedRun):
    """Streams one sheet run into a directory: the shared streamed run
    (:class:`~warpcloth.io.run_dir.StreamedRun`) with the markers' table and the geometry."""

    def __init__(
        self,
        out_dir: str | Path,
        scenes: SheetScene | list[SheetScene],
        geometry: SheetGeometry,
        markers: tuple[int, ...],
        frame_times: np.ndarray,
        overwrite: bool = False,
    ) -> None:
        scenes = [scenes] if isinstance(scenes, SheetScene) else list(scenes)
        n_frames, n_nodes, b = len(frame_times), geometry.n_nodes, len(scenes)
        n_samples = (n_frames - 1) * scenes[0].output.probes_per_frame + 1
        place = StreamedDirectory(
            out_dir,
            overwrite,
            b * (24 * n_frames * n_nodes + n_samples * ROW_BYTES * (len(SHEET_PROBE_COLUMNS) + 6 * len(markers))),
            "the run's frames.npy, probes.csv and markers.csv",
            "free space, choose another --out, or record less "
            "(output.probes_per_frame, output.frame_rate_hz, run.duration_s)",
        )
        write_scenes(place.dir, scenes)
        faces = mesh_faces(geometry)
        with naming(place.dir / "geometry.npz"):
            np.savez(
                place.dir / "geometry.npz",
                lattice=geometry.lattice,
                rest_positions=geometry.rest_positions,
                clamped=geometry.clamped,
                faces=faces,
                cells=geometry.cell_nodes,
            )
        frames_shape = (n_frames, b, n_nodes, 3)
        meta = {
            "kind": "sheet",
            "complete": False,
            "n_sheets": b,
            "n_nodes": n_nodes,
            "n_faces": len(faces),
            "spacing_m": list(geometry.spacing),
            "coordinates": SHEET_COORDINATES,
            "probe_columns": list(SHEET_PROBE_COLUMNS),
            "probe_units": {"t": "s", "sheet": "index", **SHEET_PROBE_UNITS},
            "marker_columns": list(MARKER_COLUMNS),
            "marker_units": {"t": "s", "sheet": "index", "marker": "index", "x": "m", "y": "m", "z": "m"},
            "markers": [
                {
                    "marker": k,
                    "node": int(node),
                    "lattice": [int(v) for v in geometry.lattice[node]],
                    "rest_position_m": [float(v) for v in geometry.rest_positions[node]],
                }
                for k, node in enumerate(markers)
            ],
            "frames": {
                "file": "frames.npy",
                "shape": list(frames_shape),
                "axes": ["frame", "sheet", "node", "xyz"],
                "unit": "m",
                "times_file": "frame_times.npy",
            },
            "geometry": {
                "file": "geometry.npz",
                "arrays": {
                    "lattice": "[node, (i, j)]: i along the warp, j along the weft",
                    "rest_positions": "[node, xyz], m",
                    "clamped": "[node], bool",
                    "faces": "[face, 4]: quads, corners in loop order",
                    "cells": "[cell, 4]: the cells the kernels shear and twist (probe index), corners (i,j), (i+1,j), "
                    "(i,j+1), (i+1,j+1)",
                },
            },
            "diverged": [],
        }
        tables = (probe_table("sheet", SHEET_PROBE_FIELDS), MARKER_TABLE)
        super().__init__(place, meta, tables, frame_times, frames_shape)

    def write_samples(
        self, t: np.ndarray, probes: np.ndarray, tables: dict[str, np.ndarray], valid: np.ndarray
    ) -> None:
        """Append the valid samples: probes ``[sample, field, sheet]`` and the markers
        ``[sample, sheet, marker, xyz]`` in long form (rows after a divergence are never
        written), committed together."""
        markers = tables["markers"]
        sample, sheet = np.nonzero(valid)
        n_markers = markers.shape[2]
        marker = np.tile(np.arange(n_markers), len(sample))
        positions = markers[sample, sheet].reshape(-1, 3)
        marks = np.column_stack([np.repeat(t[sample], n_markers), np.repeat(sheet, n_markers), marker, positions])
        rows = {
            "probes.csv": self.append("probes.csv", self.probe_rows(t, probes, valid)),
            "markers.csv": self.append("markers.csv", marks),
        }
        self.commit(rows)


@dataclass
class SheetSamples:
    """A sheet run directory's records as the arrays a :class:`~warpcloth.sheet.SheetResult`
    holds (what :mod:`warpcloth.viz.figures.sheet` reads), SI: ``probes[sample, field, sheet]``
    and ``markers[sample, sheet, marker, xyz]`` at ``t``, ``frames[frame, sheet, node, xyz]`` at
    ``frame_times``; NaN where a sheet recorded nothing (after its divergence)."""

    t: np.ndarray
    probes: np.ndarray
    markers: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray

    def energy_total(self) -> np.ndarray:
        """The budget that should stay constant, ``[sample, sheet]``."""
        return SHEET_PROBES.energy_total(self.probes)


@dataclass
class SheetRun:
    """A sheet run directory read back (an interrupted run: what it committed)."""

    path: Path
    scene: SheetScene
    meta: dict
    probes: pd.DataFrame
    markers: pd.DataFrame
    frame_times: np.ndarray
    frames: np.ndarray  # [frame, sheet, node, xyz], m
    lattice: np.ndarray
    rest_positions: np.ndarray
    faces: np.ndarray
    clamped: np.ndarray  # [node], bool: the nodes the clamp carries rigidly
    complete: bool

    @property
    def frame_rate(self) -> float:
        """Shape frames per second."""
        return self.scene.output.frame_rate_hz

    def samples(self) -> SheetSamples:
        """The long-form tables as arrays by sample, sheet and marker (the committed part of
        an interrupted run)."""
        n_sheets, n_markers = self.meta["n_sheets"], len(self.meta["markers"])
        t = np.unique(self.probes["t"].to_numpy())
        probes = np.full((len(t), len(SHEET_PROBE_FIELDS), n_sheets), np.nan)
        rows = np.searchsorted(t, self.probes["t"].to_numpy())
        probes[rows, :, self.probes["sheet"].to_numpy(dtype=int)] = self.probes[list(SHEET_PROBE_FIELDS)].to_numpy()
        markers = np.full((len(t), n_sheets, n_markers, 3), np.nan)
        table = self.markers  # committed with the probes, at the same times
        markers[
            np.searchsorted(t, table["t"].to_numpy()),
            table["sheet"].to_numpy(dtype=int),
            table["marker"].to_numpy(dtype=int),
        ] = table[["x", "y", "z"]].to_numpy()
        return SheetSamples(t, probes, markers, self.frame_times, self.frames)


def _why_empty(meta: dict) -> str:
    diverged = meta.get("diverged") or []
    if diverged:
        first = diverged[0]
        return f"it diverged at t = {first.get('time_s', float('nan')):.6g} s, before its first sample"
    return "it was stopped before its first sample"


META_COUNTS = ("probe_rows", "probe_bytes", "marker_rows", "marker_bytes", "frames")


def _check_sheet_meta(path: Path, meta: dict) -> None:
    # meta.json says what every other file must be; one that is not what a run writes is damaged
    file = path / "meta.json"
    if meta.get("kind") != "sheet" or meta.get("coordinates") != SHEET_COORDINATES:
        raise DataFileError(file, 'is not a sheet run\'s (kind "sheet", its coordinates)')
    committed = meta.get("committed")
    markers = meta.get("markers")
    checks = [
        (isinstance(meta.get("complete"), bool), "complete must be true or false"),
        (isinstance(meta.get("n_sheets"), int) and meta["n_sheets"] >= 1, "n_sheets must be a count ≥ 1"),
        (isinstance(meta.get("n_nodes"), int) and meta["n_nodes"] >= 4, "n_nodes must be a count ≥ 4"),
        (meta.get("probe_columns") == list(SHEET_PROBE_COLUMNS), "probe_columns differ from what a run writes"),
        (meta.get("marker_columns") == list(MARKER_COLUMNS), "marker_columns differ from what a run writes"),
        (
            isinstance(markers, list)
            and all(
                isinstance(m, dict) and m.get("marker") == k and isinstance(m.get("node"), int)
                for k, m in enumerate(markers)
            ),
            "markers must list each marker (0, 1, …) with its node",
        ),
        (
            isinstance(committed, dict)
            and all(isinstance(committed.get(k), int) and committed[k] >= 0 for k in META_COUNTS),
            f"committed must give {', '.join(META_COUNTS)} as counts ≥ 0",
        ),
    ]
    for ok, why in checks:
        if not ok:
            raise DataFileError(file, f"{why}: the run directory is damaged")


def _check_geometry(path: Path, meta: dict, scene: SheetScene, stored: dict[str, np.ndarray]) -> None:
    # every array of geometry.npz and every marker's node follow from the run's scene: rebuilt
    # from it, they must be what the file holds (an index changed there would be read as a node)
    geometry = sheet_geometry(scene)
    built = {
        "lattice": geometry.lattice,
        "rest_positions": geometry.rest_positions,
        "clamped": geometry.clamped,
        "faces": mesh_faces(geometry),
        "cells": geometry.cell_nodes,
    }
    for name, expected in built.items():
        held = stored[name]
        same = held.shape == expected.shape and (
            np.allclose(held, expected, rtol=0, atol=1e-12)
            if name == "rest_positions"
            else np.array_equal(held, expected)
        )
        if not same:
            if held.shape != expected.shape:
                how = f"holds shape {held.shape}, the scene's cut {expected.shape}"
            else:
                at = np.unravel_index(int(np.argmax(np.abs(held.astype(float) - expected) > 1e-12)), held.shape)
                how = f"[{', '.join(map(str, at))}] is {held[at]}, the scene's cut has {expected[at]}"
            raise DataFileError(
                path / "geometry.npz",
                f"{name} is not the geometry this warpcloth cuts from the run's scene ({how}): the run directory "
                "was changed after the run, or a warpcloth that cut sheets otherwise wrote it (meta.json's "
                "provenance says which)",
            )
    nodes = [m["node"] for m in meta["markers"]]
    expected_nodes = marker_nodes(scene, geometry)
    if nodes != expected_nodes:
        raise DataFileError(
            path / "meta.json",
            f"markers name nodes {nodes}, but the run's scene puts its markers at nodes {expected_nodes}: "
            "the run directory was changed after the run",
        )
    if meta["n_nodes"] != geometry.n_nodes:
        raise DataFileError(
            path / "meta.json",
            f"n_nodes is {meta['n_nodes']}, but the run's scene cuts a sheet of {geometry.n_nodes}: "
            "the run directory was changed after the run",
        )


def _check_tables(path: Path, meta: dict, probes: pd.DataFrame, markers: pd.DataFrame) -> None:
    # rows in time order per sheet, of sheets the run has; the markers' table is the probes'
    # rows, each repeated once per marker in marker order (they are written and committed together)
    n_sheets, n_markers = meta["n_sheets"], len(meta["markers"])
    check_index_column(path / "probes.csv", probes["sheet"].to_numpy(), n_sheets, "sheet")
    check_time_order(path / "probes.csv", probes["t"].to_numpy(), probes["sheet"].to_numpy(), 2, "sheet")
    expected = {
        "t": np.repeat(probes["t"].to_numpy(), n_markers),
        "sheet": np.repeat(probes["sheet"].to_numpy(), n_markers),
        "marker": np.tile(np.arange(n_markers), len(probes)),
    }
    if len(markers) != len(expected["t"]):
        raise DataFileError(
            path / "markers.csv",
            f"holds {len(markers)} rows, but the {len(probes)} committed probe rows of {n_markers} markers make "
            f"{len(expected['t'])}: the run directory was changed after the run",
        )
    for column, values in expected.items():
        wrong = np.flatnonzero(markers[column].to_numpy() != values)
        if len(wrong):
            row = int(wrong[0])
            raise DataFileError(
                path / "markers.csv",
                f"{column} is {markers[column].iat[row]:.10g}, but this row is marker {expected['marker'][row]} "
                f"of sheet {expected['sheet'][row]} at t = {expected['t'][row]:.10g} s (the probes' row "
                f"{row // max(n_markers, 1) + 2}): the rows were changed or reordered after the run",
                row + 2,
            )


def read_sheet_run(path: str | Path) -> SheetRun:
    """A sheet run directory as a :class:`SheetRun`; a DataFileError naming the file when
    it is damaged or not a sheet run: every file is checked against meta.json and the
    run's scene before any number of it is used (the geometry rebuilt from the scene, the
    tables' indices and time order, the frames' shape and times)."""
    path = Path(path)
    meta = read_json(path / "meta.json")
    _check_sheet_meta(path, meta)
    scenes = read_run_scenes(path, meta["n_sheets"], read_sheet_scene, "n_sheets")
    committed = meta["committed"]
    reached = committed["frames"]
    if not reached:
        raise DataFileError(path, "the run was interrupted before its first frame")
    try:
        stored = np.load(path / "frames.npy", mmap_mode="r")
        times = np.load(path / "frame_times.npy")
        with np.load(path / "geometry.npz") as archive:
            geometry = {name: archive[name] for name in GEOMETRY_ARRAYS}
    except (ValueError, OSError, EOFError, KeyError) as exc:
        raise DataFileError(path, f"cannot be read as a sheet run ({exc}): the run directory is damaged") from None
    _check_geometry(path, meta, scenes[0], geometry)
    expected = (len(times), meta["n_sheets"], meta["n_nodes"], 3)
    if stored.shape != expected or reached > expected[0]:
        raise DataFileError(
            path / "frames.npy",
            f"holds frames of shape {stored.shape}, but the run recorded {expected} ({reached} committed): "
            "the run directory is damaged",
        )
    check_frame_times(path / "frame_times.npy", times[:reached])
    complete = meta["complete"]
    probes = read_committed_csv(
        path / "probes.csv", committed["probe_rows"], committed["probe_bytes"], complete, SHEET_PROBE_COLUMNS
    )
    markers = read_committed_csv(
        path / "markers.csv", committed["marker_rows"], committed["marker_bytes"], complete, MARKER_COLUMNS
    )
    _check_tables(path, meta, probes, markers)
    frames = np.asarray(stored[:reached])
    # a sheet that diverged leaves NaN frames from its stop on: the run reached as far as
    # its last sheet to stop did
    alive = np.isfinite(frames).all(axis=(2, 3)).any(axis=1)
    reached = int(np.argmin(alive)) if not alive.all() else reached
    if not reached:
        raise DataFileError(path, f"recorded no frame: {_why_empty(meta)}")
    return SheetRun(
        path,
        scenes[0],
        meta,
        probes,
        markers,
        times[:reached],
        frames[:reached],
        geometry["lattice"],
        geometry["rest_positions"],
        geometry["faces"],
        geometry["clamped"],
        complete,
    )
