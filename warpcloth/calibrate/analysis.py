"""The swing metrics of anything that swings, measured by the one ruler
(:func:`~warpcloth.metrics.swing_summary`) on one time window: measured traces, run
directories and sweep directories, so a table of lab against simulation is one call. A
record longer than another is not compared on its extra time (a decaying swing's mean
decrement depends on how many half-cycles it includes): the window is the records'
overlap unless chosen (:func:`comparison_window`), and every row says which it was. A
measured trace's first period comes with its standard uncertainty (``first_period_u_s``)
from the noise the trace shows (:func:`~warpcloth.calibrate.noise.difference_noise`); a
simulation's has none (NaN)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from warpcloth import bodies
from warpcloth.errors import DataFileError
from warpcloth.io.json_file import read_json
from warpcloth.io.load import load_recording
from warpcloth.io.measured import LaserTrace, read_measurement
from warpcloth.io.sweep_dir import read_parquet, stored_sweep
from warpcloth.metrics import TIME_TOLERANCE_S, comparison_window, swing_summary

from .noise import difference_noise


@dataclass(frozen=True)
class SwingRecord:
    """One swinging series: a measured trace, or one variant of a run or sweep (SI)."""

    source: str
    variant: int | None
    t: np.ndarray
    laser: np.ndarray
    tip: np.ndarray | None  # the free end's x, for a run whose strip misses the laser line
    starts_at_rest: bool  # its first sample is the release
    measured: bool

    @property
    def span(self) -> tuple[float, float]:
        """First and last sample time (s); NaN for a record with no samples (a strip that
        diverged before t = 0)."""
        return (float(self.t[0]), float(self.t[-1])) if len(self.t) else (math.nan, math.nan)


def swing_records(source: str | Path, starts_at_rest: bool = True) -> list[SwingRecord]:
    """The series of a measured trace, or of every variant of a run or sweep directory.

    A measured trace (``t, x``) is taken to start at the release unless
    ``starts_at_rest`` is False; a run's or sweep's own scenes say whether they do.
    """
    path = Path(source)
    what = "sweep" if (path / "sweep.json").is_file() else "run" if (path / "meta.json").is_file() else None
    kind = (
        (read_json(path / "sweep.json").get("kind", "strip") if what == "sweep" else bodies.of_run(path).name)
        if what
        else "strip"
    )
    if kind != "strip":
        raise DataFileError(
            path,
            f"is a {kind} {what}: analyse measures a strip's swing (its laser line and tip); a {kind}'s own metrics "
            f"(its markers' peak displacements, its shear) are "
            + ("in the sweep's summary.csv" if what == "sweep" else "what `warpcloth run` printed, and `plot` draws"),
        )
    if (path / "sweep.json").is_file() and not (path / "summary.parquet").is_file():
        raise DataFileError(path, "the sweep has not finished (no summary.parquet); rerun it to complete it")
    if (path / "sweep.json").is_file():  # its probe store: a sweep need not have kept shape frames
        info = read_json(path / "sweep.json")
        if info.get("probes") == "none":
            raise DataFileError(
                path,
                "kept no probe series (--probes none): its swing metrics are in its summary.csv, "
                "measured as analyse measures them",
            )
        scenes = stored_sweep(path, info).scenes
        probes = read_parquet(path / "probes").sort_values(["variant", "t"], kind="stable")
        return [
            SwingRecord(
                str(path),
                int(variant),
                rows["t"].to_numpy(),
                rows["laser_x"].to_numpy(),
                rows["tip_x"].to_numpy(),
                scenes[int(variant)].release.enabled,
                False,
            )
            for variant, rows in probes.groupby("variant")
        ]
    if (path / "meta.json").is_file():
        recording = load_recording(path)
        records = []
        for j, variant in enumerate(recording.variants):
            probes = recording.probes[recording.probes["variant"] == variant]
            records.append(
                SwingRecord(
                    str(path),
                    int(variant),
                    probes["t"].to_numpy(),
                    probes["laser_x"].to_numpy(),
                    probes["tip_x"].to_numpy(),
                    recording.scenes[j].release.enabled,
                    False,
                )
            )
        return records
    measured = read_measurement(source, argument="source")
    if not isinstance(measured, LaserTrace):
        raise DataFileError(str(source), "holds tracked shapes; analyse needs a displacement trace (t_s, x_mm)")
    return [SwingRecord(str(source), None, measured.t, measured.x, None, starts_at_rest, True)]


def swing_row(record: SwingRecord, window: tuple[float, float] | None = None) -> dict:
    """The record's swing metrics on ``window`` (default: the whole record), with the window.

    A window that starts after the record's first sample does not start at the release."""
    lower, upper = window or record.span
    inside = (record.t >= lower - TIME_TOLERANCE_S) & (record.t <= upper + TIME_TOLERANCE_S)
    t, laser = record.t[inside], record.laser[inside]
    at_rest = record.starts_at_rest and not lower > record.span[0] + TIME_TOLERANCE_S
    if record.measured:
        metrics = swing_summary(t, laser, None, at_rest, noise=difference_noise([laser])) | {"signal": "measured x"}
    else:
        metrics = swing_summary(t, laser, record.tip[inside], at_rest)
    return {
        "source": record.source,
        "variant": record.variant,
        "from_s": lower,
        "to_s": upper,
        "signal": metrics["signal"],
        "first_period_s": metrics["first_period_s"],
        "first_period_u_s": metrics.get("first_period_u_s", float("nan")),
        "first_amplitude_mm": metrics["first_amplitude_m"] * 1e3,
        "mean_log_decrement": metrics["mean_log_decrement"],
        "n_half_cycles": metrics["n_half_cycles"],
        "log_decrement": json.dumps(np.asarray(metrics["log_decrement"]).tolist()),
    }


def analyse(
    sources: str | Path | list[str | Path],
    starts_at_rest: bool = True,
    t_from: float | None = None,
    t_to: float | None = None,
) -> list[dict]:
    """One row of swing metrics per measured trace and per variant of a run or sweep,
    every one on the same window (:func:`comparison_window`: the overlap of all the
    records unless ``t_from``/``t_to`` choose it); each row holds ``from_s`` and ``to_s``."""
    sources = sources if isinstance(sources, list) else [sources]
    records = [record for source in sources for record in swing_records(source, starts_at_rest)]
    # a record without samples (diverged before t = 0) gets its row of NaNs, not a say in the window
    spans = {
        f"{r.source}" + ("" if r.variant is None else f" variant {r.variant}"): r.span for r in records if len(r.t)
    }
    if not spans:
        raise DataFileError(
            ", ".join(str(s) for s in sources), "holds no samples after t = 0 (every strip diverged before it)"
        )
    window = comparison_window(spans, t_from, t_to)
    return [swing_row(record, window) for record in records]


__all__ = ["SwingRecord", "analyse", "comparison_window", "swing_records", "swing_row"]
