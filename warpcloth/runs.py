"""Running scenes: build the batch, simulate it, stream the run directory."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS

from . import bodies
from .core.result import RunResult
from .core.runner import check_divergence_policy, check_recording_fits, simulate_batch
from .errors import ArgumentError, ArgumentTypeError
from .io.recording import per_strip_parameters
from .io.run_dir import RunWriter, check_output_directory
from .io.sheet_run_dir import SHEET_COORDINATES
from .kernels.exp_lanes import requested_width
from .metrics import sheet_metrics, swing_summary
from .scene import COORDINATES, Scene, build_batch, load_scene
from .scene.overrides import Overrides, override_pairs
from .scene.sheet import SheetScene
from .scene.step import shared_auto_step
from .sheet.solver import QUANTITY
from .strip.state import checked_nodes


def simulate(scenes: Any, **options: Any) -> RunResult:
    """Run one batch of scenes of either body (one scene per variant; a strip's
    :class:`~warpcloth.scene.Scene` or a sheet's :class:`~warpcloth.scene.sheet.SheetScene`,
    :func:`~warpcloth.scene.load_scene` makes either) and return what it recorded. The
    options are the body's: :func:`simulate_strip_scenes` and :func:`simulate_sheet_scenes` list them
    (``device``, ``out``, ``progress``, ``on_divergence``, ``keep_frames``, ``overwrite``,
    ``threads``; strips also take initial positions and velocities)."""
    batch = [scenes] if not isinstance(scenes, Sequence) else list(scenes)
    if not batch:
        raise ArgumentError("scenes", "simulate needs at least one scene")
    requested_width()  # a bad WARPCLOTH_EXP_LANES is refused before anything runs, on any device
    return bodies.of_scenes(batch)("simulate", batch, **options)


def batch_of(scenes: Any, scene_type: type, body: str) -> list:
    """``scenes`` (one, or a sequence) as a non-empty list of ``scene_type``, or an error
    naming ``scenes``: what the body's ``simulate`` takes."""
    batch = [scenes] if isinstance(scenes, scene_type) else list(scenes)
    if not batch:
        raise ArgumentError("scenes", "simulate needs at least one scene")
    wrong = next((s for s in batch if not isinstance(s, scene_type)), None)
    if wrong is not None:
        raise ArgumentTypeError(
            "scenes",
            f"simulate_{body}_scenes takes {body} scenes (wc.load_scene(name_or_path) makes one), got {wrong!r}",
        )
    return batch


def simulate_strip_scenes(
    scenes: Scene | Sequence[Scene],
    *,
    device: str | None = None,
    out: str | Path | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
    keep_frames: bool = True,
    initial_positions: np.ndarray | None = None,
    initial_velocities: np.ndarray | None = None,
    overwrite: bool = False,
    threads: int | None = None,
) -> RunResult:
    """Run one batch of strips (one scene per strip) and return what it recorded.

    ``out`` streams the run directory (see :mod:`warpcloth.io.run_dir`) as the run
    proceeds. ``on_divergence="raise"`` stops at the first diverged strip with a
    DivergenceError (its ``result`` holds what was recorded); ``"record"`` lets the other
    strips go on. ``initial_positions`` / ``initial_velocities`` (``[node, variant, xy]``,
    m and m/s) replace the straight hanging start, e.g. with a mode shape; hinges start
    fresh there. Scenes whose step ``dt_s = "auto"`` chose alone share the step that suits
    them all (:func:`~warpcloth.scene.step.shared_auto_step`). An ``out`` that already
    holds something is refused unless ``overwrite``, and then replaced only once the new
    run is complete. On a CPU the batch's strips are shared among ``threads`` threads
    (default: every core this process may use; the results are bitwise the same for any
    count).
    """
    scenes = batch_of(scenes, Scene, "strip")
    check_divergence_policy(on_divergence)  # before the batch is built and its hinges set
    scenes = shared_auto_step(scenes)
    if initial_velocities is not None and initial_positions is None:
        raise ArgumentError(
            "initial_velocities",
            "given without initial_positions; give the start's positions too "
            "(e.g. the rest shape, warpcloth.scene.rest_positions)",
        )
    for argument, value in (("initial_positions", initial_positions), ("initial_velocities", initial_velocities)):
        if value is not None:
            checked_nodes(argument, value, scenes[0].n_nodes, len(scenes))
    if out is not None:
        check_output_directory(out, overwrite)
    batch = build_batch(scenes, device)
    check_recording_fits(batch.model, batch.control, batch.recorder, keep_frames)
    state = batch.model.state()
    if initial_positions is not None:
        state.set_positions(initial_positions, initial_velocities)
    sink = None
    if out is not None:
        frame_times = batch.recorder.schedule(batch.control, batch.solver).frame_times
        sink = RunWriter(out, scenes, batch.model.n_nodes, frame_times, overwrite=overwrite)
    parameters = {name: column.to_numpy() for name, column in per_strip_parameters(scenes).items()}
    result = simulate_batch(
        batch.model,
        batch.control,
        batch.solver,
        batch.recorder,
        state,
        sink=sink,
        progress=progress,
        on_divergence=on_divergence,
        keep_frames=keep_frames,
        labels=scenes,
        parameters=parameters,
        attrs={"coordinates": f"{COORDINATES}; t = 0 at the release"},
        threads=threads,
    )
    result.metrics = metrics_table(scenes, result)
    return result


