"""What a strip's divergence says: the typed report of each stopped strip, in words a user
can act on (docs/model.md §11); when a body stops is the core's
(:mod:`warpcloth.core.divergence`)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

from warpcloth.core.divergence import sample_lost
from warpcloth.kernels import STATUS_BUDGET, STATUS_FOLDED, STATUS_NONFINITE_ENERGY, STATUS_STRAIN

if TYPE_CHECKING:
    from .control import StripControl

QUANTITY = {
    STATUS_STRAIN: "tensile strain",
    STATUS_FOLDED: "hinge chord |e1+e2|/h (the strip folded onto itself)",
    STATUS_NONFINITE_ENERGY: "total energy (not finite)",
    STATUS_BUDGET: (
        "energy budget residual (in units of the peak kinetic energy, at least 1e-3 of the strip's "
        "weight times its free length or of D W / L)"
    ),
}


PHASES = ("move", "hold", "record")
"""Phases of a run: the free end carried to its hold target, held there while the strip
settles, then the record from t = 0 (the release, or the start of a run without one)."""


def phase_at(time_s: float, control: StripControl) -> str:
    """The phase (:data:`PHASES`) a time after the release (negative before it) falls in."""
    if time_s >= 0:
        return "record"
    return "move" if time_s + control.release_time < control.move_time else "hold"


@dataclass(frozen=True)
class Divergence:
    """Where and how one strip of a batch diverged: what the runner stops it for, the run
    directory records (:meth:`as_dict`) and the user reads (:meth:`describe`)."""

    strip: int  # index in the batch
    code: int  # the health code the kernel set (kernels/status.py)
    step: int  # the step it was set at
    time_s: float  # that step's time after t = 0 (negative before the release)
    phase: str  # PHASES
    quantity: str  # what left its range, in words
    where: int  # the segment of a strain, the hinge node of a fold
    value: float  # the quantity's value
    limit: float  # the range it left
    scheme: str  # the solver's integrator.scheme
    advice: str  # what the solver adds to "try a smaller dt" (its own way out)
    precision: str
    dt_s: float

    def as_dict(self) -> dict:
        """The report as the run directory's meta.json writes it."""
        return dataclasses.asdict(self)

    @property
    def body(self) -> int:
        """The strip's index in the batch (the name every body's report shares)."""
        return self.strip

    @property
    def sample_lost(self) -> bool:
        """Whether the probe sample at :attr:`step` is already unusable (an energy that is
        not finite or off budget), so only the samples before it are kept."""
        return sample_lost(self.code)

    def describe(self) -> str:
        """One sentence a user can act on."""
        where = (
            f" at segment {self.where}"
            if self.code == STATUS_STRAIN
            else (f" at hinge node {self.where}" if self.code == STATUS_FOLDED else "")
        )
        limit = {
            STATUS_STRAIN: f", beyond integrator.divergence_strain = {self.limit:g}",
            STATUS_BUDGET: f", above {self.limit:g}: the step is unstable",
        }.get(self.code, "")
        advice = f"try a smaller integrator.dt_s (now {self.dt_s:g} s, e.g. {self.dt_s / 4:g})"
        advice += self.advice
        if self.code == STATUS_BUDGET and self.precision == "float32":
            advice = (
                "float32 rounding feeds energy into the stretching modes over a long run (a smaller dt makes "
                'it worse): use integrator.precision = "float64", or ' + advice
            )
        during = {
            "move": "while its free end was carried to the hold",
            "hold": "during the hold",
            "record": "after t = 0",
        }[self.phase]
        return (
            f"strip {self.strip} diverged {during}, at t = {self.time_s:.6g} s (step {self.step}): "
            f"{self.quantity} = {self.value:.4g}{where}{limit}; {advice}"
        )
