"""Running a batch: chunked launches sized to the wall clock, progress, the divergence
policy, and streaming each finished chunk to a sink (e.g. a run directory writer)."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import pandas as pd
import warp as wp
from tqdm import tqdm

from warpcloth.errors import DivergenceError, OptionError, checked_index
from warpcloth.kernels import PROBE_FIELDS, PROBE_INDEX, STATUS_BUDGET, STATUS_NONFINITE_ENERGY

from .control import Control
from .labelled import probes_dataset, probes_frame
from .model import Model
from .recorder import Recorder, Schedule
from .resources import check_memory
from .solvers import BUDGET_TOLERANCE, Divergence, Solver
from .state import State

TARGET_LAUNCH_SECONDS = 0.5  # long enough to amortise launch cost, short enough for progress
BUFFER_BYTES = 64 * 2**20  # cap on the per-chunk probe and frame buffers
DIVERGENCE_POLICIES = ("raise", "record")
BUDGET_TERMS = ("kinetic", "gravitational", "tensile", "bending_elastic_work", "hysteresis_work", "damping_work")


class BudgetWatch:
    """Each strip's energy budget at the release and its peak kinetic energy so far, to
    stop a strip whose budget no longer closes (:data:`BUDGET_TOLERANCE`)."""

    def __init__(self, model: Model) -> None:
        self.reference = np.full(model.n_strips, np.nan)
        self.peak_kinetic = np.zeros(model.n_strips)
        free = model.n_nodes - model.n_clamped
        weight = model.node_mass * (free - 0.5) * model.gravity * free * model.spacing
        # without gravity (a set strip curling at rest) the scale is bending's: D W over the
        # free length, the work of bending it through one radian
        bending = model.bending[:, 0] * model.width / (free * model.spacing)
        self.floor = 1e-3 * np.maximum(weight, bending)

    def first_violation(self, values: np.ndarray, usable: np.ndarray) -> dict[int, tuple[int, float]]:
        """``strip → (sample index, residual / scale)`` of the first failing sample of
        each strip in the chunk ``values[sample, field, strip]`` (samples from the release
        on), looking only where ``usable[sample, strip]``."""
        total = sum(values[:, PROBE_INDEX[name], :] for name in BUDGET_TERMS) - values[:, PROBE_INDEX["drive_work"], :]
        kinetic = np.where(usable, values[:, PROBE_INDEX["kinetic"], :], 0.0)
        self.reference = np.where(np.isnan(self.reference), total[0], self.reference)
        peak = np.maximum(self.peak_kinetic, np.fmax.accumulate(np.nan_to_num(kinetic, nan=0.0), axis=0))
        self.peak_kinetic = peak[-1]
        with np.errstate(invalid="ignore"):
            bad = usable & (total - self.reference > BUDGET_TOLERANCE * np.maximum(peak, self.floor))
        out = {}
        for strip in np.flatnonzero(bad.any(axis=0)):
            n = int(np.argmax(bad[:, strip]))
            out[int(strip)] = (n, float((total[n, strip] - self.reference[strip])
                                        / max(peak[n, strip], self.floor[strip])))
        return out


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
        return probes_dataset(self.t, self.probes, self.frame_times, self.frames, np.arange(self.probes.shape[2]),
                              self.parameters, self.attrs)

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
        return (p("kinetic") + p("gravitational") + p("tensile") + p("bending_elastic_work")
                + p("hysteresis_work") + p("damping_work") - p("drive_work"))


def reversal_memory_warning(report: dict[str, object]) -> str | None:
    """The warning a run with overflowed reversal memory prints (see
    :attr:`RunResult.reversal_memory`); None when nothing overflowed."""
    overflows = np.asarray(report.get("overflows", []), dtype=int)
    if not overflows.any():
        return None
    strips = np.flatnonzero(overflows)
    named = ", ".join(f"{s} ({overflows[s]})" for s in strips[:8]) + (" …" if len(strips) > 8 else "")
    return (f"the masing reversal memory ({report['capacity']} points per hinge) was full: {int(overflows.sum())} "
            f"reversal(s) not stored in strip(s) {named}; their inner loops were traced without hysteresis, so the "
            "hysteresis work is underestimated by their area; raise integrator.reversal_memory")


def checked_probe(name: object) -> str:
    """``name`` if it is a recorded probe, else an OptionError listing them."""
    if not isinstance(name, str) or name not in PROBE_INDEX:
        raise OptionError("name", f"{name!r} is not a probe; the probes are {', '.join(PROBE_FIELDS)}")
    return name


def check_recording_fits(model: Model, control: Control, recorder: Recorder, keep_frames: bool = True) -> None:
    """Refuse, before anything is allocated, a run whose recorded results (and output
    schedule) would not fit in memory (:func:`~warpcloth.sim.resources.check_memory`)."""
    b, n, nq = model.n_strips, model.n_nodes, len(PROBE_FIELDS)
    k_min, k_max = recorder.sample_range(control)
    n_frames = k_max // recorder.probes_per_frame + 1
    # the schedule's own arrays (steps, times: 8 B per sample each) and the recorded results
    check_memory(16 * (k_max - k_min + 1) + 8 * (k_max + 1) * nq * b + (16 * n_frames * b * n if keep_frames else 0),
                 f"the recorded probes{' and frames' if keep_frames else ''} of {b} strip(s)",
                 "record less (output.probes_per_frame, output.frame_rate_hz, run.duration_s), run fewer "
                 "strips at once (sweep --max-batch), or keep frames only on disk (keep_frames=False)")


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
    b, n, nq = model.n_strips, model.n_nodes, len(PROBE_FIELDS)
    n_kept, frame_samples = len(schedule.kept), schedule.frame_samples
    t = schedule.times(schedule.kept)
    frame_times = schedule.times(frame_samples)
    probes_all = np.full((n_kept, nq, b), np.nan)
    frames_all = np.full((len(frame_samples), b, n, 2), np.nan) if keep_frames else None

    ppf = schedule.probes_per_frame
    cap = max(1, min(len(schedule.steps), BUFFER_BYTES // (8 * nq * b)))
    cap_frames = max(1, min(len(frame_samples), BUFFER_BYTES // (16 * n * b)))
    cap = min(cap, cap_frames * ppf)
    probes_buf = wp.zeros((cap, nq, b), dtype=model.scalar, device=model.device)
    frames_buf = wp.zeros((cap // ppf + 1, n, b), dtype=model.types.vec2, device=model.device)

    diverged: list[Divergence] = []
    budget = BudgetWatch(model)
    total_steps = int(schedule.steps[-1])
    bar = tqdm(total=float(schedule.times(schedule.k_min + len(schedule.steps) - 1)
                           - schedule.times(schedule.k_min)),
               unit="s", unit_scale=False, desc="simulated", disable=not progress, dynamic_ncols=True,
               bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s sim [{elapsed}<{remaining}, {rate_fmt}{postfix}]")
    started = time.perf_counter()
    chunk = max(1, min(cap, round(2000 / max(1.0, total_steps / len(schedule.steps)))))
    i = 0
    try:
        while i < len(schedule.steps):
            j = min(len(schedule.steps), i + chunk)
            k0 = schedule.k_min + i
            first_frame = -(-max(k0, 0) // ppf)
            tic = time.perf_counter()
            solver.advance(state, control, recorder, schedule.steps[i:j], k0, first_frame, probes_buf, frames_buf,
                           threads)
            wp.synchronize_device(model.device)
            wall = time.perf_counter() - tic
            new = _collect(solver, state, control, schedule, i, j, probes_buf, frames_buf, probes_all, frames_all,
                           sink, diverged, budget)
            steps_done = int(schedule.steps[j - 1] - (schedule.steps[i - 1] if i else 0))
            bar.set_postfix_str(f"{b * steps_done / max(wall, 1e-9):.3g} strip-steps/s")
            bar.update(float(schedule.times(schedule.k_min + j - 1) - schedule.times(schedule.k_min)) - bar.n)
            i = j
            chunk = max(1, min(cap, round(chunk * TARGET_LAUNCH_SECONDS / max(wall, 1e-3))))
            if new and on_divergence == "raise":
                break
            if len(diverged) == b:
                break
    finally:
        bar.close()
    wall_time = time.perf_counter() - started
    strip_steps = b * int(schedule.steps[i - 1])  # up to where the run stopped
    memory = state.reversal_report()
    result = RunResult(list(labels or []), t, probes_all, frame_times, frames_all, diverged, wall_time, strip_steps,
                       dict(parameters or {}), dict(attrs or {}), memory)
    if sink is not None:
        extra = {"wall_time_s": wall_time, "strip_steps": strip_steps, "device": str(model.device)}
        sink.close(diverged, extra | ({"reversal_memory": memory} if memory else {}))
    if diverged and on_divergence == "raise":
        raise DivergenceError("; ".join(d.describe() for d in diverged), diverged, result)
    return result


def _stop_unbalanced(state: State, budget: BudgetWatch, values: np.ndarray, steps: np.ndarray,
                     known: set[int]) -> None:
    # A strip whose budget fails stops at that sample, unless the kernel stopped it
    # earlier; the first of the two events is the one reported, however the run is cut
    # into launches (the samples from it on are dropped like others').
    fields = {name: getattr(state.struct, name).numpy() for name in ("status", "status_step", "status_index",
                                                                     "status_value")}
    # a kernel stop keeps the sample of its step for strain and fold (1, 2), not for a
    # non-finite energy (3); only kept samples are checked
    stopped = fields["status"] != 0
    through = np.where(fields["status"] == STATUS_NONFINITE_ENERGY, fields["status_step"] - 1, fields["status_step"])
    usable = ~stopped[None, :] | (steps[:, None] <= through[None, :])
    failed = {s: v for s, v in budget.first_violation(values, usable).items() if s not in known}
    if not failed:
        return
    for strip, (sample, residual) in failed.items():
        fields["status"][strip] = STATUS_BUDGET
        fields["status_step"][strip] = int(steps[sample])
        fields["status_index"][strip] = -1
        fields["status_value"][strip] = residual
    for name, value in fields.items():
        getattr(state.struct, name).assign(value)


def _collect(solver: Solver, state: State, control: Control, schedule: Schedule, i: int, j: int,
             probes_buf: wp.array, frames_buf: wp.array, probes_all: np.ndarray, frames_all: np.ndarray | None,
             sink: Sink | None, diverged: list[Divergence], budget: BudgetWatch) -> bool:
    """Copy a finished chunk out, drop samples after a divergence, stream it to the sink."""
    k = schedule.k_min + np.arange(i, j)
    keep = k >= 0
    known = {d.strip for d in diverged}
    if keep.any():
        _stop_unbalanced(state, budget, probes_buf[: j - i].numpy()[keep], schedule.steps[i:j][keep], known)
    status = state.struct.status.numpy()
    new_reports = [solver.divergence_report(state, control, int(s)) for s in np.nonzero(status)[0]
                   if s not in known]
    diverged.extend(new_reports)
    steps = schedule.steps[i:j]
    valid = np.ones((j - i, probes_all.shape[2]), dtype=bool)
    for d in diverged:
        last_ok = steps < d.step if d.sample_lost else steps <= d.step
        valid[:, d.strip] &= last_ok
    if not keep.any():
        return bool(new_reports)
    values = probes_buf[: j - i].numpy()[keep]  # copy out only this chunk's samples
    valid = valid[keep]
    values = np.where(valid[:, None, :], values, np.nan)
    probes_all[k[keep]] = values
    is_frame = (k >= 0) & (k % schedule.probes_per_frame == 0)
    frame_index = k[is_frame] // schedule.probes_per_frame
    frames = np.transpose(frames_buf[: len(frame_index)].numpy(), (0, 2, 1, 3)) if len(frame_index) else \
        np.zeros((0, probes_all.shape[2], frames_buf.shape[1], 2))
    frames = np.where(valid[(k[keep] % schedule.probes_per_frame == 0)][:, :, None, None], frames, np.nan)
    if frames_all is not None and len(frame_index):
        frames_all[frame_index] = frames
    if sink is not None:
        times = schedule.times(k[keep])
        rows_t = np.repeat(times, values.shape[2])
        rows_v = np.tile(np.arange(values.shape[2]), len(times))
        flat = np.transpose(values, (0, 2, 1)).reshape(-1, values.shape[1])
        ok = valid.reshape(-1)
        sink.write_probes(rows_t[ok], rows_v[ok], flat[ok])
        if len(frame_index):
            sink.write_frames(int(frame_index[0]), frames)
    return bool(new_reports)
