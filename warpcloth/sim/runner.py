"""Running a batch: chunked launches sized to the wall clock, progress, the divergence
policy, and streaming each finished chunk to a sink (e.g. a run directory writer)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pandas as pd
import warp as wp
from tqdm import tqdm

from warpcloth.errors import ArgumentError, DivergenceError, checked_index
from warpcloth.kernels import PROBE_FIELDS, PROBE_INDEX

from .control import Control
from .divergence import Divergence, DivergenceMonitor
from .labelled import probes_dataset, probes_frame
from .model import Model
from .recorder import OutputChunk, Recorder, Schedule
from .resources import check_memory
from .solvers import Solver
from .state import State

TARGET_LAUNCH_SECONDS = 0.5  # long enough to amortise launch cost, short enough for progress
BUFFER_BYTES = 64 * 2**20  # cap on the per-chunk probe and frame buffers
DIVERGENCE_POLICIES = ("raise", "record")


def available_cores() -> int:
    """The CPU cores this process may run on (its affinity, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_divergence_policy(on_divergence: str) -> None:
    """Raise ValueError unless ``on_divergence`` is one of :data:`DIVERGENCE_POLICIES`."""
    if on_divergence not in DIVERGENCE_POLICIES:
        raise ValueError(f"on_divergence must be 'raise' or 'record', got {on_divergence!r}")


class Sink(Protocol):
    """Where a run streams its results as they are produced."""

    def write_probes(self, t: np.ndarray, variant: np.ndarray, values: np.ndarray) -> None:
        """Append probe rows: times, strip indices and values ``[row, field]``."""

    def write_frames(self, first: int, frames: np.ndarray) -> None:
        """Store frames ``[frame, strip, node, xy]`` from frame index ``first`` on."""

    def close(self, diverged: list[Divergence], extra: dict) -> None:
        """Finish: the run ended (completely, or at a divergence it reports)."""


@dataclass
class RunResult:
    """Everything a run recorded, in SI units.

    ``probes`` is ``[sample, field, variant]`` (fields: PROBE_FIELDS) at times ``t``;
    ``frames`` is ``[frame, variant, node, xy]`` at ``frame_times``. Rows after a
    strip's divergence are NaN here (and absent from probes.csv). ``scenes`` holds what
    each strip was built from, when it was built from scenes.
    """

    scenes: list[Any]
    t: np.ndarray
    probes: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None
    diverged: list[Divergence] = field(default_factory=list)
    wall_time_s: float = 0.0
    strip_steps: int = 0
    parameters: dict[str, np.ndarray] = field(default_factory=dict)
    """Each strip's value of every per-strip scalar scene field, by dotted name (filled
    when the batch was built from scenes): the coordinates of :meth:`to_xarray`."""
    attrs: dict[str, object] = field(default_factory=dict)
    """What :meth:`to_xarray` says about the whole result (e.g. its coordinate frame)."""
    reversal_memory: dict[str, object] = field(default_factory=dict)
    """For a batch with return-point memory (the masing law): the points each hinge could
    keep (``capacity``) and, per strip, the ``deepest`` any hinge went and the
    ``overflows`` (reversals not stored: their inner loops were traced without
    hysteresis, docs/model.md §4.10). Empty otherwise."""

    def memory_warning(self) -> str | None:
        """A sentence naming the strips whose reversal memory overflowed, or None."""
        return reversal_memory_warning(self.reversal_memory)

    def to_xarray(self) -> object:
        """An ``xarray.Dataset`` of the probes over (t, variant), the frames over
        (frame_time, variant, node, xy) and :attr:`parameters` as coordinates along
        ``variant``, units in ``attrs`` (needs ``pip install 'warpcloth[xarray]'``)."""
        return probes_dataset(
            self.t,
            self.probes,
            self.frame_times,
            self.frames,
            np.arange(self.probes.shape[2]),
            self.parameters,
            self.attrs,
        )

    def to_dataframe(self) -> pd.DataFrame:
        """The probes in long form (t, variant, one column per probe, SI) joined with
        :attr:`parameters`: ready for groupby and plotting."""
        return probes_frame(self.t, self.probes, np.arange(self.probes.shape[2]), self.parameters)

    def probe(self, name: str, variant: int | None = None) -> np.ndarray:
        """Time series of one probe: ``[sample, variant]``, or ``[sample]`` for one variant
        (an index 0 … n − 1; a name or index that is not one is refused, naming it)."""
        series = self.probes[:, PROBE_INDEX[checked_probe(name)], :]
        return series if variant is None else series[:, checked_index("variant", variant, series.shape[1], "variants")]

    def energy_total(self) -> np.ndarray:
        """Budget that should stay constant: kinetic + gravitational + tensile + work done
        against bending and damping − work done by the drives, ``[sample, variant]``."""
        p = self.probe
        return (
            p("kinetic")
            + p("gravitational")
            + p("tensile")
            + p("bending_elastic_work")
            + p("hysteresis_work")
            + p("damping_work")
            - p("drive_work")
        )


def reversal_memory_warning(report: dict[str, object]) -> str | None:
    """The warning a run with overflowed reversal memory prints (see
    :attr:`RunResult.reversal_memory`); None when nothing overflowed."""
    overflows = np.asarray(report.get("overflows", []), dtype=int)
    if not overflows.any():
        return None
    strips = np.flatnonzero(overflows)
    named = ", ".join(f"{s} ({overflows[s]})" for s in strips[:8]) + (" …" if len(strips) > 8 else "")
    return (
        f"the masing reversal memory ({report['capacity']} points per hinge) was full: {int(overflows.sum())} "
        f"reversal(s) not stored in strip(s) {named}; their inner loops were traced without hysteresis, so the "
        "hysteresis work is underestimated by their area; raise integrator.reversal_memory"
    )


def checked_probe(name: object) -> str:
    """``name`` if it is a recorded probe, else an ArgumentError listing them."""
    if not isinstance(name, str) or name not in PROBE_INDEX:
        raise ArgumentError("name", f"{name!r} is not a probe; the probes are {', '.join(PROBE_FIELDS)}")
    return name


def check_recording_fits(model: Model, control: Control, recorder: Recorder, keep_frames: bool = True) -> None:
    """Refuse, before anything is allocated, a run whose recorded results (and output
    schedule) would not fit in memory (:func:`~warpcloth.sim.resources.check_memory`)."""
    b, n, nq = model.n_strips, model.n_nodes, len(PROBE_FIELDS)
    k_min, k_max = recorder.sample_range(control)
    n_frames = k_max // recorder.probes_per_frame + 1
    # the schedule's own arrays (steps, times: 8 B per sample each) and the recorded results
    check_memory(
        16 * (k_max - k_min + 1) + 8 * (k_max + 1) * nq * b + (16 * n_frames * b * n if keep_frames else 0),
        f"the recorded probes{' and frames' if keep_frames else ''} of {b} strip(s)",
        "record less (output.probes_per_frame, output.frame_rate_hz, run.duration_s), run fewer "
        "strips at once (sweep --max-batch), or keep frames only on disk (keep_frames=False)",
    )


class RecordBuffers:
    """The device buffers one launch fills (at most :data:`BUFFER_BYTES` each) and the host
    arrays of the whole record they are copied into, chunk by chunk."""

    def __init__(self, model: Model, schedule: Schedule, keep_frames: bool) -> None:
        b, n, nq = model.n_strips, model.n_nodes, len(PROBE_FIELDS)
        self.schedule = schedule
        self.probes = np.full((len(schedule.kept), nq, b), np.nan)
        self.frames = np.full((len(schedule.frame_samples), b, n, 2), np.nan) if keep_frames else None
        ppf = schedule.probes_per_frame
        cap = max(1, min(len(schedule.steps), BUFFER_BYTES // (8 * nq * b)))
        cap_frames = max(1, min(len(schedule.frame_samples), BUFFER_BYTES // (16 * n * b)))
        self.capacity = min(cap, cap_frames * ppf)
        """The most output samples one launch may record."""
        self.probe_buffer = wp.zeros((self.capacity, nq, b), dtype=model.scalar, device=model.device)
        self.frame_buffer = wp.zeros((self.capacity // ppf + 1, n, b), dtype=model.types.vec2, device=model.device)

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

    def kept(self, i: int, j: int) -> tuple[np.ndarray, np.ndarray]:
        """The kept samples (t ≥ 0) of outputs ``i`` … ``j − 1``: their indices k, and their
        probes ``[sample, field, strip]`` as the launch left them."""
        k = self.schedule.k_min + np.arange(i, j)
        keep = k >= 0
        if not keep.any():
            return k[keep], np.zeros((0, *self.probes.shape[1:]))
        return k[keep], self.probe_buffer[: j - i].numpy()[keep]

    def store(self, k: np.ndarray, values: np.ndarray, valid: np.ndarray, sink: Sink | None) -> None:
        """Copy the kept samples ``k`` (probes ``values``; ``valid[sample, strip]``, NaN
        elsewhere) and their frames into the record and stream them to ``sink``."""
        if not len(k):
            return
        ppf = self.schedule.probes_per_frame
        values = np.where(valid[:, None, :], values, np.nan)
        self.probes[k] = values
        frame_index = k[k % ppf == 0] // ppf
        frames = (
            np.transpose(self.frame_buffer[: len(frame_index)].numpy(), (0, 2, 1, 3))
            if len(frame_index)
            else np.zeros((0, self.probes.shape[2], self.frame_buffer.shape[1], 2))
        )
        frames = np.where(valid[k % ppf == 0][:, :, None, None], frames, np.nan)
        if self.frames is not None and len(frame_index):
            self.frames[frame_index] = frames
        if sink is not None:
            times = self.schedule.times(k)
            rows_t = np.repeat(times, values.shape[2])
            rows_v = np.tile(np.arange(values.shape[2]), len(times))
            flat = np.transpose(values, (0, 2, 1)).reshape(-1, values.shape[1])
            ok = valid.reshape(-1)
            sink.write_probes(rows_t[ok], rows_v[ok], flat[ok])
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


def simulate_batch(
    model: Model,
    control: Control,
    solver: Solver,
    recorder: Recorder,
    state: State | None = None,
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
    """Run a built batch to the end of the recorder's schedule and return what it recorded.

    ``sink`` receives each finished chunk (see :class:`Sink`). ``on_divergence="raise"``
    stops at the first diverged strip with a DivergenceError (its ``result`` holds what
    was recorded); ``"record"`` lets the other strips go on. ``labels`` become
    ``RunResult.scenes``; ``parameters`` and ``attrs``, the result's (see there).
    ``threads`` CPU threads share each launch's strips (default: the cores this process
    may use); results are bitwise the same for any count.
    """
    check_divergence_policy(on_divergence)
    check_recording_fits(model, control, recorder, keep_frames)
    threads = available_cores() if threads is None else threads
    if threads < 1:
        raise ValueError(f"threads must be at least 1, got {threads}")
    state = state or model.state()
    schedule = recorder.schedule(control, solver)
    record = RecordBuffers(model, schedule, keep_frames)
    monitor = DivergenceMonitor(model, solver, control)
    plan = ChunkPlan(schedule, record.capacity)
    bar = _progress_bar(schedule, progress)
    started = time.perf_counter()
    try:
        for i, j in plan:
            tic = time.perf_counter()
            solver.advance(state, control, recorder, record.chunk(i, j), threads)
            wp.synchronize_device(model.device)
            wall = time.perf_counter() - tic
            plan.took(wall)
            k, values = record.kept(i, j)
            steps = schedule.steps[k - schedule.k_min]
            new = monitor.check(state, values, steps)
            record.store(k, values, monitor.valid(steps), sink)
            steps_done = int(schedule.steps[j - 1] - (schedule.steps[i - 1] if i else 0))
            bar.set_postfix_str(f"{model.n_strips * steps_done / max(wall, 1e-9):.3g} strip-steps/s")
            bar.update(float(schedule.times(schedule.k_min + j - 1) - schedule.times(schedule.k_min)) - bar.n)
            if (new and on_divergence == "raise") or monitor.all_stopped:
                break
    finally:
        bar.close()
    wall_time = time.perf_counter() - started
    strip_steps = model.n_strips * int(schedule.steps[plan.done - 1])  # up to where the run stopped
    memory = state.reversal_report()
    diverged = monitor.diverged
    result = RunResult(
        list(labels or []),
        schedule.times(schedule.kept),
        record.probes,
        schedule.times(schedule.frame_samples),
        record.frames,
        diverged,
        wall_time,
        strip_steps,
        dict(parameters or {}),
        dict(attrs or {}),
        memory,
    )
    if sink is not None:
        extra = {"wall_time_s": wall_time, "strip_steps": strip_steps, "device": str(model.device)}
        sink.close(diverged, extra | ({"reversal_memory": memory} if memory else {}))
    if diverged and on_divergence == "raise":
        raise DivergenceError("; ".join(d.describe() for d in diverged), diverged, result)
    return result
