"""What a sheet records and when: its probes, the markers a video tracks, the probed cell
and hinge, the sample interval and frame stride. A sheet runs in the core's one loop
(:func:`warpcloth.core.runner.simulate_batch`), as a strip does."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from warpcloth.core.runner import SampleTable
from warpcloth.core.schedule import RecorderSchedule
from warpcloth.errors import ArgumentError

from .model import SheetModel


@dataclass(frozen=True)
class SheetRecorder(RecorderSchedule):
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

    def tables(self, model: SheetModel) -> tuple[SampleTable, ...]:
        """The markers' positions ``[sample, sheet, marker, xyz]``, written by the kernel
        into the settings' ``marker_positions``."""
        return (SampleTable("markers", len(self.markers), 3, "marker_positions"),)
