"""What drives a batch of strips: the clamp's rotation and the held free end."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from warpcloth.kernels import MAX_DEGREE, drives

if TYPE_CHECKING:
    from .model import StripModel


class StripControl:
    """Clamp motion θ(t) about each strip's rotation centre, and the hold-and-release.

    Times are in seconds: t = 0 is the release (or the start of the clamp motion); the
    hold lasts ``release_time`` s before it, the first ``move_time`` s of which carry the
    free end to its target. The solver converts them to its steps.
    """

    def __init__(self, model: StripModel) -> None:
        strips = model.strips
        self.release_time = model.release_time
        self.move_time = model.move_time
        n_pieces = max(1, max(len(s.clamp.start) for s in strips))
        b = model.n_strips
        start = np.zeros((n_pieces, b))
        end = np.zeros((n_pieces, b))
        coefficients = np.zeros((n_pieces, b, MAX_DEGREE + 1))
        for s, strip in enumerate(strips):
            n = len(strip.clamp.start)
            start[:n, s], end[:n, s], coefficients[:n, s] = strip.clamp.start, strip.clamp.end, strip.clamp.coefficients
        self.rotation_centre = np.array([s.rotation_centre for s in strips])
        self.hold_target = np.array([s.hold_target for s in strips])
        t = model.types
        c = drives.build(model.scalar).StripControl()
        c.segment_start = model.array(start)
        c.segment_end = model.array(end)
        c.segment_coefficients = model.array(coefficients, t.vec5)
        c.n_segments = model.array(np.array([len(s.clamp.start) for s in strips], dtype=np.int32), int)
        c.rotation_centre = model.array(self.rotation_centre, t.vec2)
        c.hold_target = model.array(self.hold_target, t.vec2)
        c.settle_damping = model.array(np.array([s.settle_damping for s in strips]))
        c.hold_free_end = model.array(np.array([s.hold_free_end for s in strips], dtype=np.int32), int)
        # where each held end stays once carried, from hold_target and the rest positions:
        # whatever changes those after this must launch reach_hold again
        c.held_position = model.array(np.zeros((b, 2)), t.vec2)
        c.held_velocity = model.array(np.zeros((b, 2)), t.vec2)
        wp.launch(
            drives.build(model.scalar).reach_hold,
            dim=b,
            inputs=[model.struct.rest_position, model.n_clamped, c],
            device=model.device,
        )
        self.struct = c
