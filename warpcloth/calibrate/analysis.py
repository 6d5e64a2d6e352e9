"""The swing metrics of anything that swings, measured by the one ruler
(:func:`~warpcloth.metrics.swing_summary`): measured traces, run directories
and sweep directories, so a table of lab against simulation is one call. A measured
trace's first period comes with its standard uncertainty (``first_period_u_s``) from the
noise the trace shows (:func:`~warpcloth.calibrate.noise.difference_noise`); a
simulation's has none (NaN)."""

from __future__ import annotations

import json
from pathlib import Path

from warpcloth.errors import DataFileError
from warpcloth.io.load import load_recording
from warpcloth.io.measured import LaserTrace, bundled_data, read_measurement
from warpcloth.io.sweep_dir import read_parquet
from warpcloth.metrics import swing_summary

from .noise import difference_noise


def _row(source: str, variant: int | None, metrics: dict) -> dict:
    return {"source": source, "variant": variant, "signal": metrics.get("signal", "laser_x"),
            "first_period_s": metrics["first_period_s"],
            "first_period_u_s": metrics.get("first_period_u_s", float("nan")),
            "first_amplitude_mm": metrics["first_amplitude_m"] * 1e3,
            "mean_log_decrement": metrics["mean_log_decrement"], "n_half_cycles": metrics["n_half_cycles"],
            "log_decrement": json.dumps(metrics["log_decrement"]) if isinstance(metrics["log_decrement"], list)
            else metrics["log_decrement"]}


def analyse(source: str | Path, starts_at_rest: bool = True) -> list[dict]:
    """One row of swing metrics per measured trace, or per variant of a run or sweep.

    A measured trace (``t, x``) is taken to start at the release unless
    ``starts_at_rest`` is False; a run's or sweep's own scenes say whether they do. A
    sweep's rows are its summary's, computed when it ran by the same function.
    """
    path = Path(source)
    if (path / "sweep.json").is_file():
        summary = path / "summary.parquet"
        if not summary.is_file():
            raise DataFileError(path, "the sweep has not finished (no summary.parquet); rerun it to complete it")
        table = read_parquet(summary)
        return [_row(str(path), int(r["variant"]), {**r, "signal": "sweep summary",
                                                    "log_decrement": list(r["log_decrement"])})
                for _, r in table.iterrows()]
    if (path / "meta.json").is_file():
        recording = load_recording(path)
        rows = []
        for j, variant in enumerate(recording.variants):
            probes = recording.probes[recording.probes["variant"] == variant]
            metrics = swing_summary(probes["t"].to_numpy(), probes["laser_x"].to_numpy(), probes["tip_x"].to_numpy(),
                                    starts_at_rest=recording.scenes[j].release.enabled)
            rows.append(_row(str(path), int(variant), metrics))
        return rows
    measured = read_measurement(bundled_data(source), flag="INPUT")
    if not isinstance(measured, LaserTrace):
        raise DataFileError(str(source), "holds tracked shapes; analyse needs a displacement trace (t_s, x_mm)")
    metrics = swing_summary(measured.t, measured.x, None, starts_at_rest, noise=difference_noise([measured.x]))
    return [_row(str(source), None, metrics | {"signal": "measured x"})]


__all__ = ["analyse"]