def simulate_sheet_scenes(
    scenes: SheetScene | Sequence[SheetScene],
    *,
    device: str | None = None,
    out: str | Path | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
    keep_frames: bool = True,
    overwrite: bool = False,
    threads: int | None = None,
) -> RunResult:
    """Run one batch of sheet scenes (one sheet per scene, in the same launches; they must
    agree on what a batch shares: :func:`~warpcloth.scene.sheet_build.check_sheet_batch`)
    and return what it recorded; ``out`` streams the sheet run directory
    (:mod:`warpcloth.io.sheet_run_dir`), with the strip's refusal of an existing result
    unless ``overwrite``, which replaces it only once the new run is complete. The other
    options are :func:`simulate_strip_scenes`'."""
    from .io.sheet_run_dir import SheetRunWriter
    from .scene.sheet_build import build_sheets

    scenes = batch_of(scenes, SheetScene, "sheet")
    check_divergence_policy(on_divergence)
    if out is not None:
        check_output_directory(out, overwrite)
    batch = build_sheets(scenes, device)
    check_recording_fits(batch.model, batch.control, batch.recorder, keep_frames)
    sink = None
    if out is not None:
        frame_times = batch.recorder.schedule(batch.control, batch.solver).frame_times
        sink = SheetRunWriter(out, scenes, batch.model.geometry, batch.recorder.markers, frame_times, overwrite)
    result = simulate_batch(
        batch.model,
        batch.control,
        batch.solver,
        batch.recorder,
        sink=sink,
        progress=progress,
        on_divergence=on_divergence,
        keep_frames=keep_frames,
        labels=scenes,
        attrs={"coordinates": f"{SHEET_COORDINATES}; t = 0 at the release"},
        threads=threads,
    )
    result.metrics = metrics_table(scenes, result)
    return result


def strip_result_metrics(scene: Scene, result: RunResult, strip: int) -> dict[str, object]:
    """The swing metrics of strip ``strip`` of ``result``, a run of ``scene``, as ``run``
    prints them and a sweep's summary holds them (:func:`~warpcloth.metrics.swing_summary`
    of the laser and tip, its peak speed and the work hysteresis and damping took), measured
    on what it recorded before any divergence, and that divergence (when, in which phase,
    of what)."""
    kept = np.isfinite(result.probe("tip_x", strip))
    metrics = swing_summary(
        result.t[kept],
        result.probe("laser_x", strip)[kept],
        result.probe("tip_x", strip)[kept],
        starts_at_rest=scene.release.enabled,
    )
    metrics.pop("signal")
    report = next((d for d in result.diverged if d.body == strip), None)
    return metrics | {
        "peak_tip_speed_m_per_s": _peak(result.probe("tip_speed", strip)[kept]),
        "hysteresis_work_J": _last(result.probe("hysteresis_work", strip)[kept]),
        "damping_work_J": _last(result.probe("damping_work", strip)[kept]),
        "diverged": report is not None,
        "diverged_time_s": report.time_s if report else float("nan"),
        "diverged_phase": report.phase if report else "",
        "diverged_quantity": report.quantity if report else "",
    }


def _last(series: np.ndarray) -> float:
    # NaN for a strip with no recorded sample (it diverged during the hold, before t = 0)
    return float(series[-1]) if len(series) else float("nan")


def _peak(series: np.ndarray) -> float:
    return float(np.max(series)) if len(series) else float("nan")


def sheet_result_metrics(scene: SheetScene, result: RunResult, sheet: int) -> dict[str, object]:
    """:func:`~warpcloth.metrics.sheet_metrics` of sheet ``sheet`` of ``result``, a run of
    ``scene`` (its clamp's translation direction; NaN for a diverged sheet: what it did
    before it diverged is no measurement of it), and its divergence."""
    c = scene.clamp
    report = next((d for d in result.diverged if d.body == sheet), None)
    metrics = sheet_metrics(
        result.markers[:, sheet],
        result.probe("clamp_displacement", sheet),
        (c.direction_x, c.direction_y, c.direction_z),
        {name: result.probe(name, sheet) for name in SHEET_PROBE_FIELDS},
        result.energy_total()[:, sheet],
    )
    if report is not None:
        metrics = dict.fromkeys(metrics, float("nan"))
    return metrics | {
        "diverged": report is not None,
        "diverged_time_s": report.time_s if report else float("nan"),
        "diverged_phase": ("settle" if report.time_s < 0 else "record") if report else "",
        "diverged_quantity": QUANTITY[report.code][0] if report else "",
    }


def metrics_table(scenes: Sequence[Any], result: RunResult) -> pd.DataFrame:
    """One row per variant of ``result`` (a run of ``scenes``, strips or sheets): its
    body's metrics, as a sweep's summary has them."""
    measure: Callable[[Any, RunResult, int], dict[str, object]] = (
        sheet_result_metrics if result.body == "sheet" else strip_result_metrics
    )
    rows = [measure(scene, result, j) for j, scene in enumerate(scenes)]
    return pd.DataFrame(rows, index=pd.RangeIndex(len(rows), name="variant"))


def run(scene: Any, overrides: Overrides = (), **kwargs: Any) -> RunResult:
    """Load a scene (path or bundled name), apply overrides, simulate it.

    ``overrides`` are ``"key=value"`` strings or a mapping ``{"damping.gamma_per_s": 0.5}``
    (values as Python numbers, strings, booleans or lists). Keyword arguments go to
    :func:`simulate` (``out``, ``device``, ``progress``, ...).
    """
    if not isinstance(scene, str | Path):
        if override_pairs(overrides):
            raise ArgumentTypeError(
                "overrides", "apply to a scene being loaded; a Scene is immutable (load it with them)"
            )
    else:
        scene = load_scene(scene, overrides)
    return simulate(scene, **kwargs)
