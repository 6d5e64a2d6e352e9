"""What advances a batch of strips: one kernel launch per chunk of output samples."""

from __future__ import annotations

import numpy as np
import warp as wp

from warpcloth.kernels import STATUS_FOLDED, STATUS_NONFINITE_ENERGY, STATUS_OK, STATUS_STRAIN

from . import units
from .control import Control
from .model import Model, clamp_edge
from .state import State

QUANTITY = {
    STATUS_STRAIN: "tensile strain",
    STATUS_FOLDED: "hinge chord |e1+e2|/h (the strip folded onto itself)",
    STATUS_NONFINITE_ENERGY: "total energy (not finite)",
}


class Solver:
    """Explicit integrator (semi-implicit or forward Euler) for a Model under a Control."""

    def __init__(self, model: Model, control: Control) -> None:
        self.model = model
        self.control = control
        scene = model.scenes[0]
        self.laser_height = float(clamp_edge(scene)[1] + scene.output.laser_height_mm * units.LENGTH_MM)
        self.probes_per_frame = scene.output.probes_per_frame
        self.loop_hinge = scene.loop_hinge

    def advance(self, state: State, output_steps: np.ndarray, first_output: int, first_frame: int,
                probes: wp.array, frames: wp.array) -> None:
        """Advance every healthy strip to each step in ``output_steps`` in one launch.

        Probe k of the chunk goes to ``probes[k, :, strip]``; outputs that are frames
        (index ≥ 0, a multiple of probes_per_frame) go to ``frames[index // ppf −
        first_frame]``. Strips that diverge stop and report through ``state.status``.
        """
        k = self.model.kernels
        steps = wp.array(np.asarray(output_steps, dtype=np.int32), dtype=int, device=self.model.device)
        wp.launch(k.advance, dim=self.model.n_strips, device=self.model.device,
                  inputs=[self.model.struct, self.control.struct, state.struct, steps, int(first_output),
                          int(first_frame), self.probes_per_frame, k.scalar(self.laser_height), self.loop_hinge, probes,
                          frames])

    def divergence_report(self, state: State, strip: int) -> dict | None:
        """Where and how ``strip`` diverged, or None while it is healthy."""
        code = int(state.struct.status.numpy()[strip])
        if code == STATUS_OK:
            return None
        step = int(state.struct.status_step.numpy()[strip])
        dt = self.control.dt
        scene = self.model.scenes[strip]
        return {
            "strip": strip,
            "code": code,
            "step": step,
            "time_s": (step - self.control.release_step) * dt,
            "quantity": QUANTITY[code],
            "where": int(state.struct.status_index.numpy()[strip]),
            "value": float(state.struct.status_value.numpy()[strip]),
            "limit": scene.integrator.divergence_strain,
            "scheme": scene.integrator.scheme,
            "dt_s": dt,
        }


def describe_divergence(report: dict) -> str:
    """One sentence a user can act on."""
    where = f" at segment {report['where']}" if report["code"] == STATUS_STRAIN else (
        f" at hinge node {report['where']}" if report["code"] == STATUS_FOLDED else "")
    limit = (f", beyond integrator.divergence_strain = {report['limit']:g}"
             if report["code"] == STATUS_STRAIN else "")
    advice = f"try a smaller integrator.dt_s (now {report['dt_s']:g} s, e.g. {report['dt_s'] / 4:g})"
    if report["scheme"] == "forward":
        advice += (" or integrator.scheme = semi_implicit (forward Euler amplifies every undamped"
                   " oscillation, MODEL.md)")
    return (f"strip {report['strip']} diverged at t = {report['time_s']:.6g} s (step {report['step']}): "
            f"{report['quantity']} = {report['value']:.4g}{where}{limit}; {advice}")
