"""The clamp's grip zone of a scene, in SI (docs/model.md §5.4): read by the batch and by
the step's stability bound."""

from __future__ import annotations

from warpcloth import units
from warpcloth.strip import Grip

from .schema import Scene


def grip_of(scene: Scene) -> Grip:
    """The clamp's grip zone of ``scene`` in SI (docs/model.md §5.4)."""
    return Grip(
        scene.clamp.grip_length_mm * units.LENGTH_MM,
        scene.clamp.grip_bending_factor,
        scene.clamp.grip_hysteresis_factor,
    )
