"""What a batch of strips *is doing*: node positions and velocities, the hysteresis
memory of every hinge, the work done so far, and each strip's health."""

from __future__ import annotations

import numpy as np
import warp as wp

from .model import Model, rest_positions


class State:
    """Dynamic state of B strips, laid out ``[node, strip]`` / ``[hinge, strip]``.

    Starts straight and at rest with fresh hinges; :meth:`set_positions` replaces the
    initial shape (and re-initialises the hinges there, so it carries no moment offset).
    """

    def __init__(self, model: Model) -> None:
        self.model = model
        k = model.kernels
        n, b = model.n_nodes, model.n_strips
        n_hinges = n - model.n_clamped
        rest = np.repeat(rest_positions(model.scenes[0])[:, None, :], b, axis=1)

        def nodes() -> wp.array:
            return wp.zeros((n, b), dtype=k.vec2, device=model.device)

        def hinges() -> wp.array:
            return wp.zeros((n_hinges, b), dtype=k.scalar, device=model.device)

        def per_strip(dtype: object) -> wp.array:
            return wp.zeros(b, dtype=dtype, device=model.device)

        s = k.StripState()
        s.rest_position = model.array(rest, k.vec2)
        s.position = model.array(rest, k.vec2)
        s.velocity = nodes()
        s.force_tensile = nodes()
        s.force_elastic = nodes()
        s.force_hysteretic = nodes()
        s.branch = hinges()
        s.loop_centre = hinges()
        s.previous_curvature = hinges()
        s.work = per_strip(k.vec4)
        s.step = per_strip(int)
        s.status = per_strip(int)
        s.status_step = per_strip(int)
        s.status_index = per_strip(int)
        s.status_value = per_strip(k.scalar)
        self.struct = s
        self.reset_hysteresis()

    def set_positions(self, positions: np.ndarray, velocities: np.ndarray | None = None) -> None:
        """Replace node positions ``[node, strip, 2]`` (and velocities), e.g. a mode shape."""
        k = self.model.kernels
        self.struct.position.assign(self.model.array(positions, k.vec2))
        if velocities is not None:
            self.struct.velocity.assign(self.model.array(velocities, k.vec2))
        self.reset_hysteresis()

    def reset_hysteresis(self) -> None:
        """Make every hinge fresh at its current curvature (rising branch, H = 0)."""
        wp.launch(self.model.kernels.initialise_hysteresis, dim=self.model.n_strips,
                  inputs=[self.model.struct, self.struct], device=self.model.device)
