"""Building a batch of strips from Python, in SI: geometry, per-strip materials and drives::

    builder = StripBuilder(rest_positions, n_clamped=5, spacing=5e-3)
    for material in materials:
        builder.add_strip(material, width=0.05, damping=0.3)
    model = builder.finalize(device="cpu")
    control, state = model.control(), model.state()

Every strip of a batch shares the node count, spacing, gravity and the hold-and-release
timing; everything else may differ per strip. Nothing here knows scene files or KES units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from warpcloth.errors import ArgumentError
from warpcloth.kernels import MAX_DEGREE, bending_masing

from .material import MaterialSI
from .model import StripModel
from .state import check_reversal_memory


@dataclass(frozen=True)
class ClampMotion:
    """θ(t) of the clamp as pieces θ = Σ c_k (t − start_k)^k on [start_k, end_k] (rad, s);
    no pieces: the clamp stands still. θ is held at its end value outside the span."""

    start: np.ndarray = field(default_factory=lambda: np.zeros(0))
    end: np.ndarray = field(default_factory=lambda: np.zeros(0))
    coefficients: np.ndarray = field(default_factory=lambda: np.zeros((0, MAX_DEGREE + 1)))


@dataclass(frozen=True)
class FabricSet:
    """The natural curvature K_rest(s) (1/m, counter-clockwise positive) the unloaded strip
    keeps, s the arc length below the clamp edge (m): ``curvature`` everywhere, or the
    piecewise-linear profile through (``table_s``, ``table_curvature``) when those are given
    (docs/model.md §5.4)."""

    curvature: float = 0.0
    table_s: tuple[float, ...] = ()
    table_curvature: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        s = np.asarray(self.table_s, dtype=float)
        if len(s) != len(self.table_curvature) or len(s) == 1 or np.any(np.diff(s) <= 0):
            raise ArgumentError(
                "table_s",
                f"a rest-curvature table needs at least 2 strictly increasing arc lengths, one curvature "
                f"each; got {len(s)} arc lengths and {len(self.table_curvature)} curvatures",
            )

    def hinge_values(self, intervals: np.ndarray) -> np.ndarray:
        """K_rest of each hinge: the profile's mean over the arc ``intervals`` ``[hinge, (start,
        end)]`` it bends (m), so the rest turning angle of the chain is the profile's own."""
        if not self.table_s:
            return np.full(len(intervals), self.curvature)
        s, k = np.asarray(self.table_s), np.asarray(self.table_curvature)
        # ∫K ds of the linear interpolant from s[0], at any point (the profile is held beyond its ends)
        cumulative = np.concatenate([[0.0], np.cumsum(np.diff(s) * (k[1:] + k[:-1]) / 2)])

        def integral(x: np.ndarray) -> np.ndarray:
            i = np.clip(np.searchsorted(s, x, side="right") - 1, 0, len(s) - 2)
            kx = np.interp(x, s, k)
            return cumulative[i] + (x - s[i]) * (k[i] + kx) / 2

        a, b = intervals[:, 0], intervals[:, 1]
        return (integral(b) - integral(a)) / (b - a)


def hinge_intervals(spacing: float, hinges: int) -> np.ndarray:
    """``[hinge, (start, end)]``: the arc below the clamp edge each of ``hinges`` hinges
    bends (m) at node ``spacing`` h. The clamp-edge hinge bends [0, h/2] (either edge model:
    the paper's acts h/2 inside the clamp, §5.3), hinge j the segment halves either side of
    it, [(j − ½) h, (j + ½) h]."""
    j = np.arange(hinges, dtype=float)
    return np.column_stack([np.maximum(j - 0.5, 0.0) * spacing, (j + 0.5) * spacing])


@dataclass(frozen=True)
class Grip:
    """The clamp's grip: over ``length`` (m) below the clamp edge the bending rigidity is
    ``bending_factor`` × the fabric's and the hysteresis amplitude ``hysteresis_factor`` ×
    (docs/model.md §5.4); length 0 or both factors 1: no grip effect."""

    length: float = 0.0
    bending_factor: float = 1.0
    hysteresis_factor: float = 1.0

    def __post_init__(self) -> None:
        for argument, ok in (
            ("length", self.length >= 0),
            ("bending_factor", self.bending_factor > 0),
            ("hysteresis_factor", self.hysteresis_factor >= 0),
        ):
            if not ok:
                raise ArgumentError(
                    argument,
                    f"a grip needs length ≥ 0, bending_factor > 0 and hysteresis_factor ≥ 0; got "
                    f"{self.length:g}, {self.bending_factor:g}, {self.hysteresis_factor:g}",
                )

    def hinge_factors(self, intervals: np.ndarray) -> np.ndarray:
        """``[hinge, (bending, hysteresis)]`` factors of hinges bending the arc ``intervals``:
        a hinge partly in the zone is the series compliance of its two parts for the
        rigidity (its rotation is ∫M/D ds) and their length-weighted mean for the amplitude;
        exactly 1 for a hinge outside it."""
        a, b = intervals[:, 0], intervals[:, 1]
        inside = np.clip(np.minimum(b, self.length) - a, 0.0, None) / (b - a)
        f, g = self.bending_factor, self.hysteresis_factor
        # a factor of 1 gives exactly 1 (the moment unscaled to the bit), whatever the length
        bending = f / (inside + (1.0 - inside) * f) if f != 1.0 else np.ones(len(a))
        hysteresis = inside * g + (1.0 - inside) if g != 1.0 else np.ones(len(a))
        return np.column_stack([bending, hysteresis])


