"""Sweep directories: results stream to disk per batch, and are read back as Recordings.

Layout of a sweep directory::

    sweep.json              fingerprint of the expanded sweep, the batch layout, the spec
    variants.csv            variant, batch and the swept field values (written first)
    summary/batch-NNNN.parquet   per variant: parameters and summary metrics
    probes/batch-NNNN.parquet    probe series, long format (variant, t and the probes the
                                 sweep kept, :data:`PROBE_RECORDS`: by default those its
                                 summary is measured from; a sheet's markers as
                                 marker_K_x, _y, _z), zstd-compressed, the floats' bytes
                                 split by significance (lossless)
    frames/batch-NNNN.npy        optional shape frames [frame, variant-in-batch, node, xy]
                                 (a sheet's: xyz)
    summary.parquet, summary.csv merged summaries, written when every batch is done

``pandas.read_parquet(DIR / "probes")`` opens the whole probe store (one file per batch,
i.e. chunked by batch); ``xarray`` users convert with ``.set_index(["variant", "t"]).to_xarray()``.

sweep.json says its ``format`` (:data:`FORMAT`). Format 1 (no ``format`` key) was written
before the Latin hypercube became SciPy's, which draws other variants from the same seed:
such a directory is read back with the variants its variants.csv stores, and is not
resumed.

A batch is complete when its summary file exists. Every file is written through
:mod:`warpcloth.io.atomic`, so a killed process or a lost Dask worker leaves no
half-written result, and the same sweep run again computes only the batches that are
missing.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from warpcloth.errors import ArgumentError, DataFileError
from warpcloth.kernels import PROBE_FIELDS
from warpcloth.scene import COORDINATES, Sweep, expand
from warpcloth.scene.sweep import samples_latin_hypercube, variant_scenes

from .atomic import write_atomically, write_npy_atomically
from .json_file import json_text, read_json
from .provenance import provenance
from .recording import Recording, check_time_order, per_strip_parameters, select_variants

FORMAT = 2
"""The sweep directory format sweep.json states: 2 since the Latin hypercube became
:class:`scipy.stats.qmc.LatinHypercube` (other draws from a seed than format 1's own)."""

LIST_COLUMNS = ("half_cycle_amplitude_m", "log_decrement")
"""Summary columns holding a list per variant: in summary.parquet, not summary.csv."""


def read_parquet(path: Path, **options: object) -> pd.DataFrame:
    """A sweep's Parquet file, or a DataFileError saying it is damaged (a resumed sweep
    recomputes a batch whose files do not read)."""
    try:
        return pd.read_parquet(path, **options)
    except (OSError, pa.ArrowException, ValueError) as exc:
        raise DataFileError(
            path,
            f"cannot be read ({exc}); it is damaged: run the sweep again into its directory to recompute that batch",
        ) from None


def _readable(path: Path, frames: bool = False) -> bool:
    try:
        if frames:
            np.load(path, mmap_mode="r")
        else:
            pq.read_metadata(path)
    except (OSError, pa.ArrowException, ValueError, EOFError):
        return False
    return True


def _cell(value: object) -> object:
    return json.dumps(value) if isinstance(value, list) else value


class SweepDirectory:
    """One sweep directory on disk (see the module docstring)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.probes = "all"
        """What its batches keep of the probe series (:data:`PROBE_RECORDS`), as sweep.json says."""

    def summary_path(self, batch: int) -> Path:
        """The per-batch summary file, whose existence marks the batch done."""
        return self.path / "summary" / f"batch-{batch:04d}.parquet"

    def is_done(self, batch: int) -> bool:
        """Whether ``batch`` has been written completely and its files still read (a
        damaged batch counts as not done, so a resumed sweep recomputes it)."""
        summary, probes = self.summary_path(batch), self.path / "probes" / f"batch-{batch:04d}.parquet"
        frames = self.path / "frames" / f"batch-{batch:04d}.npy"
        return (
            summary.exists()
            and _readable(summary)
            and (self.probes == "none" or _readable(probes))
            and (not frames.exists() or _readable(frames, frames=True))
        )

    def prepare(
        self,
        sweep: Sweep,
        plan: Callable[[], list[list[int]]],
        coordinates: str = COORDINATES,
        probes: str = "all",
    ) -> list[list[int]]:
        """The batch layout: the stored one when this directory holds the same sweep
        keeping the same ``probes`` (resume), else ``plan()``'s, written with the manifest
        (stating ``coordinates``, the frame of the positions stored, and ``probes``) and
        variants.csv."""
        manifest = self.path / "sweep.json"
        self.probes = probes
        if manifest.exists():
            stored = read_json(manifest)
            check_coordinates(manifest, stored, coordinates)
            if stored["fingerprint"] != sweep.fingerprint:
                why = (
                    "was written by an older warpcloth (sweep format 1), whose Latin hypercube drew other "
                    "variants from the same seed"
                    if _older_sample(stored)
                    else "holds a different sweep (its scenes or sweep spec changed)"
                )
                raise ArgumentError("out", f"{self.path} {why}; choose a new --out directory to start this one")
            kept = stored.get("probes", "all")  # before --probes, a sweep kept every probe
            if kept != probes:
                raise ArgumentError(
                    "probes",
                    f"{self.path} keeps {kept!r} probes, not {probes!r}: resume it with --probes {kept}, "
                    "or choose a new --out directory",
                )
            return stored["batches"]
        batches = plan()
        for sub in ("summary", "probes", "frames"):
            (self.path / sub).mkdir(parents=True, exist_ok=True)
        batch_of = {v: b for b, ids in enumerate(batches) for v in ids}
        table = pd.DataFrame(
            [
                {"variant": i, "batch": batch_of[i]} | {k: _cell(v) for k, v in a.items()}
                for i, a in enumerate(sweep.assignments)
            ]
        )
        write_atomically(self.path / "variants.csv", lambda p: table.to_csv(p, index=False))
        info = {
            "fingerprint": sweep.fingerprint,
            "n_variants": len(sweep.scenes),
            "keys": sweep.keys,
            "batches": batches,
            "sweep": sweep.spec,
            "base_scene": sweep.base,
            "complete": False,
            "coordinates": coordinates,
            "kind": sweep.kind,
            "probes": probes,
            "format": FORMAT,
            "discrepancy": sweep.discrepancy,
            "provenance": provenance(),
        }
        write_atomically(manifest, lambda p: p.write_text(json_text(info)))
        return batches

    def write_batch(
        self, batch: int, probes: dict[str, np.ndarray], summary_rows: list[dict], frames: np.ndarray | None
    ) -> None:
        """Store one batch: probe columns (none but variant and t: no probe file), optional
        frames, then (last) its summary rows."""
        if set(probes) - {"variant", "t"}:
            table = pa.table(probes)
            floats = [name for name in table.column_names if name != "variant"]
            write_atomically(
                self.path / "probes" / f"batch-{batch:04d}.parquet",
                lambda p: pq.write_table(
                    table,
                    p,
                    compression="zstd",
                    use_dictionary=["variant"],
                    column_encoding=dict.fromkeys(floats, "BYTE_STREAM_SPLIT"),
                ),
            )
        if frames is not None:
            write_npy_atomically(self.path / "frames" / f"batch-{batch:04d}.npy", frames)
        summary = pa.Table.from_pylist(summary_rows)
        write_atomically(self.summary_path(batch), lambda p: pq.write_table(summary, p))  # last: marks it done

    def finish(self, n_batches: int) -> pd.DataFrame:
        """Merge every batch's summary into summary.parquet and summary.csv, mark the
        sweep complete, and return the merged summary (sorted by variant)."""
        summary = pd.concat([read_parquet(self.summary_path(b)) for b in range(n_batches)])
        summary = summary.sort_values("variant").reset_index(drop=True)
        write_atomically(self.path / "summary.parquet", lambda p: summary.to_parquet(p, index=False))
        scalar = [c for c in summary.columns if c not in LIST_COLUMNS]
        write_atomically(self.path / "summary.csv", lambda p: summary[scalar].to_csv(p, index=False))
        manifest = self.path / "sweep.json"
        info = read_json(manifest) | {"complete": True}
        write_atomically(manifest, lambda p: p.write_text(json_text(info)))
        return summary


def check_coordinates(manifest: Path, info: dict, coordinates: str = COORDINATES) -> None:
    """Refuse a sweep whose positions are not in ``coordinates`` (a strip's from the clamp
    edge, or a sheet's :data:`~warpcloth.io.sheet_run_dir.SHEET_COORDINATES`): a sweep of
    the other kind of scene, or an older warpcloth's, which measured from the clamp's top."""
    if info.get("coordinates") == coordinates:
        return
    stored, ours = info.get("kind", "strip"), "strip" if coordinates == COORDINATES else "sheet"
    if stored != ours:
        raise DataFileError(
            manifest, f"holds a sweep of {stored} scenes, not of {ours} scenes; choose a new --out directory"
        )
    raise DataFileError(
        manifest,
        "does not say its positions are from the clamp edge (an older warpcloth "
        "measured them from the clamp's top); run the sweep again into a new --out directory",
    )


def _older_sample(info: dict) -> bool:
    """Whether a stored sweep drew its variants with format 1's own Latin hypercube."""
    return info.get("format", 1) < FORMAT and samples_latin_hypercube(info["sweep"])


def stored_sweep(path: Path, info: dict) -> Sweep:
    """The sweep a directory's sweep.json describes, expanded again; a format-1 Latin
    hypercube's sampled values are taken from its variants.csv instead (this SciPy
    sampler draws others from the seed)."""
    sweep = expand(info["base_scene"] | {"sweep": info["sweep"]}, max_variants=info["n_variants"])
    if not _older_sample(info):
        return sweep
    sampled = list(info["sweep"]["random"]["ranges"])
    try:
        table = pd.read_csv(path / "variants.csv").sort_values("variant")
        values = table[sampled].to_numpy(dtype=float)
    except (OSError, KeyError, ValueError, pd.errors.ParserError) as exc:
        raise DataFileError(
            path / "variants.csv",
            f"cannot be read ({exc}); a sweep of format 1 is labelled by the variants it stores there",
        ) from None
    if len(values) != len(sweep.assignments):
        raise DataFileError(
            path / "variants.csv",
            f"lists {len(values)} variants, sweep.json "
            f"{len(sweep.assignments)}; a sweep of format 1 is labelled by the variants it stores",
        )
    assignments = [
        a | dict(zip(sampled, map(float, row), strict=True)) for a, row in zip(sweep.assignments, values, strict=True)
    ]
    return Sweep(sweep.base, sweep.spec, sweep.keys, assignments, variant_scenes(sweep.base, assignments))


def read_sweep(path: Path, variants: str | None, where: str | None) -> Recording:
    """Selected variants of a sweep directory run with ``--frames``, as a Recording."""
    info = read_json(path / "sweep.json")
    if info.get("kind") == "sheet":
        raise DataFileError(
            path,
            "is a sweep of sheet scenes: its summary is plotted with --metric and --x, and its "
            "probes/ and frames/ ([frame, variant in batch, node, xyz]) are read with pandas and numpy; "
            "the views of a run's variants take a strip sweep",
        )
    check_coordinates(path / "sweep.json", info)
    if info.get("probes", "all") != "all":
        raise DataFileError(
            path,
            f"kept {info['probes']!r} of its probe series (--probes {info['probes']}); the views of a run's "
            "variants need every probe: run the sweep with --probes all --frames into a new --out directory",
        )
    sweep = stored_sweep(path, info)
    if sweep.fingerprint != info["fingerprint"]:
        raise DataFileError(
            path,
            "its variants no longer resolve to the scenes that were simulated "
            "(a material file it uses has changed?); the stored results cannot be labelled",
        )
    parameters = per_strip_parameters(sweep.strips)
    parameters.insert(0, "variant", np.arange(len(sweep.scenes)))
    chosen = select_variants(parameters, variants, where)
    where_is = {v: (b, k) for b, ids in enumerate(info["batches"]) for k, v in enumerate(ids)}
    needed = sorted({where_is[v][0] for v in chosen})
    missing = [b for b in needed if not (path / "frames" / f"batch-{b:04d}.npy").is_file()]
    if missing:
        raise DataFileError(
            path,
            f"has no shape frames for batch {missing[0]}: that batch ran without --frames "
            "(or has not finished); a resumed sweep keeps finished batches, so run it with "
            "--frames into a new --out directory",
        )
    try:
        stores = {b: np.load(path / "frames" / f"batch-{b:04d}.npy", mmap_mode="r") for b in needed}
    except (OSError, ValueError, EOFError) as exc:
        raise DataFileError(
            path / "frames",
            f"a batch's frames cannot be read ({exc}); run the sweep again into its directory to recompute it",
        ) from None
    n_frames = min(len(s) for s in stores.values())
    frames = np.stack([stores[where_is[v][0]][:n_frames, where_is[v][1]] for v in chosen], axis=1)
    tables = {
        b: read_parquet(
            path / "probes" / f"batch-{b:04d}.parquet", filters=[("variant", "in", [int(v) for v in chosen])]
        )
        for b in needed
    }
    for b, table in tables.items():
        check_time_order(path / "probes" / f"batch-{b:04d}.parquet", table["t"].to_numpy(), table["variant"].to_numpy())
    probes = pd.concat(tables.values())
    probes = probes[["t", "variant", *PROBE_FIELDS]]
    frame_times = np.arange(n_frames) / sweep.scenes[0].output.frame_rate_hz
    return Recording(
        path,
        chosen,
        [sweep.strips[i] for i in chosen],
        frame_times,
        frames,
        probes,
        parameters.iloc[chosen].reset_index(drop=True),
    )
