"""Running a batch of sheets: chunked launches sized to the wall clock, progress, the
divergence policy, and what is recorded (probes, markers, frames)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import warp as wp
from tqdm import tqdm

from warpcloth.errors import ArgumentError, DivergenceError
from warpcloth.kernels.sheet import SHEET_PROBE_FIELDS, SHEET_PROBE_INDEX
from warpcloth.sim.divergence import BudgetWatch, stop_unbalanced
from warpcloth.sim.recorder import output_schedule
from warpcloth.sim.resources import check_memory
from warpcloth.sim.runner import ChunkPlan, available_cores, check_divergence_policy

from .geometry import SheetGeometry
from .model import SheetControl, SheetModel, SheetState
from .solver import SheetDivergence, SheetSolver

BUFFER_BYTES = 64 * 2**20
KINETIC = SHEET_PROBE_INDEX["kinetic"]


def sheet_budget_floor(model: SheetModel) -> np.ndarray:
    """The least energy scale each sheet's budget is judged at (the strip's rule,
    :data:`warpcloth.sim.divergence.BUDGET_TOLERANCE`): 1e-3 of its free nodes' weight
    times its free length, or of its warp's D W / L where that is larger (without gravity)."""
    g = model.geometry
    free = ~g.clamped
    length = float(np.ptp(g.rest_positions[:, 1])) or max(g.spacing)
    width = float(np.ptp(g.rest_positions[:, 2])) or max(g.spacing)
    weight = model.density * float(g.node_area[free].sum()) * model.gravity * length
    bending = np.array([s.material.warp.bending_rigidity for s in model.sheets]) * width / length
    return 1e-3 * np.maximum(weight, bending)


@dataclass(frozen=True)
class SheetRecorder:
    """Probes and markers every ``interval`` s from t = 0 to ``duration``, a shape frame
    every ``probes_per_frame`` samples; ``markers`` are the nodes whose positions are
    recorded at every sample (what a video tracks), ``probe_cell`` and ``probe_hinge`` the
    cell and hinge whose law is probed (indices into the geometry's lists)."""

    interval: float
    probes_per_frame: int
    duration: float
    markers: tuple[int, ...] = ()
    probe_cell: int = 0
    probe_hinge: int = 0

    def settings(self, model: SheetModel) -> object:
        """The kernel's SheetProbeSettings struct."""
        g = model.geometry
        for name, value, count in (
            ("probe_cell", self.probe_cell, len(g.cell_nodes)),
            ("probe_hinge", self.probe_hinge, len(g.hinge_nodes)),
        ):
            if count and not 0 <= value < count:
                raise ArgumentError(name, f"is {value}; the sheet has {count} (0 … {count - 1})")
        bad = [m for m in self.markers if not 0 <= m < model.n_nodes]
        if bad:
            raise ArgumentError("markers", f"node {bad[0]} is not one of the sheet's {model.n_nodes} nodes")
        s = model.kernels.SheetProbeSettings()
        s.probe_cell = self.probe_cell
        s.probe_hinge = self.probe_hinge
        s.markers = wp.array(np.array(self.markers, dtype=np.int32), dtype=int, device=model.device)
        s.probes_per_frame = self.probes_per_frame
        return s


class SheetSink(Protocol):
    """Where a sheet run streams its results as they are produced."""

    def write_samples(self, t: np.ndarray, probes: np.ndarray, markers: np.ndarray, valid: np.ndarray) -> None:
        """Append samples: times, probes ``[sample, field, sheet]``, markers ``[sample, sheet,
        marker, xyz]``, and which (sample, sheet) are valid."""

    def write_frames(self, first: int, frames: np.ndarray) -> None:
        """Store frames ``[frame, sheet, node, xyz]`` from frame index ``first`` on."""

    def close(self, diverged: list[SheetDivergence], extra: dict) -> None:
        """Finish: the run ended (completely, or at a divergence it reports)."""


