"""Running a sweep: batches as Dask tasks, each streamed to the sweep directory
(:mod:`warpcloth.io.sweep_dir`) as it finishes, resumable.

Each strip's result does not depend on the batch it ran in (tests/test_batch.py), nor
does each sheet's (tests/test_sheet_sweep.py), so the final results are identical however
often the sweep was interrupted. A sweep of sheet scenes runs through the same directory,
threads, Dask tasks and resume; only how its batch is simulated
(:func:`sheet_sweep_batch`), its size estimates and its summary's metrics
(:func:`~warpcloth.metrics.sheet_metrics`) are its own.
"""

from __future__ import annotations

import json
import os
import re
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from warpcloth import bodies
from warpcloth.core.resources import check_disk, check_memory
from warpcloth.errors import ArgumentError, InternalError, checked_count, checked_instance, checked_path
from warpcloth.io import PROBE_RECORDS
from warpcloth.io.sweep_dir import SweepDirectory
from warpcloth.io.writing import claim_result
from warpcloth.kernels import PROBE_FIELDS
from warpcloth.kernels.exp_lanes import requested_width
from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS
from warpcloth.runs import sheet_result_metrics, simulate
from warpcloth.scene import Scene, Sweep, scene_from_dict
from warpcloth.scene.sheet import SheetScene, sheet_scene_from_dict
from warpcloth.scene.sheet_build import build_sheets, sheet_geometry
from warpcloth.sheet import simulate_sheets
from warpcloth.strip.model import init_warp_quietly, machine_device

WORKER_MEMORY_BYTES = 1 << 30  # per-batch result memory a worker may hold
MAX_WORKERS_PER_CORE = 4
BATCHES_PER_WORKER = 8  # enough batches for balance, progress and resume granularity
SUMMARY_SCALARS = (
    "first_period_s",
    "first_amplitude_m",
    "mean_log_decrement",
    "n_half_cycles",
    "peak_tip_speed_m_per_s",
    "hysteresis_work_J",
    "damping_work_J",
    "diverged",
    "diverged_time_s",
    "diverged_phase",
    "diverged_quantity",
)


def _recorded(scene: Scene) -> tuple[int, int]:
    # probe samples and shape frames of one strip's record, as Python integers
    return (
        int(scene.run.duration_s / scene.output_interval) + 1,
        int(scene.run.duration_s * scene.output.frame_rate_hz) + 1,
    )


def strip_memory_bytes(scene: Scene, frames: bool) -> int:
    """Memory one strip's recorded results take while its batch runs (probes and frames
    twice: as recorded and as written)."""
    n_samples, n_frames = _recorded(scene)
    return (
        8 * len(PROBE_FIELDS) * n_samples * 2
        + 16 * 8 * scene.n_nodes
        + (16 * scene.n_nodes * n_frames * 2 if frames else 0)
    )


def strip_summary_probes(scene: Scene) -> list[str]:
    """The probes a strip's summary is measured from (and `warpcloth analyse` of the sweep
    measures again): the laser line's and the free end's x."""
    return ["laser_x", "tip_x"]


def strip_disk_bytes(scene: Scene, frames: bool, probes: str = "all") -> int:
    """Bytes one strip's files take in the sweep directory at most: its probe rows
    (variant, t and the ``probes`` kept, uncompressed) and, with ``frames``, its frames."""
    n_samples, n_frames = _recorded(scene)
    row = _row_bytes(probes, len(PROBE_FIELDS), len(strip_summary_probes(scene)))
    return row * n_samples + (16 * scene.n_nodes * n_frames if frames else 0)


def _row_bytes(probes: str, every: int, summary: int) -> int:
    # one sample's row in the probe store: variant (int32), t and the columns kept (float64)
    kept = {"all": every, "summary": summary}.get(probes)
    return 0 if kept is None else 4 + 8 + 8 * kept


def _sheet_recorded(scene: SheetScene) -> tuple[int, int, int]:
    # probe samples, shape frames and nodes of one sheet's record, as Python integers
    n_frames = int(scene.run.duration_s * scene.output.frame_rate_hz) + 1
    return (n_frames - 1) * scene.output.probes_per_frame + 1, n_frames, sheet_geometry(scene).n_nodes