@dataclass(frozen=True)
class StripSpec:
    """One strip of a batch as :meth:`StripBuilder.add_strip` recorded it (SI)."""

    material: MaterialSI
    width: float
    damping: float
    clamp: ClampMotion
    rotation_centre: np.ndarray
    hold_target: np.ndarray
    settle_damping: float
    edge_hinge_length: float
    hold_free_end: bool = True
    fabric_set: FabricSet = field(default_factory=FabricSet)
    grip: Grip = field(default_factory=Grip)


class StripBuilder:
    """Collects a batch of strips, then :meth:`finalize` makes the :class:`Model`.

    ``rest_positions`` ``[node, xy]`` (m) is the straight hanging chain the strips start
    from and the clamp nodes rotate rigidly from; its first ``n_clamped`` nodes are held
    by the clamp. ``release_time`` > 0 starts with the hold-and-release phase: the free
    end is carried to its hold target over ``move_time`` s and held until t = 0.
    ``reversal_memory`` is how many open reversal points each hinge of a strip with
    return-point memory (the masing law) keeps; a reversal beyond it is counted and
    reported (:attr:`warpcloth.strip.RunResult.reversal_memory`).
    """

    def __init__(
        self,
        rest_positions: np.ndarray,
        n_clamped: int,
        spacing: float,
        gravity: float = 9.80665,
        release_time: float = 0.0,
        move_time: float = 0.0,
        reversal_memory: int = bending_masing.DEFAULT_CAPACITY,
    ) -> None:
        self.rest_positions = np.asarray(rest_positions, dtype=np.float64)
        if self.rest_positions.ndim != 2 or self.rest_positions.shape[1] != 2:
            raise ArgumentError("rest_positions", f"must be [node, xy], got shape {self.rest_positions.shape}")
        if not 2 <= n_clamped <= len(self.rest_positions) - 2:
            raise ArgumentError(
                "n_clamped", f"{n_clamped} clamped nodes must leave at least 2 free nodes of {len(rest_positions)}"
            )
        lengths = np.linalg.norm(np.diff(self.rest_positions, axis=0), axis=1)
        worst = int(np.argmax(np.abs(lengths - spacing)))
        if not abs(lengths[worst] - spacing) <= 1e-9 * spacing:
            # every segment shares one rest length in the kernel: the chain must be uniform
            raise ArgumentError(
                "rest_positions",
                f"segment {worst} of rest_positions is {lengths[worst]:.6g} m long, not the spacing {spacing:.6g} m",
            )
        self.n_clamped = n_clamped
        self.spacing = spacing
        self.gravity = gravity
        self.release_time = release_time
        self.move_time = move_time
        check_reversal_memory(reversal_memory)
        self.reversal_memory = reversal_memory
        self.strips: list[StripSpec] = []

    @property
    def clamp_edge(self) -> np.ndarray:
        """The clamp's lowest node, where the free strip begins."""
        return self.rest_positions[self.n_clamped - 1]

    def add_strip(
        self,
        material: MaterialSI,
        *,
        width: float,
        damping: float = 0.0,
        clamp: ClampMotion | None = None,
        rotation_centre: Sequence[float] | None = None,
        hold_target: Sequence[float] | None = None,
        settle_damping: float = 0.0,
        edge_hinge_length: float | None = None,
        fabric_set: FabricSet | None = None,
        grip: Grip | None = None,
        hold_free_end: bool = True,
    ) -> int:
        """Add one strip (SI: m, 1/s, absolute positions); returns its index in the batch.

        ``rotation_centre`` defaults to the clamp edge and ``hold_target`` to the free
        end's rest position. ``edge_hinge_length`` is the length of strip the clamp-edge
        hinge bends: h/2 (the default, like a scene's ``clamp.edge_hinge = "second_order"``)
        makes the built-in end second order in h; h is the paper's model, which acts as if
        clamped h/2 inside the clamp (docs/model.md §5.3). ``fabric_set`` is the strip's
        natural curvature and ``grip`` the clamp's grip zone (docs/model.md §5.4; default:
        neither). ``hold_free_end`` False leaves the free end free during the hold: the
        strip settles under its own weight instead of in the held shape.
        """
        edge = 0.5 * self.spacing if edge_hinge_length is None else edge_hinge_length
        if not 0 < edge <= self.spacing:
            raise ArgumentError("edge_hinge_length", f"{edge:g} m must lie in (0, spacing = {self.spacing:g} m]")
        self.strips.append(
            StripSpec(
                material=material,
                width=width,
                damping=damping,
                clamp=clamp or ClampMotion(),
                rotation_centre=np.asarray(
                    self.clamp_edge if rotation_centre is None else rotation_centre, dtype=float
                ),
                hold_target=np.asarray(self.rest_positions[-1] if hold_target is None else hold_target, dtype=float),
                settle_damping=settle_damping,
                edge_hinge_length=edge,
                fabric_set=fabric_set or FabricSet(),
                grip=grip or Grip(),
                hold_free_end=bool(hold_free_end),
            )
        )
        return len(self.strips) - 1

    def hinge_intervals(self) -> np.ndarray:
        """``[hinge, (start, end)]``: the arc below the clamp edge each hinge bends (m), see
        :func:`hinge_intervals`."""
        return hinge_intervals(self.spacing, len(self.rest_positions) - self.n_clamped)

    def finalize(self, device: str | None = None, precision: str = "float64", terms: tuple = ()) -> StripModel:
        """The :class:`Model` of every strip added, on ``device`` in ``precision``, with the
        force ``terms`` (kernels/force_terms.py) acting on every free node."""
        if not self.strips:
            raise ArgumentError("strips", "a batch needs at least one strip (add_strip adds one)")
        return StripModel(self, device=device, precision=precision, terms=terms)