@dataclass
class SheetResult:
    """Everything a sheet run recorded, SI: ``probes[sample, field, sheet]`` (fields
    :data:`~warpcloth.kernels.sheet.SHEET_PROBE_FIELDS`) and ``markers[sample, sheet,
    marker, xyz]`` at ``t``; ``frames[frame, sheet, node, xyz]`` at ``frame_times``. Samples
    after a sheet's divergence are NaN."""

    geometry: SheetGeometry
    t: np.ndarray
    probes: np.ndarray
    markers: np.ndarray
    frame_times: np.ndarray
    frames: np.ndarray | None
    diverged: list[SheetDivergence] = field(default_factory=list)
    wall_time_s: float = 0.0
    node_steps: int = 0
    reversal_memory: dict[str, object] = field(default_factory=dict)

    def probe(self, name: str, sheet: int | None = None) -> np.ndarray:
        """One probe's time series: ``[sample, sheet]``, or ``[sample]`` for one sheet."""
        if name not in SHEET_PROBE_INDEX:
            raise ArgumentError("name", f"{name!r} is not a sheet probe; they are {', '.join(SHEET_PROBE_FIELDS)}")
        series = self.probes[:, SHEET_PROBE_INDEX[name], :]
        return series if sheet is None else series[:, sheet]

    def energy_total(self) -> np.ndarray:
        """The budget that should stay constant: kinetic + gravitational + tensile + work
        done against the laws and damping − work done by the clamp, ``[sample, sheet]``."""
        return sheet_energy_total(self.probes)


def sheet_energy_total(probes: np.ndarray) -> np.ndarray:
    """The sheet's energy budget ``[sample, sheet]`` from its probes ``[sample, field,
    sheet]``: kinetic + gravitational + tensile + work done against the laws and damping −
    work done by the clamp (constant to O(dt))."""

    def p(name: str) -> np.ndarray:
        return probes[:, SHEET_PROBE_INDEX[name], :]

    return (
        p("kinetic")
        + p("gravitational")
        + p("tensile")
        + p("elastic_work")
        + p("hysteresis_work")
        + p("damping_work")
        - p("drive_work")
    )


