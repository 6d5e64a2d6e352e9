"""Running a batch of any body: chunked launches sized to the wall clock, progress, the
divergence policy, the record buffers and streaming each finished chunk to a sink (a run
directory writer). The strip's and the sheet's runs are this one loop."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
import warp as wp
from tqdm import tqdm

from warpcloth.errors import ArgumentError, ArgumentTypeError, DivergenceError, LongRunWarning

from .divergence import DivergenceMonitor
from .resources import check_memory, duration_text
from .result import RunResult
from .schedule import OutputChunk, Schedule, sample_bounds
from .solver import Solver

LONG_RUN_STEPS = 10**7
"""Steps of each body past which a run says, before it starts, how many and how long
(a tenth of the default ``integrator.max_steps``, where it is refused)."""
TARGET_LAUNCH_SECONDS = 0.5  # long enough to amortise launch cost, short enough for progress
BUFFER_BYTES = 64 * 2**20  # cap on the per-chunk probe, table and frame buffers
DIVERGENCE_POLICIES = ("raise", "record")


def available_cores() -> int:
    """The CPU cores this process may run on (its affinity, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_divergence_policy(on_divergence: object) -> None:
    """An ArgumentError unless ``on_divergence`` is one of :data:`DIVERGENCE_POLICIES`."""
    if on_divergence not in DIVERGENCE_POLICIES:
        raise ArgumentError("on_divergence", f"must be 'raise' or 'record', got {on_divergence!r}")


def checked_threads(threads: object) -> int:
    """The CPU threads a run may use: ``threads``, or the cores this process may run on
    when None; anything but a whole number ≥ 1 is refused, naming it."""
    if threads is None:
        return available_cores()
    if isinstance(threads, bool) or not isinstance(threads, int | np.integer):
        raise ArgumentTypeError("threads", f"must be a whole number of threads, got {threads!r}")
    if threads < 1:
        raise ArgumentError("threads", f"must be at least 1, got {threads}")
    return int(threads)


@dataclass(frozen=True)
class SampleTable:
    """A per-sample record besides the probes that a recorder declares (a sheet's
    markers): ``count`` entries of ``dim`` components per body and sample, which the
    kernel writes into the device buffer the runner puts in the settings struct's
    ``settings_field``; ``[sample, body, entry, component]`` on the host."""

    name: str
    count: int
    dim: int
    settings_field: str


class Sink(Protocol):
    """Where a run streams its results as they are produced."""

    def write_samples(
        self, t: np.ndarray, probes: np.ndarray, tables: dict[str, np.ndarray], valid: np.ndarray
    ) -> None:
        """Append samples: times, probes ``[sample, field, body]``, the recorder's tables
        ``{name: [sample, body, entry, component]}``, and which (sample, body) are valid."""

    def write_frames(self, first: int, frames: np.ndarray) -> None:
        """Store frames ``[frame, body, node, component]`` from frame index ``first`` on."""

    def close(self, diverged: list, extra: dict) -> None:
        """Finish: the run ended (completely, or at a divergence it reports)."""


def check_recording_fits(model: Any, control: Any, recorder: Any, keep_frames: bool = True) -> None:
    """Refuse, before anything is allocated, a run whose recorded results (and output
    schedule) would not fit in memory (:func:`~warpcloth.core.resources.check_memory`)."""
    b, n, nq = model.n_bodies, model.n_nodes, len(model.probes.fields)
    per_sample = nq + sum(t.count * t.dim for t in recorder.tables(model))
    k_min, k_max = sample_bounds(recorder, control.release_time)
    n_frames = k_max // recorder.probes_per_frame + 1
    # the schedule's own arrays (steps, times: 8 B per sample each) and the recorded results
    check_memory(
        16 * (k_max - k_min + 1)
        + 8 * (k_max + 1) * per_sample * b
        + (8 * model.dim * n_frames * b * n if keep_frames else 0),
        f"the recorded probes{' and frames' if keep_frames else ''} of {b} {model.body}(s)",
        "record less (output.probes_per_frame, output.frame_rate_hz, run.duration_s), run fewer "
        f"{model.body}s at once (sweep --max-batch), or keep frames only on disk (keep_frames=False)",
    )


class RecordBuffers:
    """The device buffers one launch fills (at most :data:`BUFFER_BYTES` each) and the host
    arrays of the whole record they are copied into, chunk by chunk."""

    def __init__(
        self, model: Any, schedule: Schedule, tables: tuple[SampleTable, ...], settings: Any, keep_frames: bool
    ) -> None:
        b, n, nq, dim = model.n_bodies, model.n_nodes, len(model.probes.fields), model.dim
        self.schedule = schedule
        self.dim = dim
        self.probes = np.full((len(schedule.kept), nq, b), np.nan)
        self.frames = np.full((len(schedule.frame_samples), b, n, dim), np.nan) if keep_frames else None
        self.tables = {t.name: np.full((len(schedule.kept), b, t.count, t.dim), np.nan) for t in tables}
        ppf = schedule.probes_per_frame
        per_sample = 8 * b * (nq + sum(max(t.count, 1) * t.dim for t in tables))
        cap = max(1, min(len(schedule.steps), BUFFER_BYTES // per_sample))
        cap_frames = max(1, min(len(schedule.frame_samples), BUFFER_BYTES // (8 * dim * n * b)))
        self.capacity = min(cap, cap_frames * ppf)
        """The most output samples one launch may record."""
        self.probe_buffer = wp.zeros((self.capacity, nq, b), dtype=model.scalar, device=model.device)
        self.frame_buffer = wp.zeros((self.capacity // ppf + 1, n, b), dtype=model.position_type, device=model.device)
        self.table_buffers = {}
        for t in tables:
            vector = wp.types.vector(length=t.dim, dtype=model.scalar)
            buffer = wp.zeros((self.capacity, max(t.count, 1), b), dtype=vector, device=model.device)
            setattr(settings, t.settings_field, buffer)
            self.table_buffers[t.name] = (buffer, t.count)

    def chunk(self, i: int, j: int) -> OutputChunk:
        """What the launch for the schedule's outputs ``i`` … ``j − 1`` records, and where."""
        k0 = self.schedule.k_min + i
        return OutputChunk(
            self.schedule.steps[i:j],
            k0,
            -(-max(k0, 0) // self.schedule.probes_per_frame),
            self.probe_buffer,
            self.frame_buffer,
        )

    def kept(self, i: int, j: int) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """The kept samples (t ≥ 0) of outputs ``i`` … ``j − 1``: their indices k, their
        probes ``[sample, field, body]`` and tables ``[sample, body, entry, component]`` as
        the launch left them."""
        k = self.schedule.k_min + np.arange(i, j)
        keep = k >= 0
        if not keep.any():
            empty = {name: np.zeros((0, *host.shape[1:])) for name, host in self.tables.items()}
            return k[keep], np.zeros((0, *self.probes.shape[1:])), empty
        tables = {
            name: np.transpose(buffer[: j - i].numpy()[keep][:, :count], (0, 2, 1, 3))
            for name, (buffer, count) in self.table_buffers.items()
        }
        return k[keep], self.probe_buffer[: j - i].numpy()[keep], tables

    def store(
        self, k: np.ndarray, values: np.ndarray, tables: dict[str, np.ndarray], valid: np.ndarray, sink: Sink | None
    ) -> None:
        """Copy the kept samples ``k`` (probes ``values``, ``tables``; ``valid[sample,
        body]``, NaN elsewhere) and their frames into the record and stream them to ``sink``."""
        if not len(k):
            return
        ppf = self.schedule.probes_per_frame
        values = np.where(valid[:, None, :], values, np.nan)
        self.probes[k] = values
        tables = {name: np.where(valid[:, :, None, None], table, np.nan) for name, table in tables.items()}
        for name, table in tables.items():
            self.tables[name][k] = table
        frame_index = k[k % ppf == 0] // ppf
        frames = (
            np.transpose(self.frame_buffer[: len(frame_index)].numpy(), (0, 2, 1, 3))
            if len(frame_index)
            else np.zeros((0, self.probes.shape[2], self.frame_buffer.shape[1], self.dim))
        )
        frames = np.where(valid[k % ppf == 0][:, :, None, None], frames, np.nan)
        if self.frames is not None and len(frame_index):
            self.frames[frame_index] = frames
        if sink is not None:
            sink.write_samples(self.schedule.times(k), values, tables, valid)
            if len(frame_index):
                sink.write_frames(int(frame_index[0]), frames)


class ChunkPlan:
    """The schedule's outputs cut into launches: each as long as about
    :data:`TARGET_LAUNCH_SECONDS` of wall clock (re-sized from the last launch's), at most
    ``capacity`` outputs, the first about 2000 substeps."""

    def __init__(self, schedule: Schedule, capacity: int) -> None:
        self.outputs = len(schedule.steps)
        self.capacity = capacity
        steps_per_output = int(schedule.steps[-1]) / self.outputs
        self.size = max(1, min(capacity, round(2000 / max(1.0, steps_per_output))))
        self.done = 0

    def __iter__(self) -> Iterator[tuple[int, int]]:
        while self.done < self.outputs:
            i, j = self.done, min(self.outputs, self.done + self.size)
            self.done = j  # counted as soon as it is handed out: a run that stops there ran it
            yield i, j

    def took(self, wall: float) -> None:
        """Size the next launch from the wall time the last one took."""
        self.size = max(1, min(self.capacity, round(self.size * TARGET_LAUNCH_SECONDS / max(wall, 1e-3))))


def _progress_bar(schedule: Schedule, show: bool) -> tqdm:
    span = float(schedule.times(schedule.k_min + len(schedule.steps) - 1) - schedule.times(schedule.k_min))
    return tqdm(
        total=span,
        unit="s",
        unit_scale=False,
        desc="simulated",
        disable=not show,
        dynamic_ncols=True,
        bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s sim [{elapsed}<{remaining}, {rate_fmt}{postfix}]",
    )


def announce_long_run(model: Any, steps: int, dt: float, threads: int) -> None:
    """A :class:`~warpcloth.errors.LongRunWarning` with the steps of each body and the
    time they take on ``threads`` CPU cores (the body's measured cost per node-step) when
    a body takes more than :data:`LONG_RUN_STEPS`."""
    if steps <= LONG_RUN_STEPS:
        return
    import warnings

    from warpcloth import bodies

    node_steps = float(steps) * model.n_nodes * model.n_bodies
    if model.device.is_cpu:
        cores = min(threads, model.n_bodies)
        ns = bodies.named(model.body).cpu_ns_per_node_step
        estimate = (
            f"about {duration_text(node_steps * ns * 1e-9 / cores)} on {cores} CPU core(s) at ~{ns:g} ns a node-step"
        )
    else:
        estimate = f"{node_steps:.3g} node-steps on {model.device}"
    warnings.warn(
        f"{steps:.3g} steps of each of {model.n_bodies} {model.body}(s) of {model.n_nodes} nodes (dt {dt:.4g} s), "
        f"{estimate}; Ctrl-C stops it and keeps what was recorded",
        LongRunWarning,
        stacklevel=3,
    )


def simulate_batch(
    model: Any,
    control: Any,
    solver: Solver,
    recorder: Any,
    state: Any = None,
    *,
    sink: Sink | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
    keep_frames: bool = True,
    labels: list[Any] | None = None,
    parameters: dict[str, np.ndarray] | None = None,
    attrs: dict[str, object] | None = None,
    threads: int | None = None,
) -> RunResult:
    """Run a built batch of strips or sheets to the end of the recorder's schedule and
    return what it recorded.

    ``sink`` receives each finished chunk (see :class:`Sink`). ``on_divergence="raise"``
    stops at the first diverged body with a DivergenceError (its ``result`` holds what was
    recorded); ``"record"`` lets the others go on. ``labels`` become ``RunResult.scenes``;
    ``parameters`` and ``attrs``, the result's (see there). ``threads`` CPU threads share
    each launch's bodies (default: the cores this process may use); results are bitwise
    the same for any count.
    """
    check_divergence_policy(on_divergence)
    threads = checked_threads(threads)
    check_recording_fits(model, control, recorder, keep_frames)
    declared = getattr(sink, "probe_fields", model.probes.fields)
    if tuple(declared) != model.probes.fields:
        raise ArgumentError(
            "sink",
            f"its probe table has columns for {', '.join(declared)}, but the model records "
            f"{', '.join(model.probes.fields)} (a force term's channel: a run directory stores the body's own probes)",
        )
    state = state or model.state()
    schedule = recorder.schedule(control, solver)
    announce_long_run(model, int(schedule.steps[-1]), solver.dt, threads)
    settings = recorder.settings(model)
    record = RecordBuffers(model, schedule, recorder.tables(model), settings, keep_frames)
    monitor = DivergenceMonitor(model, solver, control)
    plan = ChunkPlan(schedule, record.capacity)
    bar = _progress_bar(schedule, progress)
    started = time.perf_counter()
    try:
        for i, j in plan:
            tic = time.perf_counter()
            solver.advance(state, control, settings, record.chunk(i, j), threads)
            wp.synchronize_device(model.device)
            wall = time.perf_counter() - tic
            plan.took(wall)
            k, values, tables = record.kept(i, j)
            steps = schedule.steps[k - schedule.k_min]
            new = monitor.check(state, values, steps)
            record.store(k, values, tables, monitor.valid(steps), sink)
            steps_done = int(schedule.steps[j - 1] - (schedule.steps[i - 1] if i else 0))
            bar.set_postfix_str(f"{model.n_bodies * steps_done / max(wall, 1e-9):.3g} {model.body}-steps/s")
            bar.update(float(schedule.times(schedule.k_min + j - 1) - schedule.times(schedule.k_min)) - bar.n)
            if (new and on_divergence == "raise") or monitor.all_stopped:
                break
    finally:
        bar.close()
    wall_time = time.perf_counter() - started
    body_steps = int(state.struct.step.numpy().sum())  # each body's own count, to where it stopped
    memory = state.reversal_report()
    diverged = sorted(monitor.diverged, key=lambda d: d.body)
    result = RunResult(
        list(labels or []),
        schedule.times(schedule.kept),
        record.probes,
        schedule.times(schedule.frame_samples),
        record.frames,
        diverged,
        wall_time,
        body_steps,
        dict(parameters or {}),
        dict(attrs or {}),
        memory,
        record.tables,
        model.probes,
        model.body,
        model.n_nodes,
        getattr(model, "geometry", None),
    )
    if sink is not None:
        extra = {
            "wall_time_s": wall_time,
            "body_steps": body_steps,
            "node_steps": result.node_steps,
            "device": str(model.device),
        }
        sink.close(diverged, extra | ({"reversal_memory": memory} if memory else {}))
    if diverged and on_divergence == "raise":
        raise DivergenceError("; ".join(d.describe() for d in diverged), diverged, result)
    return result
