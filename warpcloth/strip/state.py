"""What a batch of strips *is doing*: node positions and velocities, the bending law's
memory of every hinge, the work done so far, and each strip's health."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import warp as wp

from warpcloth.errors import ArgumentError, ArgumentTypeError
from warpcloth.kernels import hinge_kernels

if TYPE_CHECKING:
    from .model import StripModel


def allocate_reversal_memory(
    struct_type: type, capacity: int, n_hinges: int, n_strips: int, vec2: object, device: object
) -> object:
    """A law history struct with ``capacity`` reversal points per hinge above the origin
    (capacity 0: no strip stores any, so the points array is a placeholder)."""
    history = struct_type()
    shape = (capacity + 1, n_hinges, n_strips) if capacity else (1, 1, 1)
    history.points = wp.zeros(shape, dtype=vec2, device=device)
    history.overflows = wp.zeros(n_strips, dtype=int, device=device)
    history.deepest = wp.zeros(n_strips, dtype=int, device=device)
    return history


def check_reversal_memory(reversal_memory: object) -> None:
    """Refuse a ``reversal_memory`` (open reversal points a hinge keeps) that is not a whole
    number of at least 1: an ArgumentTypeError or ArgumentError naming it."""
    message = f"must be a whole number of at least 1, got {reversal_memory!r}"
    if not isinstance(reversal_memory, int):
        raise ArgumentTypeError("reversal_memory", message)
    if not reversal_memory >= 1:
        raise ArgumentError("reversal_memory", message)


def checked_nodes(argument: str, value: object, n_nodes: int, n_strips: int) -> np.ndarray:
    """``value`` as a float array ``[node, strip, xy]`` of ``n_nodes`` × ``n_strips`` × 2
    finite numbers, or an ArgumentTypeError / ArgumentError naming ``argument``, what it got and what
    is expected (a NaN start would otherwise read as a divergence of the run)."""
    expected = (n_nodes, n_strips, 2)
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ArgumentTypeError(
            argument, f"must be an array of numbers [node, strip, xy] of shape {expected}, got {type(value).__name__}"
        ) from None
    if array.shape != expected:
        raise ArgumentError(
            argument,
            f"has shape {array.shape}; expected {expected} ([node, strip, xy]: "
            f"{n_nodes} nodes, {n_strips} strip(s), x and y)",
        )
    if not np.isfinite(array).all():
        node, strip, axis = np.argwhere(~np.isfinite(array))[0]
        raise ArgumentError(
            argument, f"[{node}, {strip}, {axis}] is {array[node, strip, axis]}; every value must be finite"
        )
    return array


class StripState:
    """Dynamic state of B strips, laid out ``[node, strip]`` / ``[hinge, strip]``.

    Starts in the model's rest shape and at rest with fresh hinges; :meth:`set_positions`
    replaces the shape (and re-initialises the hinges there, so it carries no moment offset).
    ``struct.history`` holds the open reversal points of strips whose law has return-point
    memory, and per strip the reversals a full memory could not hold (:meth:`reversal_report`).
    """

    def __init__(self, model: StripModel) -> None:
        self.model = model
        t = model.types
        n, b = model.n_nodes, model.n_strips
        n_hinges = n - model.n_clamped

        def nodes() -> wp.array:
            return wp.zeros((n, b), dtype=t.vec2, device=model.device)

        def per_strip(dtype: object) -> wp.array:
            return wp.zeros(b, dtype=dtype, device=model.device)

        s = model.structs.StripState()
        s.position = wp.clone(model.struct.rest_position)
        s.velocity = nodes()
        s.force_tensile = nodes()
        s.force_elastic = nodes()
        s.force_hysteretic = nodes()
        s.correction = nodes()
        s.elimination = wp.zeros((n, b), dtype=t.vec4, device=model.device)
        s.hinge = wp.zeros((n_hinges, b), dtype=model.structs.law.Memory, device=model.device)
        s.history = allocate_reversal_memory(
            model.structs.law.History, model.reversal_memory, n_hinges, b, t.vec2, model.device
        )
        s.work = per_strip(model.structs.tally)
        s.step = per_strip(int)
        s.status = per_strip(int)
        s.status_step = per_strip(int)
        s.status_index = per_strip(int)
        s.status_value = per_strip(t.scalar)
        self.struct = s
        self.reset_hinges()

    def reversal_report(self) -> dict[str, object]:
        """The reversal memory's use so far: its ``capacity`` (points per hinge), and per
        strip the ``deepest`` any hinge went and the ``overflows`` (reversals not stored,
        their inner loops traced without hysteresis); empty when no strip stores any."""
        capacity = self.model.reversal_memory
        if not capacity:
            return {}
        h = self.struct.history
        return {"capacity": capacity, "deepest": h.deepest.numpy().tolist(), "overflows": h.overflows.numpy().tolist()}

    def set_positions(self, positions: np.ndarray, velocities: np.ndarray | None = None) -> None:
        """Replace node positions ``[node, strip, 2]`` (and velocities), e.g. a mode shape
        (m, m/s; finite, of exactly that shape: anything else is refused, naming it)."""
        vec2 = self.model.types.vec2
        n, b = self.model.n_nodes, self.model.n_strips
        self.struct.position.assign(self.model.array(checked_nodes("positions", positions, n, b), vec2))
        if velocities is not None:
            self.struct.velocity.assign(self.model.array(checked_nodes("velocities", velocities, n, b), vec2))
        self.reset_hinges()

    def reset_hinges(self) -> None:
        """Make every hinge fresh at its current curvature (no memory of past bending)."""
        self.struct.history.overflows.zero_()
        self.struct.history.deepest.zero_()
        kernel = hinge_kernels(self.model.scalar, self.model.terms).initialise_hinges
        wp.launch(kernel, dim=self.model.n_strips, inputs=[self.model.struct, self.struct], device=self.model.device)
