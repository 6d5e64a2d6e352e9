"""Orchestration of a batch run: output schedule, chunked launches, progress, streaming."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import warp as wp
from tqdm import tqdm

from warpcloth.kernels import PROBE_FIELDS, PROBE_INDEX, STATUS_NONFINITE_ENERGY

from .control import Control
from .errors import DivergenceError
from .model import Model
from .output import RunWriter
from .scene import Scene, load_scene
from .solver import Solver, describe_divergence
from .state import State

TARGET_LAUNCH_SECONDS = 0.5  # long enough to amortise launch cost, short enough for progress
BUFFER_BYTES = 64 * 2**20  # cap on the per-chunk probe and frame buffers


@dataclass
class RunResult:
    """Everything a run recorded, in SI units.

    ``probes`` is ``[sample, field, variant]`` (fields: PROBE_FIELDS) at times ``t``;
    ``frames`` is ``[frame, variant, node, xy]`` at ``frame_times``. Rows after a
    strip's divergence are NaN here (and absent from probes.csv).
    """

    scenes: list[Scene]
    t: np.ndarray
    probes: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None
    diverged: list[dict] = field(default_factory=list)
    wall_time_s: float = 0.0
    strip_steps: int = 0

    def probe(self, name: str, variant: int | None = None) -> np.ndarray:
        """Time series of one probe: ``[sample, variant]``, or ``[sample]`` for one variant."""
        series = self.probes[:, PROBE_INDEX[name], :]
        return series if variant is None else series[:, variant]

    def energy_total(self) -> np.ndarray:
        """Budget that should stay constant: kinetic + gravitational + tensile + work done
        against bending and damping − work done by the drives, ``[sample, variant]``."""
        p = self.probe
        return (p("kinetic") + p("gravitational") + p("tensile") + p("bending_elastic_work")
                + p("hysteresis_work") + p("damping_work") - p("drive_work"))


@dataclass
class Schedule:
    """Output samples k_min..k_max at t_k = k·interval; sample k ends at ``steps[k - k_min]``."""

    k_min: int
    steps: np.ndarray
    probes_per_frame: int
    release_step: int
    dt: float

    @classmethod
    def for_scene(cls, scene: Scene, release_step: int) -> Schedule:
        """The output schedule of a scene: pre-roll samples (k < 0) are run, not kept."""
        interval = scene.output_interval
        dt = scene.integrator.dt_s
        k_min = -math.floor(scene.preroll / interval + 1e-9)
        k_max = math.floor(scene.run.duration_s / interval + 1e-9)
        k = np.arange(k_min, k_max + 1)
        steps = np.maximum(0, release_step + np.rint(k * interval / dt).astype(np.int64))
        return cls(k_min, steps, scene.output.probes_per_frame, release_step, dt)

    def times(self, k: np.ndarray) -> np.ndarray:
        """Exact simulated times of samples ``k``."""
        return (self.steps[np.asarray(k) - self.k_min] - self.release_step) * self.dt

    @property
    def kept(self) -> np.ndarray:
        """Sample indices kept (t ≥ 0)."""
        return np.arange(0, self.k_min + len(self.steps))

    @property
    def frame_samples(self) -> np.ndarray:
        """Sample indices that are also frames."""
        return self.kept[:: self.probes_per_frame]


def simulate(
    scenes: Scene | Sequence[Scene],
    *,
    device: str | None = None,
    out: str | Path | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
    keep_frames: bool = True,
    initial_positions: np.ndarray | None = None,
    initial_velocities: np.ndarray | None = None,
) -> RunResult:
    """Run one batch of strips (one scene per strip) and return what it recorded.

    ``out`` streams the run directory (see warpcloth.output) as the run proceeds.
    ``on_divergence="raise"`` stops at the first diverged strip with a DivergenceError
    (its ``result`` holds what was recorded); ``"record"`` lets the other strips go on.
    ``initial_positions`` / ``initial_velocities`` (``[node, variant, xy]``, m and m/s)
    replace the straight hanging start, e.g. with a mode shape; hinges start fresh there.
    """
    scenes = [scenes] if isinstance(scenes, Scene) else list(scenes)
    if on_divergence not in ("raise", "record"):
        raise ValueError(f"on_divergence must be 'raise' or 'record', got {on_divergence!r}")
    model = Model(scenes, device)
    control = Control(model)
    solver = Solver(model, control)
    state = State(model)
    if initial_positions is not None:
        state.set_positions(initial_positions, initial_velocities)
    schedule = Schedule.for_scene(scenes[0], control.release_step)
    n_kept, frame_samples = len(schedule.kept), schedule.frame_samples
    b, n, nq = model.n_strips, model.n_nodes, len(PROBE_FIELDS)
    t = schedule.times(schedule.kept)
    frame_times = schedule.times(frame_samples)
    probes_all = np.full((n_kept, nq, b), np.nan)
    frames_all = np.full((len(frame_samples), b, n, 2), np.nan) if keep_frames else None
    writer = RunWriter(out, scenes, n, frame_times) if out is not None else None

    ppf = schedule.probes_per_frame
    cap = max(1, min(len(schedule.steps), BUFFER_BYTES // (8 * nq * b)))
    cap_frames = max(1, min(len(frame_samples), BUFFER_BYTES // (16 * n * b)))
    cap = min(cap, cap_frames * ppf)
    probes_buf = wp.zeros((cap, nq, b), dtype=model.kernels.scalar, device=model.device)
    frames_buf = wp.zeros((cap // ppf + 1, n, b), dtype=model.kernels.vec2, device=model.device)

    diverged: list[dict] = []
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
            solver.advance(state, schedule.steps[i:j], k0, first_frame, probes_buf, frames_buf)
            wp.synchronize_device(model.device)
            wall = time.perf_counter() - tic
            new = _collect(solver, state, schedule, i, j, probes_buf, frames_buf, probes_all, frames_all,
                           writer, diverged)
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
    result = RunResult(scenes, t, probes_all, frame_times, frames_all, diverged, wall_time, strip_steps)
    if writer is not None:
        writer.close(diverged, {"wall_time_s": wall_time, "strip_steps": strip_steps,
                                "device": str(model.device)})
    if diverged and on_divergence == "raise":
        raise DivergenceError("; ".join(describe_divergence(d) for d in diverged), diverged, result)
    return result


def _collect(solver: Solver, state: State, schedule: Schedule, i: int, j: int, probes_buf: wp.array,
             frames_buf: wp.array, probes_all: np.ndarray, frames_all: np.ndarray | None,
             writer: RunWriter | None, diverged: list[dict]) -> bool:
    """Copy a finished chunk out, drop samples after a divergence, stream it to disk."""
    status = state.struct.status.numpy()
    known = {d["strip"] for d in diverged}
    new_reports = [solver.divergence_report(state, int(s)) for s in np.nonzero(status)[0] if s not in known]
    diverged.extend(new_reports)
    steps = schedule.steps[i:j]
    valid = np.ones((j - i, probes_all.shape[2]), dtype=bool)
    for d in diverged:
        last_ok = steps < d["step"] if d["code"] == STATUS_NONFINITE_ENERGY else steps <= d["step"]
        valid[:, d["strip"]] &= last_ok
    k = schedule.k_min + np.arange(i, j)
    keep = k >= 0
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
    if writer is not None:
        times = schedule.times(k[keep])
        rows_t = np.repeat(times, values.shape[2])
        rows_v = np.tile(np.arange(values.shape[2]), len(times))
        flat = np.transpose(values, (0, 2, 1)).reshape(-1, values.shape[1])
        ok = valid.reshape(-1)
        writer.write_probes(rows_t[ok], rows_v[ok], flat[ok])
        if len(frame_index):
            writer.write_frames(int(frame_index[0]), frames)
    return bool(new_reports)


def run(scene: str | Path | Scene, overrides: Sequence[str] = (), **kwargs: object) -> RunResult:
    """Load a scene (path or bundled name), apply ``key=value`` overrides, simulate it.

    Keyword arguments go to :func:`simulate` (``out``, ``device``, ``progress``, ...).
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene, overrides)
    return simulate(scene, **kwargs)