def _n_markers(scene: SheetScene) -> int:
    return len(scene.output.markers_ij) + len(scene.output.markers_mm)


def sheet_memory_bytes(scene: SheetScene, frames: bool) -> int:
    """Memory one sheet's recorded results take while its batch runs (probes, markers and
    frames twice: as recorded and as written)."""
    n_samples, n_frames, n_nodes = _sheet_recorded(scene)
    return 8 * (len(SHEET_PROBE_FIELDS) + 3 * _n_markers(scene)) * n_samples * 2 + (
        24 * n_nodes * n_frames * 2 if frames else 0
    )


def sheet_summary_probes(scene: SheetScene) -> list[str]:
    """The probes a sheet's summary's marker metrics are measured from: the clamp's
    displacement and the markers' positions (its energies are in the summary already)."""
    return ["clamp_displacement", *marker_columns(_n_markers(scene))]


def sheet_disk_bytes(scene: SheetScene, frames: bool, probes: str = "all") -> int:
    """Bytes one sheet's files take in the sweep directory at most: its probe rows
    (variant, t and the ``probes`` kept, the markers' x, y, z among them, uncompressed)
    and, with ``frames``, its frames."""
    n_samples, n_frames, n_nodes = _sheet_recorded(scene)
    row = _row_bytes(probes, len(SHEET_PROBE_FIELDS) + 3 * _n_markers(scene), len(sheet_summary_probes(scene)))
    return row * n_samples + (24 * n_nodes * n_frames if frames else 0)


def memory_bytes(scene: Scene | SheetScene, frames: bool) -> int:
    """Memory one variant's recorded results take while its batch runs (its body's hook)."""
    return bodies.of_scene(scene)("memory_bytes", scene, frames)


def disk_bytes(scene: Scene | SheetScene, frames: bool, probes: str = "all") -> int:
    """Bytes one variant's files take in the sweep directory (its body's hook)."""
    return bodies.of_scene(scene)("disk_bytes", scene, frames, probes)


