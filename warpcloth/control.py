"""What drives a batch of strips: the clamp's rotation and the held free end."""

from __future__ import annotations

import numpy as np

from warpcloth.kernels import FORWARD, SEMI_IMPLICIT

from . import units
from .clamp import MAX_DEGREE, clamp_pieces
from .model import Model, clamp_edge

SCHEMES = {"semi_implicit": SEMI_IMPLICIT, "forward": FORWARD}


class Control:
    """Clamp motion θ(t) about each strip's rotation centre, and the hold-and-release.

    Time is counted in substeps; step ``release_step`` is t = 0. Before it (when the
    scene has a release phase) the free end is carried to and held at its target.
    """

    def __init__(self, model: Model) -> None:
        scene = model.scenes[0]
        k = model.kernels
        self.dt = scene.integrator.dt_s
        self.release_step = round(scene.preroll / self.dt)
        self.move_steps = max(1, round(scene.release.move_time_s / self.dt))
        pieces = [clamp_pieces(s.clamp) for s in model.scenes]
        n_pieces = max(1, max(len(p[0]) for p in pieces))
        start = np.zeros((n_pieces, model.n_strips))
        end = np.zeros((n_pieces, model.n_strips))
        coefficients = np.zeros((n_pieces, model.n_strips, MAX_DEGREE + 1))
        for s, (a, b, c) in enumerate(pieces):
            start[: len(a), s], end[: len(a), s], coefficients[: len(a), s] = a, b, c
        edge = clamp_edge(scene)
        self.rotation_centre = np.array(
            [edge + units.LENGTH_MM * np.array([s.clamp.rotation_centre_dx_mm, s.clamp.rotation_centre_dy_mm])
             for s in model.scenes])
        self.hold_target = np.array(
            [edge + units.LENGTH_MM * np.array([s.release.hold_x_mm, s.release.hold_y_mm]) for s in model.scenes])
        c = k.StripControl()
        c.segment_start = model.array(start)
        c.segment_end = model.array(end)
        c.segment_coefficients = model.array(coefficients, k.vec5)
        c.n_segments = model.array(np.array([len(p[0]) for p in pieces], dtype=np.int32), int)
        c.rotation_centre = model.array(self.rotation_centre, k.vec2)
        c.hold_target = model.array(self.hold_target, k.vec2)
        c.settle_damping = model.array(np.array([s.release.settle_damping_per_s for s in model.scenes]))
        c.release_step = self.release_step
        c.move_steps = self.move_steps
        c.dt = k.scalar(self.dt)
        c.integrator = SCHEMES[scene.integrator.scheme]
        c.max_strain = k.scalar(scene.integrator.divergence_strain)
        self.struct = c