def simulate_sheets(
    model: SheetModel,
    control: SheetControl,
    solver: SheetSolver,
    recorder: SheetRecorder,
    state: SheetState | None = None,
    *,
    sink: SheetSink | None = None,
    progress: bool = False,
    on_divergence: str = "raise",
    keep_frames: bool = True,
    threads: int | None = None,
) -> SheetResult:
    """Run a built batch of sheets to the end of the recorder's schedule and return what it
    recorded (the policy, ``threads`` and ``sink`` as :func:`warpcloth.sim.simulate_batch`'s)."""
    check_divergence_policy(on_divergence)
    threads = available_cores() if threads is None else threads
    if threads < 1:
        raise ArgumentError("threads", f"must be at least 1, got {threads}")
    state = state or model.state()
    settings = recorder.settings(model)
    schedule = output_schedule(recorder, control.release_time, solver.dt, solver.release_step(control))
    b, n, nq, nm = model.n_sheets, model.n_nodes, len(SHEET_PROBE_FIELDS), len(recorder.markers)
    kept = schedule.kept
    n_frames = len(schedule.frame_samples)
    check_memory(
        8 * len(kept) * b * (nq + 3 * nm) + (24 * n_frames * b * n if keep_frames else 0),
        f"the recorded probes, markers{' and frames' if keep_frames else ''} of {b} sheet(s)",
        "record less (output.probes_per_frame, output.frame_rate_hz, run.duration_s) or run fewer sheets at once",
    )
    probes = np.full((len(kept), nq, b), np.nan)
    markers = np.full((len(kept), b, nm, 3), np.nan)
    frames = np.full((n_frames, b, n, 3), np.nan) if keep_frames else None
    ppf = schedule.probes_per_frame
    per_sample = 8 * b * (nq + 3 * max(nm, 1))
    capacity = max(1, min(len(schedule.steps), BUFFER_BYTES // per_sample, (BUFFER_BYTES // (24 * n * b)) * ppf))
    vec3 = model.types.vec3
    probe_buffer = wp.zeros((capacity, nq, b), dtype=model.scalar, device=model.device)
    marker_buffer = wp.zeros((capacity, max(nm, 1), b), dtype=vec3, device=model.device)
    frame_buffer = wp.zeros((capacity // ppf + 1, n, b), dtype=vec3, device=model.device)
    settings.marker_positions = marker_buffer
    plan = ChunkPlan(schedule, capacity)
    budget = BudgetWatch(sheet_budget_floor(model))
    span = float(schedule.times(schedule.k_min + len(schedule.steps) - 1) - schedule.times(schedule.k_min))
    bar = tqdm(
        total=span,
        unit="s",
        desc="simulated",
        disable=not progress,
        dynamic_ncols=True,
        bar_format="{l_bar}{bar}| {n:.3f}/{total:.3f} s sim [{elapsed}<{remaining}{postfix}]",
    )
    diverged: dict[int, SheetDivergence] = {}
    stopped_at = np.full(b, np.iinfo(np.int64).max)
    started = time.perf_counter()
    try:
        for i, j in plan:
            k0 = schedule.k_min + i
            tic = time.perf_counter()
            solver.advance(
                state,
                control,
                settings,
                schedule.steps[i:j],
                k0,
                -(-max(k0, 0) // ppf),
                (probe_buffer, frame_buffer),
                threads,
            )
            wp.synchronize_device(model.device)
            wall = time.perf_counter() - tic
            plan.took(wall)
            k = schedule.k_min + np.arange(i, j)
            recorded = k >= 0
            if recorded.any():
                # an unstable step feeds energy in before any strain limit is reached
                values = probe_buffer[: j - i].numpy()[recorded]
                known = set(diverged)
                stop_unbalanced(
                    state,
                    budget,
                    sheet_energy_total(values),
                    values[:, KINETIC],
                    schedule.steps[k[recorded] - schedule.k_min],
                    known,
                )
            status = state.struct.status.numpy()
            for s in np.flatnonzero(status):
                if int(s) not in diverged:
                    report = solver.divergence_report(state, control, int(s))
                    if report is not None:
                        diverged[int(s)] = report
                        stopped_at[s] = report.step
            keep = recorded
            if keep.any():
                steps = schedule.steps[k - schedule.k_min]
                valid = steps[:, None] < stopped_at[None, :]
                values = np.where(valid[:, None, :], probe_buffer[: j - i].numpy(), np.nan)[keep]
                marks = np.transpose(marker_buffer[: j - i].numpy()[:, :nm], (0, 2, 1, 3))
                marks = np.where(valid[:, :, None, None], marks, np.nan)[keep]
                valid = valid[keep]
                k = k[keep]
                probes[k] = values
                markers[k] = marks
                frame_k = k[k % ppf == 0]
                chunk_frames = np.transpose(frame_buffer[: len(frame_k)].numpy(), (0, 2, 1, 3))
                chunk_frames = np.where(valid[k % ppf == 0][:, :, None, None], chunk_frames, np.nan)
                if frames is not None and len(frame_k):
                    frames[frame_k // ppf] = chunk_frames
                if sink is not None:
                    sink.write_samples(schedule.times(k), values, marks, valid)
                    if len(frame_k):
                        sink.write_frames(int(frame_k[0] // ppf), chunk_frames)
            steps_done = int(schedule.steps[j - 1] - (schedule.steps[i - 1] if i else 0))
            bar.set_postfix_str(f"{b * n * steps_done / max(wall, 1e-9):.3g} node-steps/s")
            bar.update(float(schedule.times(schedule.k_min + j - 1) - schedule.times(schedule.k_min)) - bar.n)
            if (diverged and on_divergence == "raise") or len(diverged) == b:
                break
    finally:
        bar.close()
    wall_time = time.perf_counter() - started
    reports = [diverged[s] for s in sorted(diverged)]
    result = SheetResult(
        model.geometry,
        schedule.times(kept),
        probes,
        markers,
        schedule.times(schedule.frame_samples),
        frames,
        reports,
        wall_time,
        n * int(state.struct.step.numpy().sum()),  # the steps each sheet ran, to its stop
        state.reversal_report(),
    )
    if sink is not None:
        sink.close(reports, {"wall_time_s": wall_time, "node_steps": result.node_steps, "device": str(model.device)})
    if reports and on_divergence == "raise":
        raise DivergenceError("; ".join(d.describe() for d in reports), reports, result)
    return result