def default_max_batch(scene: Scene | SheetScene, n_variants: int, workers: int, frames: bool) -> int:
    """Largest batch whose recorded results fit a worker's memory budget, and small
    enough that every worker gets several batches."""
    memory_cap = max(1, WORKER_MEMORY_BYTES // memory_bytes(scene, frames))
    balance = -(-n_variants // (BATCHES_PER_WORKER * max(1, workers)))
    return max(1, min(memory_cap, balance))


def check_sweep_fits(
    sweep: Sweep,
    batches: list[list[int]],
    pending: list[int],
    workers: int | None,
    frames: bool,
    out: Path,
    probes: str = "all",
) -> None:
    """Refuse, before its first batch, a sweep whose batches running side by side would
    not fit in memory (``workers`` at once; None: on a Dask cluster, whose memory is its
    own) or whose remaining results would not fit the free disk of ``out``."""
    what = "probes and frames" if frames else "probes"
    if workers is not None:
        sizes = sorted((sum(memory_bytes(sweep.scenes[v], frames) for v in batches[b]) for b in pending), reverse=True)[
            : max(1, workers)
        ]
        check_memory(
            sum(sizes),
            f"the recorded {what} of {len(sizes)} sweep batch(es) running side by side",
            "run fewer at once (--workers) or smaller ones (--max-batch), or record less "
            "(output.probes_per_frame, output.frame_rate_hz, run.duration_s)",
        )
    variants = [v for b in pending for v in batches[b]]
    check_disk(
        out,
        sum(disk_bytes(sweep.scenes[v], frames, probes) for v in variants),
        f"the {what} of the sweep's {len(variants)} remaining variants",
        "free space, choose another --out, or record less (output.probes_per_frame, output.frame_rate_hz, "
        "run.duration_s" + (", or leave out --frames)" if frames else ")"),
    )


@dataclass
class SimulatedBatch:
    """One batch simulated, as its files need it: the probe store's columns ``names``,
    their series ``values[sample, column, variant]`` at ``t`` and which samples each
    variant recorded (``ok[sample, variant]``: not after a divergence), per variant its
    summary's metric columns, the frames (or None), and the steps done (strip- or node-)."""

    names: list[str]
    t: np.ndarray
    values: np.ndarray
    ok: np.ndarray
    metrics: list[dict[str, object]]
    frames: np.ndarray | None
    steps: int


def _as_scenes(items: list, from_dict: Callable[[dict], Any]) -> list:
    # A batch run in this process is handed its scenes; one run on a Dask worker, their
    # dicts (a scene's round trip through a dict costs as much Python as its summary).
    return [item if isinstance(item, (Scene, SheetScene)) else from_dict(item) for item in items]


def strip_sweep_batch(items: list, device: str | None, frames: bool) -> SimulatedBatch:
    """A batch of strips (scenes, or their dicts), one launch sequence; each strip's swing
    metrics."""
    scenes = _as_scenes(items, scene_from_dict)
    # one thread per batch: the sweep already runs its batches on the cores
    result = simulate(scenes, device=device, on_divergence="record", keep_frames=frames, threads=1)
    ok = np.isfinite(result.probes[:, PROBE_FIELDS.index("tip_x")])
    # simulate measured each strip already (result.metrics: strip_result_metrics per strip)
    if result.metrics is None:  # simulate measures every strip it runs
        raise InternalError("a strip batch came back without its metrics")
    measured = result.metrics.to_dict("records")
    rows = [row | _overflows(result.reversal_memory, local) for local, row in enumerate(measured)]
    return SimulatedBatch(
        list(PROBE_FIELDS), result.t, result.probes, ok, rows, result.frames if frames else None, result.strip_steps
    )


def _overflows(reversal_memory: dict, local: int) -> dict[str, int]:
    # reversals a full masing memory could not store (no hysteresis in their loops)
    if not reversal_memory:
        return {}
    return {"reversal_overflows": int(np.asarray(reversal_memory["overflows"])[local])}


def marker_columns(n_markers: int) -> list[str]:
    """The probe store's columns of a sheet's markers: ``marker_K_x``, ``_y``, ``_z`` (m)."""
    return [f"marker_{k}_{axis}" for k in range(n_markers) for axis in "xyz"]


def sheet_sweep_batch(items: list, device: str | None, frames: bool) -> SimulatedBatch:
    """A batch of sheets (scenes, or their dicts) in the same launches; each sheet's
    :func:`~warpcloth.metrics.sheet_metrics` (NaN for a diverged one: what a sheet did
    before it diverged is no measurement of it)."""
    scenes = _as_scenes(items, sheet_scene_from_dict)  # resolved: checked as the sweep was expanded
    built = build_sheets(scenes, device)
    result = simulate_sheets(
        built.model, built.control, built.solver, built.recorder, on_divergence="record", keep_frames=frames, threads=1
    )
    n_samples, b, n_markers = len(result.t), len(scenes), result.markers.shape[2]
    markers = np.transpose(result.markers.reshape(n_samples, b, 3 * n_markers), (0, 2, 1))
    rows = [
        sheet_result_metrics(scene, result, local) | _overflows(result.reversal_memory, local)
        for local, scene in enumerate(scenes)
    ]
    return SimulatedBatch(
        [*SHEET_PROBE_FIELDS, *marker_columns(n_markers)],
        result.t,
        np.concatenate([result.probes, markers], axis=1),
        np.isfinite(result.probes[:, SHEET_PROBE_FIELDS.index("kinetic")]),
        rows,
        result.frames if frames else None,
        result.node_steps,
    )


def run_batch(
    out_dir: str,
    batch: int,
    variants: list[int],
    scenes: list,
    assignments: list[dict],
    device: str | None,
    frames: bool,
    kind: str = "strip",
    probes: str = "all",
) -> dict:
    """Simulate one batch of body ``kind`` (:mod:`warpcloth.bodies`) and write its files,
    keeping ``probes`` of its probe series (runs in a Dask worker, given the scenes' dicts,
    or in-process, given the scenes)."""
    init_warp_quietly()  # a worker process starts Warp afresh: no banner or notices in the results
    started = time.perf_counter()
    body = bodies.named(kind)
    done = body("sweep_batch", scenes, device, frames)
    wall = time.perf_counter() - started
    kept = {
        "all": done.names,
        "summary": body("summary_probes", _as_scenes(scenes[:1], body.hook("scene_from_dict"))[0]),
        "none": [],
    }[probes]
    columns: dict[str, list] = {"variant": [], "t": []} | {name: [] for name in kept}
    rows = []
    for local, variant in enumerate(variants):
        ok = done.ok[:, local]
        columns["variant"].append(np.full(ok.sum(), variant, dtype=np.int32))
        columns["t"].append(done.t[ok])
        for name in kept:
            columns[name].append(done.values[ok, done.names.index(name), local])
        row: dict[str, object] = {"variant": variant, "batch": batch}
        row |= {key: (json.dumps(v) if isinstance(v, list) else v) for key, v in assignments[local].items()}
        rows.append(row | done.metrics[local])
    SweepDirectory(out_dir).write_batch(batch, {k: np.concatenate(v) for k, v in columns.items()}, rows, done.frames)
    return {"batch": batch, "n_variants": len(variants), "steps": done.steps, "wall_s": wall}


def warm_sheet_kernel_cache(scenes: list[SheetScene], device: str | None) -> None:
    """:func:`warm_kernel_cache` for sheets: one short run per precision the batches use."""
    for precision in sorted({s.integrator.precision for s in scenes}):
        scene = next(s for s in scenes if s.integrator.precision == precision)
        data = scene.to_dict()
        data["release"]["settle_time_s"] = 0.0
        data["run"]["duration_s"] = scene.output_interval
        built = build_sheets([sheet_scene_from_dict(data)], device)
        simulate_sheets(
            built.model, built.control, built.solver, built.recorder, on_divergence="record", keep_frames=False
        )


def warm_kernel_cache(scenes: list[Scene], device: str | None) -> None:
    """Compile the kernels once in this process, so workers load them from Warp's cache
    instead of several processes compiling into it at once (Warp FAQ). Each kernel is a
    module of its own (kernels/strip.py), so one short run per (precision, scheme) that
    the batches use warms exactly what the workers will load."""
    configurations = {(s.integrator.precision, s.integrator.scheme) for s in scenes}
    for precision, scheme in sorted(configurations):
        scene = next(s for s in scenes if (s.integrator.precision, s.integrator.scheme) == (precision, scheme))
        data = scene.to_dict()
        data["release"]["enabled"] = False
        data["run"]["duration_s"] = scene.output_interval
        simulate(scene_from_dict(data), device=device, keep_frames=False, on_divergence="record", threads=1)


def run_sweep(
    sweep: Sweep,
    out: str | Path,
    *,
    max_batch: int | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    device: str | None = None,
    frames: bool = False,
    probes: str = "summary",
    progress: bool = False,
) -> pd.DataFrame:
    """Run (or resume) a sweep into ``out`` and return the merged per-variant summary.

    ``probes`` says what each variant's probe series keep (:data:`~warpcloth.io.sweep_dir.PROBE_RECORDS`):
    by default those its summary is measured from, ``"all"`` the full record (a
    resumed sweep keeps what it began with), ``"none"`` only the summary.

    The batches run in this process on ``workers`` threads (default: one per core; 0:
    one after another), each batch one launch sequence of its own (Warp releases the GIL
    during a CPU launch, so the threads fill the cores); with ``scheduler`` they are Dask
    tasks on that running cluster instead. Results do not depend on either (on a cluster
    whose machines differ in whether they take the paper's law's exponentials in groups,
    docs/model.md §9.4, by rounding). A sweep of sheet scenes runs the same way, each
    batch's sheets in one launch sequence.
    """
    checked_instance("sweep", sweep, Sweep, "warpcloth.load_sweep(name_or_path)")
    if workers is not None:
        checked_count("workers", workers, 0, " (0 runs the batches in this process)")
    cores = os.cpu_count() or 1
    if workers is not None and workers > MAX_WORKERS_PER_CORE * cores:
        raise ArgumentError(
            "workers",
            f"{workers} threads on {cores} cores would only wait on each other "
            f"(at most {MAX_WORKERS_PER_CORE * cores}); a cluster is reached with --scheduler",
        )
    if scheduler is not None and not (
        isinstance(scheduler, str) and re.match(r"^(\w+://)?[\w.\-\[\]:]+:\d+$", scheduler)
    ):
        raise ArgumentError("scheduler", f"{scheduler!r} is not a scheduler address (host:port or tcp://host:port)")
    if max_batch is not None:
        checked_count("max_batch", max_batch, 1)
    if probes not in PROBE_RECORDS:
        raise ArgumentError("probes", f"{probes!r} is not one of {', '.join(PROBE_RECORDS)}")
    requested_width()  # a bad WARPCLOTH_EXP_LANES is refused before the directory is laid out
    out = Path(checked_path("out", out))
    if out.is_dir() and any(out.iterdir()) and not (out / "sweep.json").is_file():
        # resuming is for the same sweep only; a run or other files are never mixed into
        held = "a run" if (out / "meta.json").is_file() else "files that are not a sweep"
        raise ArgumentError("out", f"{out} already holds {held}; choose another --out")
    claim_result(out, argument="out")  # two sweeps into one directory never write it at once
    directory = SweepDirectory(out)
    body = bodies.named(sweep.kind)
    n_workers = (os.cpu_count() or 1) if workers is None else workers
    if max_batch is None:
        max_batch = default_max_batch(sweep.scenes[0], len(sweep.scenes), n_workers, frames)
    at_once = None if scheduler is not None else max(1, n_workers)

    def planned() -> list[list[int]]:
        # a new sweep is sized as a whole before its directory is laid out
        layout = sweep.batches(max_batch)
        check_sweep_fits(sweep, layout, list(range(len(layout))), at_once, frames, out, probes)
        return layout

    batches = directory.prepare(sweep, planned, body.hook("coordinates"), probes)
    pending = [b for b in range(len(batches)) if not directory.is_done(b)]
    check_sweep_fits(sweep, batches, pending, at_once, frames, out, probes)  # a resumed one: what remains
    done = len(sweep.scenes) - sum(len(batches[b]) for b in pending)
    bar = tqdm(
        total=len(sweep.scenes), initial=done, unit="variant", desc="sweep", disable=not progress, dynamic_ncols=True
    )
    started = time.perf_counter()
    steps = 0

    def finished(info: dict) -> None:
        nonlocal steps
        steps += info["steps"]
        bar.update(info["n_variants"])
        bar.set_postfix_str(f"{steps / (time.perf_counter() - started):.3g} {body.steps}/s")

    def task(b: int, portable: bool = False) -> tuple:
        ids = batches[b]
        return (
            str(out),
            b,
            ids,
            [sweep.scenes[i].to_dict() if portable else sweep.scenes[i] for i in ids],
            [sweep.assignments[i] for i in ids],
            device,
            frames,
            sweep.kind,
            probes,
        )

    try:
        if pending:
            if scheduler is None or _here(device):
                # kernels compiled once before the batches start (a cluster's workers on
                # this machine share its cache; a GPU they have and it lacks, they compile for)
                body("warm", [sweep.scenes[batches[b][0]] for b in pending], device)
            if scheduler is not None:
                _run_on_dask(pending, task, finished, scheduler, sweep.fingerprint)
            elif n_workers == 0:
                for b in pending:
                    finished(run_batch(*task(b)))
            else:
                # Threads, not processes: Warp releases the GIL for a CPU launch, so one
                # thread per core runs batches side by side in this one process.
                pool = ThreadPoolExecutor(n_workers)
                try:
                    for future in as_completed([pool.submit(run_batch, *task(b)) for b in pending]):
                        finished(future.result())
                finally:
                    # on Ctrl-C (or a failed batch) the batches not yet started are dropped;
                    # the ones running finish their files (a thread cannot be stopped)
                    pool.shutdown(wait=True, cancel_futures=True)
    finally:
        bar.close()
    return directory.finish(len(batches))


def _here(device: str | None) -> bool:
    # whether this machine has the device (a cluster's workers may have one it lacks)
    try:
        machine_device(device)
    except ArgumentError:
        return False
    return True


def _run_on_dask(
    pending: list[int], task: Callable[..., tuple], finished: Callable[[dict], None], scheduler: str, fingerprint: str
) -> None:
    from dask.distributed import Client, as_completed

    client = Client(scheduler)
    try:
        futures = [
            client.submit(
                run_batch,
                *task(b, portable=True),
                key=f"warpcloth-{fingerprint[:12]}-batch-{b:04d}",
                pure=False,
                retries=2,
            )
            for b in pending
        ]
        for future in as_completed(futures):
            finished(future.result())
    finally:
        client.close()
