"""When a run records: the output samples of a body's recorder, the steps they end on,
which are kept and which are shape frames (docs/model.md §12)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import warp as wp


class RecorderSchedule:
    """What every body's recorder shares (a mixin of a frozen dataclass with ``interval``,
    ``probes_per_frame`` and ``duration``): where its samples fall."""

    def sample_range(self, control: Any) -> tuple[int, int]:
        """First and last output sample k (k < 0 during the hold), without building arrays."""
        return sample_bounds(self, control.release_time)

    def schedule(self, control: Any, solver: Any) -> Schedule:
        """The output samples of a run: hold samples (k < 0) are run, not kept."""
        return output_schedule(self, control.release_time, solver.dt, solver.release_step(control))


def sample_bounds(recorder: Any, release_time: float) -> tuple[int, int]:
    """First and last output sample k of a recorder's schedule (k < 0 during the hold)."""
    return (
        -math.floor(release_time / recorder.interval + 1e-9),
        math.floor(recorder.duration / recorder.interval + 1e-9),
    )


def output_schedule(recorder: Any, release_time: float, dt: float, release_step: int) -> Schedule:
    """The output samples every ``recorder.interval`` s from −``release_time`` (the hold,
    run but not kept) to ``recorder.duration``, each ending on the step nearest its time,
    a frame every ``recorder.probes_per_frame``: a strip's or a sheet's recorder alike."""
    k_min, k_max = sample_bounds(recorder, release_time)
    k = np.arange(k_min, k_max + 1)
    steps = np.maximum(0, release_step + np.rint(k * recorder.interval / dt).astype(np.int64))
    return Schedule(k_min, steps, recorder.probes_per_frame, release_step, dt)


@dataclass
class OutputChunk:
    """What one launch records and where: the output samples ``first_output`` … ending at
    ``output_steps``, probe k of the chunk into ``probes[k, :, strip]``, a sample that is a
    frame (index ≥ 0, a multiple of probes_per_frame) into ``frames[index // ppf −
    first_frame]``."""

    output_steps: np.ndarray
    first_output: int
    first_frame: int
    probes: wp.array
    frames: wp.array


@dataclass(frozen=True)
class Schedule:
    """Output samples k_min..k_max at t_k = k·interval; sample k ends at ``steps[k - k_min]``."""

    k_min: int
    steps: np.ndarray
    probes_per_frame: int
    release_step: int
    dt: float

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

    @property
    def frame_times(self) -> np.ndarray:
        """Times of the shape frames, s."""
        return self.times(self.frame_samples)
