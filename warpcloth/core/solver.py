"""What advances a batch of bodies: the contract the runner needs of a solver, and the
base every solver of a fused kernel shares (docs/model.md §9).

A body's solver (:mod:`warpcloth.strip.solvers`, :mod:`warpcloth.sheet.solver`) names its
kernel, the stepping struct it fills and how it words a divergence; owning the time step,
launching the kernel over CPU threads or one GPU launch and reading the health fields is
the same for every body, here.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from typing import Any, Protocol

import numpy as np
import warp as wp

from warpcloth.kernels import STATUS_OK

from .schedule import OutputChunk


def launch_over_threads(
    kernel: object, n_bodies: int, inputs: list, device: object, threads: int, per_thread: int
) -> None:
    """Launch ``kernel`` over ``n_bodies`` whose last input is the first body's index: on
    a CPU as ``threads`` launches of contiguous ranges of at least ``per_thread`` bodies,
    each from its own thread (Warp runs a CPU launch on one thread and releases the GIL),
    else one launch. Every body's arithmetic is the same either way."""
    parts = max(1, min(threads, n_bodies // per_thread)) if device.is_cpu else 1
    bounds = np.linspace(0, n_bodies, parts + 1).round().astype(int)

    def launch(part: int) -> None:
        wp.launch(kernel, dim=int(bounds[part + 1] - bounds[part]), device=device, inputs=[*inputs, int(bounds[part])])

    if parts == 1:
        launch(0)
        return
    with ThreadPoolExecutor(parts) as pool:
        list(pool.map(launch, range(parts)))


class Solver(Protocol):
    """What the runner needs of a solver: its time step, where t = 0 falls, one launch
    that advances every body through a chunk of outputs, and a divergence report."""

    dt: float

    def release_step(self, control: Any) -> int:
        """Step index of t = 0 under ``control``."""

    def advance(self, state: Any, control: Any, settings: Any, chunk: OutputChunk, threads: int = 1) -> None:
        """Advance every healthy body to each output step of ``chunk``, recording its probes
        (with the recorder's kernel ``settings``) and frames there, on up to ``threads``
        CPU threads."""

    def divergence_report(self, state: Any, control: Any, body: int) -> Any:
        """Where and how ``body`` diverged, or None while it is healthy."""


class FusedSolver:
    """The base of every solver whose kernel is a fused advance loop (kernels/fused.py):
    a fixed ``dt``, one launch per chunk of outputs (on a CPU, one per thread over
    contiguous ranges of at least :attr:`bodies_per_thread` bodies). A body's solver sets
    :attr:`kernel` and implements :meth:`stepping` and :meth:`divergence_report`."""

    bodies_per_thread = 1
    kernel: Any = None

    def __init__(self, model: Any, dt: float) -> None:
        self.model = model
        self.dt = float(dt)

    def step_of(self, time: float) -> int:
        """The step count nearest ``time`` seconds."""
        return round(time / self.dt)

    def release_step(self, control: Any) -> int:
        """Step index of t = 0 under ``control``."""
        return self.step_of(control.release_time)

    def stepping(self, control: Any) -> object:
        """The kernel's stepping struct (dt, the divergence limits, the release step)."""
        raise NotImplementedError(f"{type(self).__name__} does not say how it steps")  # a new solver's omission

    def advance(self, state: Any, control: Any, settings: Any, chunk: OutputChunk, threads: int = 1) -> None:
        """Advance every healthy body to each output step of ``chunk``, recording there
        (:class:`~warpcloth.core.schedule.OutputChunk`): one launch, or on a CPU one launch
        per thread over contiguous ranges of bodies (each body's arithmetic is the same
        either way, bit for bit). Bodies that diverge stop and report through
        ``state.struct.status``."""
        model = self.model
        steps = wp.array(np.asarray(chunk.output_steps, dtype=np.int32), dtype=int, device=model.device)
        inputs = [
            model.struct,
            control.struct,
            self.stepping(control),
            state.struct,
            settings,
            steps,
            int(chunk.first_output),
            int(chunk.first_frame),
            chunk.probes,
            chunk.frames,
        ]
        launch_over_threads(self.kernel, model.n_bodies, inputs, model.device, threads, self.bodies_per_thread)

    @staticmethod
    def health(state: Any, body: int) -> tuple[int, int, int, float] | None:
        """``(code, step, index, value)`` of the stop ``body``'s kernel (or the budget
        check) recorded, or None while it is healthy."""
        code = int(state.struct.status.numpy()[body])
        if code == STATUS_OK:
            return None
        s = state.struct
        return (
            code,
            int(s.status_step.numpy()[body]),
            int(s.status_index.numpy()[body]),
            float(s.status_value.numpy()[body]),
        )
