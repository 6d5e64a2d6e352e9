"""What a strip records and when: the laser line, the probed hinge, the sample interval
and frame stride (docs/model.md §12); the schedule itself is the core's
(:mod:`warpcloth.core.schedule`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from warpcloth.core.runner import SampleTable
from warpcloth.core.schedule import RecorderSchedule
from warpcloth.kernels import probes

if TYPE_CHECKING:
    from .model import StripModel


@dataclass(frozen=True)
class Recorder(RecorderSchedule):
    """Probes every ``interval`` s (from t = 0 to ``duration``), a shape frame every
    ``probes_per_frame`` probes; the laser line at height ``laser_height`` (m, absolute)
    and the moment–curvature loop of hinge ``loop_hinge`` (0 = the clamp-edge hinge)."""

    interval: float
    probes_per_frame: int
    duration: float
    laser_height: float
    loop_hinge: int = 0

    def settings(self, model: StripModel) -> object:
        """The kernel's ProbeSettings struct for ``model``'s strips."""
        s = probes.build(model.scalar, model.terms).ProbeSettings()
        s.laser_height = model.scalar(self.laser_height)
        s.loop_hinge = self.loop_hinge
        s.probes_per_frame = self.probes_per_frame
        return s

    def tables(self, model: StripModel) -> tuple[SampleTable, ...]:
        """What a strip records besides its probes and frames: nothing."""
        return ()
