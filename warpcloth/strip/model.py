"""What a batch of strips *is*: geometry and per-strip material, as Warp arrays (SI)."""

from __future__ import annotations

import logging
import os
import sys
import threading
from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from warpcloth.core.terms import checked_terms
from warpcloth.errors import ArgumentError
from warpcloth.kernels import bending_law, structs
from warpcloth.kernels import precision as precision_types
from warpcloth.kernels.probes import STRIP_PROBES

if TYPE_CHECKING:
    from .builder import StripBuilder
    from .control import StripControl
    from .state import StripState

PRECISIONS = {"float64": wp.float64, "float32": wp.float32}


_INIT_LOCK = threading.Lock()
_INITIALISED: list[bool] = []


def init_warp_quietly(verbose: bool = False) -> None:
    """Initialise Warp (once per process) without its banner, module-load lines and native
    notice that a machine has no CUDA driver (on a CPU machine every command, sweep worker
    and script would print them); a --device cuda there is refused with its own message.
    ``verbose`` (``warpcloth --verbose``) lets Warp say everything instead."""
    with _INIT_LOCK:
        # once per process: redirecting the process's stderr is not something two threads
        # may do at once (the second would save and later restore the redirection)
        if _INITIALISED:
            return
        if verbose:
            wp.config.verbose = True
            wp.init()
            _INITIALISED.append(True)
            return
        wp.config.log_level = logging.WARNING  # no init banner or module-load lines
        sys.stderr.flush()
        saved = os.dup(2)
        silent = os.open(os.devnull, os.O_WRONLY)
        try:
            os.dup2(silent, 2)
            wp.init()
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            os.close(silent)
        _INITIALISED.append(True)


def machine_device(device: str | None) -> wp.context.Device:
    """The Warp device ``device`` names (None: the default), or an ArgumentError naming the
    devices this machine has (a GPU asked for on a machine without one)."""
    init_warp_quietly()  # scripts are as quiet as the CLI, unless Warp was started before
    known = ", ".join(d.alias for d in wp.get_devices())
    if device is not None and str(device).startswith("cuda") and not wp.is_cuda_available():
        # asked before wp.get_device, whose native code would print Warp's own CUDA errors first
        raise ArgumentError(
            "device", f"{device!r} is not a device of this machine (it has no CUDA GPU); it has: {known}"
        )
    try:
        return wp.get_device(device)
    except (RuntimeError, ValueError) as exc:
        raise ArgumentError("device", f"{device!r} is not a device of this machine ({exc}); it has: {known}") from None


class StripModel:
    """Static description of B strips sharing node count, spacing and gravity.

    Made by :meth:`warpcloth.strip.StripBuilder.finalize`. Material, width and damping may
    differ per strip; :meth:`state` and :meth:`control` make the matching dynamic state
    and drives.
    """

    def __init__(
        self, builder: StripBuilder, device: str | None = None, precision: str = "float64", terms: tuple = ()
    ) -> None:
        self.device = machine_device(device)
        self.precision = precision
        self.scalar = PRECISIONS[precision]
        self.types = precision_types(self.scalar)
        self.terms = checked_terms(terms)
        """The force terms acting on every free node besides damping and gravity (kernels/force_terms.py)."""
        self.probes = STRIP_PROBES.with_terms(self.terms)
        """What the strips record: :data:`~warpcloth.kernels.probes.STRIP_PROBES` and the terms' channels."""
        self.structs = structs.build(self.scalar, self.terms)
        # A copy of what was built: adding strips to the builder afterwards does not
        # change this model.
        self.strips = tuple(builder.strips)
        self.release_time = builder.release_time
        self.move_time = builder.move_time
        strips = self.strips
        self.n_strips = len(strips)
        self.n_nodes = len(builder.rest_positions)
        self.n_clamped = builder.n_clamped
        self.spacing = builder.spacing
        self.gravity = builder.gravity
        self.rest_positions = builder.rest_positions.copy()
        self.width = np.array([s.width for s in strips])
        self.density = np.array([s.material.density for s in strips])
        self.node_mass = self.density * self.width * self.spacing
        self.tensile = np.array([s.material.tensile for s in strips])
        self.bending = np.array([s.material.bending_parameters() for s in strips])
        self.damping = np.array([s.damping for s in strips])
        self.edge_curvature_scale = np.array([self.spacing / s.edge_hinge_length for s in strips])
        intervals = builder.hinge_intervals()
        self.rest_curvature = np.stack([s.fabric_set.hinge_values(intervals) for s in strips], axis=1)  # [hinge, strip]
        self.grip_factors = np.stack([s.grip.hinge_factors(intervals) for s in strips], axis=1)  # [hinge, strip, 2]
        # Reversal points are stored only when some strip's law has return-point memory.
        uses_history = any(bending_law(s.material.bending_law).uses_reversal_memory for s in strips)
        self.reversal_memory = builder.reversal_memory if uses_history else 0
        self.struct = self._build_struct()

    body = "strip"
    """The body these are (:mod:`warpcloth.core.bodies`)."""
    dim = 2
    """Components of a node position: x, y in the plane of the swing."""

    @property
    def n_bodies(self) -> int:
        """The strips of the batch (the name every body's model shares)."""
        return self.n_strips

    @property
    def position_type(self) -> object:
        """The Warp vector of a node position."""
        return self.types.vec2

    def budget_floor(self) -> np.ndarray:
        """The least energy scale each strip's budget is judged at
        (:data:`~warpcloth.core.divergence.BUDGET_TOLERANCE`): 1e-3 of its weight times its
        free length, or of D W / L where that is larger (without gravity, a set strip curling
        at rest, the scale is bending's: the work of bending it through one radian)."""
        free = self.n_nodes - self.n_clamped
        weight = self.node_mass * (free - 0.5) * self.gravity * free * self.spacing
        bending = self.bending[:, 0] * self.width / (free * self.spacing)
        return 1e-3 * np.maximum(weight, bending)

    def array(self, values: np.ndarray, dtype: object = None) -> wp.array:
        """A Warp array of ``values`` on this model's device in its precision."""
        return wp.array(np.ascontiguousarray(values), dtype=dtype or self.scalar, device=self.device)

    def state(self) -> StripState:
        """A state at rest in the rest shape, every hinge fresh."""
        from .state import StripState

        return StripState(self)

    def control(self) -> StripControl:
        """The drives the strips were built with (clamp motion, hold and release)."""
        from .control import StripControl

        return StripControl(self)

    def _build_struct(self) -> object:
        t = self.types
        m = self.structs.StripModel()
        m.n_nodes = self.n_nodes
        m.n_clamped = self.n_clamped
        m.rest_length = self.scalar(self.spacing)
        m.gravity = self.scalar(self.gravity)
        m.rest_position = self.array(np.repeat(self.rest_positions[:, None, :], self.n_strips, axis=1), t.vec2)
        m.tensile = self.array(self.tensile, t.vec4)
        m.bending = self.array(self.bending, self.structs.law.Parameters)
        m.width = self.array(self.width)
        m.node_mass = self.array(self.node_mass)
        m.damping = self.array(self.damping)
        m.edge_curvature_scale = self.array(self.edge_curvature_scale)
        m.rest_curvature = self.array(self.rest_curvature)
        m.grip = self.array(self.grip_factors, t.vec2)
        return m
